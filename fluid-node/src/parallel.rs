//! Row-parallel loops over several fields at once, and deterministic reductions.
//!
//! Reductions go through per-row partial results combined in row order, so a sum does not
//! depend on how rayon splits the work or on the number of threads.
use crate::transform::SharedPtr;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Most fields one [`for_each_row`] call can hand out.
pub const MAX_FIELDS: usize = 4;

/// Elements below which splitting work across threads costs more than it saves (a rayon
/// task costs microseconds; a small grid's whole step is a few hundred microseconds): the
/// default, which [`crate::grain_tuner`] may change at run time ([`set_grain`]).
pub const GRAIN: usize = 16_384;

/// The grain in use; process-wide, since it decides only how rows are shared among threads,
/// never a result (reductions go through per-row partial results).
static GRAIN_NOW: AtomicUsize = AtomicUsize::new(GRAIN);

/// Elements a rayon task gets at least: [`GRAIN`] unless [`set_grain`] changed it.
pub fn grain() -> usize {
    GRAIN_NOW.load(Ordering::Relaxed)
}

/// Change [`grain`] for every loop started from now on (at least 1).
pub fn set_grain(elements: usize) {
    GRAIN_NOW.store(elements.max(1), Ordering::Relaxed);
}

/// Minimum rows of `row_len` elements per rayon task: at least [`grain`] elements, and few
/// enough tasks (eight per thread) to balance.
pub fn min_len(rows: usize, row_len: usize) -> usize {
    (rows / (8 * rayon::current_num_threads().max(1)))
        .max(grain().div_ceil(row_len.max(1)))
        .max(1)
}

/// Call `f(r, rows)` for every row index `r` in parallel, where `rows[c]` is row `r` (of
/// `row_len` elements) of `fields[c]`. All fields must have the same length, a multiple of
/// `row_len`; at most [`MAX_FIELDS`] fields.
pub fn for_each_row<T: Send>(
    fields: &mut [&mut [T]],
    row_len: usize,
    f: impl Fn(usize, &mut [&mut [T]]) + Sync + Send,
) {
    let k = fields.len();
    assert!((1..=MAX_FIELDS).contains(&k), "for_each_row: 1..=4 fields");
    let len = fields[0].len();
    assert!(fields.iter().all(|s| s.len() == len) && len.checked_rem(row_len) == Some(0));
    let rows = len / row_len;
    let ptrs: [SharedPtr<T>; MAX_FIELDS] = std::array::from_fn(|c| {
        SharedPtr(if c < k {
            fields[c].as_mut_ptr()
        } else {
            std::ptr::null_mut()
        })
    });
    (0..rows)
        .into_par_iter()
        .with_min_len(min_len(rows, row_len))
        .for_each(|r| {
            let ptrs = &ptrs;
            let mut s: [&mut [T]; MAX_FIELDS] = std::array::from_fn(|c| {
                if c < k {
                    // SAFETY: row r of field c is handed to this call only; the fields are
                    // distinct exclusive borrows of `len` elements.
                    unsafe { std::slice::from_raw_parts_mut(ptrs[c].0.add(r * row_len), row_len) }
                } else {
                    &mut []
                }
            });
            f(r, &mut s[..k]);
        });
}

/// `out[r] = f(r)` for every row index `r < rows` (of `row_len` elements), in parallel.
/// `out` keeps its capacity, so a buffer reserved once is never reallocated.
pub fn per_row<T: Send>(
    out: &mut Vec<T>,
    rows: usize,
    row_len: usize,
    f: impl Fn(usize) -> T + Sync + Send,
) {
    (0..rows)
        .into_par_iter()
        .with_min_len(min_len(rows, row_len))
        .map(f)
        .collect_into_vec(out);
}

/// Sum in index order.
pub fn ordered_sum(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a, b| a + b)
}

/// Largest |v| (0 for none), NaN if any value is NaN. Eight lanes and a NaN flag instead of a
/// branch per value: the maximum does not depend on the order, and a single running maximum
/// waits on every comparison in turn.
pub fn max_abs(v: &[f64]) -> f64 {
    const LANES: usize = 8;
    let mut m = [0.0f64; LANES];
    let mut nan = false;
    let mut chunks = v.chunks_exact(LANES);
    for c in &mut chunks {
        for l in 0..LANES {
            m[l] = m[l].max(c[l].abs());
            nan |= c[l].is_nan();
        }
    }
    for (l, x) in chunks.remainder().iter().enumerate() {
        m[l] = m[l].max(x.abs());
        nan |= x.is_nan();
    }
    if nan {
        f64::NAN
    } else {
        m.iter().fold(0.0f64, |a, &b| a.max(b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lanes give the plain maximum for every remainder, and NaN wherever it sits.
    #[test]
    fn max_abs_is_the_plain_maximum_and_sees_nan() {
        for n in 0..12 {
            let v: Vec<f64> = (0..n).map(|i| ((i * 37 % 11) as f64 - 5.3) * 0.7).collect();
            let plain = v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            assert_eq!(max_abs(&v), plain, "{n} values");
            for k in 0..n {
                let mut w = v.clone();
                w[k] = f64::NAN;
                assert!(max_abs(&w).is_nan(), "NaN at {k} of {n}");
            }
        }
    }
}
