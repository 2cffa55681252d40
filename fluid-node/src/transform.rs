//! Real-to-complex Fourier transforms of periodic 2D and 3D fields, planned once.
//!
//! Layout. A real field holds `nz * ny * nx` values with x fastest: index
//! `(z * ny + y) * nx + x` (in 2D `nz = 1`). Its spectrum holds `nz * ny * nxh` complex values,
//! `nxh = nx / 2 + 1`, in the same order: index `(kz * ny + ky) * nxh + kx`.
//!
//! Forward: realfft r2c along x (the contiguous last axis) row by row, then rustfft along y and
//! (in 3D) z in place, gathering blocks of neighbouring columns (see [`BLOCK_VALUES`]) into a
//! contiguous workspace so that the strided axes are read in long contiguous runs. The forward transform is
//! unnormalised; the inverse divides by the number of cells.
//!
//! Work is split over a fixed set of workspaces allocated with the plans; a transform
//! allocates nothing. Every line is transformed by the same plan whatever the split, so the
//! result does not depend on the number of threads.
use crate::grid::Grid;
use crate::parallel::grain;
use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

/// Complex values gathered per column block along y and z: the block holds
/// `max(MIN_BLOCK, BLOCK_VALUES / len)` neighbouring columns of `len` values, so that a
/// strided axis is read in runs of that many contiguous values while the block stays in
/// the L2 cache.
pub const BLOCK_VALUES: usize = 1024;
/// Fewest columns per block.
pub const MIN_BLOCK: usize = 8;

/// Columns per block for lines of `len` values.
fn block(len: usize) -> usize {
    (BLOCK_VALUES / len.max(1)).max(MIN_BLOCK)
}

/// A raw pointer shared between rayon tasks that touch disjoint elements.
#[derive(Clone, Copy)]
pub(crate) struct SharedPtr<T>(pub(crate) *mut T);
// SAFETY: used only where every task reads and writes a set of elements no other task touches.
unsafe impl<T: Send> Send for SharedPtr<T> {}
unsafe impl<T: Send> Sync for SharedPtr<T> {}

struct Workspace {
    /// One real row (the r2c input is destroyed by realfft).
    row: Vec<f64>,
    /// Scratch of the largest plan.
    fft_scratch: Vec<Complex64>,
    /// `BLOCK` gathered columns of the longest strided axis.
    lines: Vec<Complex64>,
}

/// Planned transforms and their workspaces for one grid.
pub struct Transform {
    grid: Grid,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    fy: [Arc<dyn Fft<f64>>; 2],
    fz: Option<[Arc<dyn Fft<f64>>; 2]>,
    workspaces: Vec<Workspace>,
    /// Whether the number of workspaces in use follows [`grain`] (else all are used).
    tuned: bool,
    /// Intermediate spectrum of the inverse transform (the input is left untouched).
    work: Vec<Complex64>,
}

/// Strided columns of a spectrum: `outer` groups `outer_stride` apart, each with `width`
/// neighbouring columns of `len` elements `stride` apart.
#[derive(Clone, Copy)]
struct Columns {
    outer: usize,
    outer_stride: usize,
    width: usize,
    len: usize,
    stride: usize,
}

impl Transform {
    /// Plan the transforms of `grid` and allocate workspaces for `groups` parallel tasks
    /// (`0`: four per rayon thread, of which a transform uses fewer on small grids, so that a
    /// task has at least [`grain`] values at the time).
    pub fn new(grid: Grid, groups: usize) -> Self {
        let mut rp = RealFftPlanner::<f64>::new();
        let r2c = rp.plan_fft_forward(grid.nx);
        let c2r = rp.plan_fft_inverse(grid.nx);
        let mut cp = FftPlanner::<f64>::new();
        let fy = [cp.plan_fft_forward(grid.ny), cp.plan_fft_inverse(grid.ny)];
        let fz =
            (grid.dims == 3).then(|| [cp.plan_fft_forward(grid.nz), cp.plan_fft_inverse(grid.nz)]);
        let mut scratch = r2c.get_scratch_len().max(c2r.get_scratch_len());
        for f in fy.iter().chain(fz.iter().flatten()) {
            scratch = scratch.max(f.get_inplace_scratch_len());
        }
        let tuned = groups == 0;
        let groups = if tuned {
            4 * rayon::current_num_threads().max(1)
        } else {
            groups
        };
        // A block of columns holds block(len) * len values for each column length used;
        // the longest length need not give the largest block (120 x 120 x 32: 8 * 120 < 32 * 32).
        let lines_len = (block(grid.ny) * grid.ny).max(block(grid.nz) * grid.nz);
        let workspaces = (0..groups)
            .map(|_| Workspace {
                row: vec![0.0; grid.nx],
                fft_scratch: vec![Complex64::default(); scratch],
                lines: vec![Complex64::default(); lines_len],
            })
            .collect();
        Self {
            grid,
            r2c,
            c2r,
            fy,
            fz,
            workspaces,
            tuned,
            work: vec![Complex64::default(); grid.modes()],
        }
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// Workspaces (parallel tasks) a transform uses now: all of them, or on a small grid as
    /// many as give each at least [`grain`] values. Which lines a task gets never changes a
    /// line's transform.
    fn active(&self) -> usize {
        if self.tuned {
            self.workspaces
                .len()
                .min(self.grid.cells().div_ceil(grain()))
                .max(1)
        } else {
            self.workspaces.len()
        }
    }

    fn y_columns(&self) -> Columns {
        let g = self.grid;
        Columns {
            outer: g.nz,
            outer_stride: g.ny * g.nxh(),
            width: g.nxh(),
            len: g.ny,
            stride: g.nxh(),
        }
    }

    fn z_columns(&self) -> Columns {
        let g = self.grid;
        Columns {
            outer: g.ny,
            outer_stride: g.nxh(),
            width: g.nxh(),
            len: g.nz,
            stride: g.ny * g.nxh(),
        }
    }

    /// Transform the columns `cols` of `src` into `dst` (which may be `src`).
    ///
    /// # Safety
    /// `src` and `dst` must point to spectra of this grid's size, `dst` valid for writes.
    unsafe fn columns(
        workspaces: &mut [Workspace],
        fft: &dyn Fft<f64>,
        src: SharedPtr<Complex64>,
        dst: SharedPtr<Complex64>,
        c: Columns,
    ) {
        let bw = block(c.len);
        let blocks = c.width.div_ceil(bw);
        let items = c.outer * blocks;
        let per = items.div_ceil(workspaces.len());
        workspaces.par_iter_mut().enumerate().for_each(|(g, ws)| {
            let (src, dst) = (src, dst);
            for item in g * per..((g + 1) * per).min(items) {
                let o = item / blocks;
                let c0 = (item % blocks) * bw;
                let b = bw.min(c.width - c0);
                let base = o * c.outer_stride + c0;
                let lines = &mut ws.lines[..b * c.len];
                for i in 0..c.len {
                    let p = base + i * c.stride;
                    for j in 0..b {
                        // SAFETY: item (o, c0..c0 + b) owns these elements (see the caller).
                        lines[j * c.len + i] = unsafe { *src.0.add(p + j) };
                    }
                }
                fft.process_with_scratch(lines, &mut ws.fft_scratch);
                for i in 0..c.len {
                    let p = base + i * c.stride;
                    for j in 0..b {
                        unsafe { *dst.0.add(p + j) = lines[j * c.len + i] };
                    }
                }
            }
        });
    }

    /// Unnormalised forward transform of `real` into `spec`.
    pub fn forward(&mut self, real: &[f64], spec: &mut [Complex64]) {
        let g = self.grid;
        assert_eq!(real.len(), g.cells());
        assert_eq!(spec.len(), g.modes());
        let (nx, nxh) = (g.nx, g.nxh());
        let rows = g.rows();
        let active = self.active();
        let per = rows.div_ceil(active);
        let r2c = &self.r2c;
        spec.par_chunks_mut(per * nxh)
            .zip(real.par_chunks(per * nx))
            .zip(self.workspaces[..active].par_iter_mut())
            .for_each(|((s, r), ws)| {
                for (srow, rrow) in s.chunks_exact_mut(nxh).zip(r.chunks_exact(nx)) {
                    ws.row.copy_from_slice(rrow);
                    // Lengths are right by construction; realfft reports nothing else here.
                    let _ = r2c.process_with_scratch(&mut ws.row, srow, &mut ws.fft_scratch);
                }
            });
        let p = SharedPtr(spec.as_mut_ptr());
        let (ycols, zcols) = (self.y_columns(), self.z_columns());
        // SAFETY: `spec` has the grid's size (asserted above) and is exclusively borrowed.
        unsafe {
            Self::columns(&mut self.workspaces[..active], &*self.fy[0], p, p, ycols);
            if let Some(fz) = &self.fz {
                Self::columns(&mut self.workspaces[..active], &*fz[0], p, p, zcols);
            }
        }
    }

    /// Inverse transform of `spec` into `real`, divided by the number of cells. `spec` is
    /// left untouched. The imaginary parts that a real field's spectrum cannot have (kx = 0
    /// and, for even nx, the Nyquist column after the y and z transforms) are dropped.
    pub fn inverse(&mut self, spec: &[Complex64], real: &mut [f64]) {
        let g = self.grid;
        assert_eq!(real.len(), g.cells());
        assert_eq!(spec.len(), g.modes());
        let src = SharedPtr(spec.as_ptr() as *mut Complex64);
        let w = SharedPtr(self.work.as_mut_ptr());
        let (ycols, zcols) = (self.y_columns(), self.z_columns());
        let active = self.active();
        let ws = &mut self.workspaces[..active];
        // SAFETY: sizes asserted above; `src` is only read, `work` is owned by self.
        unsafe {
            if let Some(fz) = &self.fz {
                Self::columns(ws, &*fz[1], src, w, zcols);
                Self::columns(ws, &*self.fy[1], w, w, ycols);
            } else {
                Self::columns(ws, &*self.fy[1], src, w, ycols);
            }
        }
        let (nx, nxh) = (g.nx, g.nxh());
        let scale = 1.0 / g.cells() as f64;
        let per = g.rows().div_ceil(active);
        let c2r = &self.c2r;
        let even = nx % 2 == 0;
        self.work
            .par_chunks_mut(per * nxh)
            .zip(real.par_chunks_mut(per * nx))
            .zip(self.workspaces[..active].par_iter_mut())
            .for_each(|((s, r), ws)| {
                for (srow, rrow) in s.chunks_exact_mut(nxh).zip(r.chunks_exact_mut(nx)) {
                    srow[0].im = 0.0;
                    if even {
                        srow[nxh - 1].im = 0.0;
                    }
                    let _ = c2r.process_with_scratch(srow, rrow, &mut ws.fft_scratch);
                    for v in rrow.iter_mut() {
                        *v *= scale;
                    }
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(g: Grid) -> Vec<f64> {
        (0..g.cells())
            .map(|i| ((i * 7919) % 1013) as f64 / 1013.0 - 0.5)
            .collect()
    }

    #[test]
    fn round_trip_and_parseval_on_odd_and_even_grids() {
        for g in [
            Grid::new(2, [8, 8, 1]),
            Grid::new(2, [15, 12, 1]),
            Grid::new(3, [9, 10, 11]),
            Grid::new(3, [16, 12, 8]),
            // A short z whose column block outgrows the longest axis's (32 * 32 > 8 * 120).
            Grid::new(3, [4, 120, 32]),
        ] {
            let mut t = Transform::new(g, 3);
            let a = field(g);
            let mut s = vec![Complex64::default(); g.modes()];
            t.forward(&a, &mut s);
            let mut b = vec![0.0; g.cells()];
            t.inverse(&s, &mut b);
            let err = a
                .iter()
                .zip(&b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-14, "{g:?}: round trip {err:e}");
            // Mean mode.
            let sum: f64 = a.iter().sum();
            assert!((s[0].re - sum).abs() < 1e-11 && s[0].im.abs() < 1e-11);
        }
    }

    #[test]
    fn single_mode_lands_where_expected() {
        let g = Grid::new(3, [12, 10, 9]);
        let mut t = Transform::new(g, 0);
        let (mx, my, mz) = (2usize, 3usize, 4usize);
        let two_pi = 2.0 * std::f64::consts::PI;
        let mut a = vec![0.0; g.cells()];
        for z in 0..g.nz {
            for y in 0..g.ny {
                for x in 0..g.nx {
                    let ph = two_pi
                        * (mx as f64 * x as f64 / g.nx as f64
                            + my as f64 * y as f64 / g.ny as f64
                            + mz as f64 * z as f64 / g.nz as f64);
                    a[g.index(x, y, z)] = ph.cos();
                }
            }
        }
        let mut s = vec![Complex64::default(); g.modes()];
        t.forward(&a, &mut s);
        let at = s[(mz * g.ny + my) * g.nxh() + mx];
        assert!((at.re - g.cells() as f64 / 2.0).abs() < 1e-9, "{at}");
        let total: f64 = s.iter().map(|c| c.norm()).sum();
        assert!((total - at.norm()).abs() < 1e-8);
    }

    #[test]
    fn result_does_not_depend_on_the_split() {
        let g = Grid::new(3, [20, 14, 18]);
        let a = field(g);
        let run = |groups| {
            let mut t = Transform::new(g, groups);
            let mut s = vec![Complex64::default(); g.modes()];
            t.forward(&a, &mut s);
            let mut b = vec![0.0; g.cells()];
            t.inverse(&s, &mut b);
            (s, b)
        };
        let (s1, b1) = run(1);
        for groups in [2, 5, 64] {
            let (s, b) = run(groups);
            assert!(
                s1.iter()
                    .zip(&s)
                    .all(|(x, y)| x.re.to_bits() == y.re.to_bits()
                        && x.im.to_bits() == y.im.to_bits())
            );
            assert!(b1.iter().zip(&b).all(|(x, y)| x.to_bits() == y.to_bits()));
        }
    }
}
