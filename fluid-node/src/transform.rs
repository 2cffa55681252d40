//! Real-to-complex Fourier transforms of periodic 2D and 3D fields, planned once.
//!
//! Layout. A real field holds `nz * ny * nx` values with x fastest: index
//! `(z * ny + y) * nx + x` (in 2D `nz = 1`). Its spectrum holds `nz * ny * nxh` complex values,
//! `nxh = nx / 2 + 1`, in the same order: index `(kz * ny + ky) * nxh + kx`.
//!
//! Forward: realfft r2c along x (the contiguous last axis) row by row, then rustfft along y and
//! (in 3D) z in place, gathering blocks of neighbouring columns (see [`BLOCK_VALUES`]) into a
//! contiguous workspace so that the strided axes are read in long contiguous runs. In 3D the
//! rows and the y columns of one z plane are transformed together while the plane is in the
//! cache (the inverse: y columns then rows), so the spectrum crosses memory once less each
//! way. The forward transform is unnormalised; the inverse divides by the number of cells.
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
/// `max(MIN_BLOCK, BLOCK_VALUES / len)` neighbouring columns of `len` values, rounded down
/// to a multiple of `MIN_BLOCK`, so that a strided axis is read in runs of that many
/// contiguous values while the block stays in the L2 cache.
pub const BLOCK_VALUES: usize = 1024;
/// Fewest columns per block.
pub const MIN_BLOCK: usize = 8;

/// Columns per block for lines of `len` values.
fn block(len: usize) -> usize {
    // A multiple of MIN_BLOCK, so that whole blocks take the fixed-width copies.
    (BLOCK_VALUES / len.max(1)).max(MIN_BLOCK) / MIN_BLOCK * MIN_BLOCK
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
    /// Intermediate spectra of the inverse transform, one per field of a batch (the input is
    /// left untouched).
    work: Vec<Vec<Complex64>>,
}

/// Strided columns of a spectrum: `outer` groups `outer_stride` apart, each with `width`
/// neighbouring columns of `len` elements `stride` apart. Only the groups `o` with `keep[o]`
/// set are transformed (`keep` empty: all).
#[derive(Clone, Copy)]
struct Columns<'a> {
    outer: usize,
    outer_stride: usize,
    width: usize,
    len: usize,
    stride: usize,
    keep: &'a [bool],
}

/// Call `f(ws, item)` for every `item < items`, in parallel: workspace `w` takes the items
/// `w * per .. (w + 1) * per` in order (`per = ceil(items / workspaces)`).
fn share_items(
    workspaces: &mut [Workspace],
    items: usize,
    f: impl Fn(&mut Workspace, usize) + Sync + Send,
) {
    let per = items.div_ceil(workspaces.len().max(1));
    workspaces.par_iter_mut().enumerate().for_each(|(w, ws)| {
        for item in w * per..((w + 1) * per).min(items) {
            f(ws, item);
        }
    });
}

/// Whether every value of `row` is zero (either sign). Tested eight at a time, without an
/// early exit inside the eight, so that the test vectorises; a NaN is not zero.
fn all_zero(row: &[f64]) -> bool {
    let mut eights = row.chunks_exact(8);
    let nonzero = |c: &[f64]| c.iter().fold(false, |any, &v| any | (v != 0.0));
    !eights.any(nonzero) && !nonzero(eights.remainder())
}

/// Copy the `B` neighbouring columns starting at `base` (`len = lines.len() / B` values each,
/// `stride` apart) of `src` into `lines`, column `j` at `lines[j * len..]`. `B` fixed, so the
/// inner copy is unrolled and unchecked: every whole block, in groups of `MIN_BLOCK`.
///
/// # Safety
/// `src` must hold the `B` columns; no other task writes them meanwhile.
unsafe fn gather<const B: usize>(
    src: *const Complex64,
    (base, stride): (usize, usize),
    lines: &mut [Complex64],
) {
    let len = lines.len() / B;
    for i in 0..len {
        // SAFETY: the caller's; the row of B values lies inside the spectrum.
        let row: [Complex64; B] = unsafe { std::ptr::read(src.add(base + i * stride).cast()) };
        for (j, v) in row.into_iter().enumerate() {
            // SAFETY: j < B and i < len, so j * len + i < lines.len().
            unsafe { *lines.get_unchecked_mut(j * len + i) = v };
        }
    }
}

/// [`gather`] of `b` columns, `b` known only at run time (the narrower last block of a row).
///
/// # Safety
/// As for [`gather`].
unsafe fn gather_any(
    src: *const Complex64,
    (base, stride, b): (usize, usize, usize),
    lines: &mut [Complex64],
) {
    let len = lines.len() / b;
    for i in 0..len {
        let p = base + i * stride;
        for j in 0..b {
            // SAFETY: the caller's.
            lines[j * len + i] = unsafe { *src.add(p + j) };
        }
    }
}

/// The inverse of [`gather`]: column `j` of `lines` back into column `base + j` of `dst`.
///
/// # Safety
/// `dst` must hold the `B` columns and be valid for writes; no other task touches them.
unsafe fn scatter<const B: usize>(
    lines: &[Complex64],
    dst: *mut Complex64,
    (base, stride): (usize, usize),
) {
    let len = lines.len() / B;
    for i in 0..len {
        let mut row = [Complex64::default(); B];
        for (j, v) in row.iter_mut().enumerate() {
            // SAFETY: j < B and i < len, so j * len + i < lines.len().
            *v = unsafe { *lines.get_unchecked(j * len + i) };
        }
        // SAFETY: the caller's.
        unsafe { std::ptr::write(dst.add(base + i * stride).cast(), row) };
    }
}

/// [`scatter`] of `b` columns, `b` known only at run time.
///
/// # Safety
/// As for [`scatter`].
unsafe fn scatter_any(
    lines: &[Complex64],
    dst: *mut Complex64,
    (base, stride, b): (usize, usize, usize),
) {
    let len = lines.len() / b;
    for i in 0..len {
        let p = base + i * stride;
        for j in 0..b {
            // SAFETY: the caller's.
            unsafe { *dst.add(p + j) = lines[j * len + i] };
        }
    }
}

/// Which modes a forward transform must deliver.
#[derive(Clone, Copy, Debug)]
pub enum Modes<'a> {
    /// Every mode.
    All,
    /// Only the modes a dealiased product keeps (the 2/3 rule): kx below `kx` (a prefix of
    /// the stored kx) and, in 3D, ky with `ky[iy]` set. The strided transforms of the other
    /// columns are skipped, so their values are unfinished and must not be read.
    Band { kx: usize, ky: &'a [bool] },
}

/// Most fields one batched transform takes.
pub const MAX_BATCH: usize = 4;

impl Transform {
    /// Plan the transforms of `grid` and allocate workspaces for `groups` parallel tasks
    /// (`0`: four per rayon thread, of which a transform uses fewer on small grids, so that a
    /// task has at least [`grain`] values at the time).
    pub fn new(grid: Grid, groups: usize) -> Self {
        Self::with_batch(grid, groups, 1)
    }

    /// As [`Transform::new`], with the intermediate spectra for inverse transforms of `batch`
    /// fields at once ([`Transform::inverse_many`]); more fields are taken `batch` at a time.
    pub fn with_batch(grid: Grid, groups: usize, batch: usize) -> Self {
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
            work: (0..batch.clamp(1, MAX_BATCH))
                .map(|_| vec![Complex64::default(); grid.modes()])
                .collect(),
        }
    }

    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// Workspaces (parallel tasks) a transform of `fields` fields uses now: all of them, or on
    /// a small grid as many as give each at least [`grain`] values. Which lines a task gets
    /// never changes a line's transform.
    fn active(&self, fields: usize) -> usize {
        if self.tuned {
            self.workspaces
                .len()
                .min((fields * self.grid.cells()).div_ceil(grain()))
                .max(1)
        } else {
            self.workspaces.len()
        }
    }

    fn y_columns(&self, width: usize) -> Columns<'static> {
        let g = self.grid;
        Columns {
            outer: g.nz,
            outer_stride: g.ny * g.nxh(),
            width,
            len: g.ny,
            stride: g.nxh(),
            keep: &[],
        }
    }

    fn z_columns<'a>(&self, width: usize, keep: &'a [bool]) -> Columns<'a> {
        let g = self.grid;
        Columns {
            outer: g.ny,
            outer_stride: g.nxh(),
            width,
            len: g.nz,
            stride: g.ny * g.nxh(),
            keep,
        }
    }

    /// Transform the columns `c` of every `src[f]` into `dst[f]` (which may be `src[f]`), the
    /// blocks of all fields shared out in one parallel pass.
    ///
    /// # Safety
    /// Every `src[f]` and `dst[f]` must point to a spectrum of this grid's size, `dst[f]`
    /// valid for writes and touched by nothing else meanwhile.
    unsafe fn columns(
        workspaces: &mut [Workspace],
        fft: &dyn Fft<f64>,
        src: &[SharedPtr<Complex64>],
        dst: &[SharedPtr<Complex64>],
        c: Columns,
    ) {
        let blocks = c.width.div_ceil(block(c.len));
        let per_field = c.outer * blocks;
        share_items(workspaces, src.len() * per_field, |ws, item| {
            let (f, rest) = (item / per_field, item % per_field);
            let o = rest / blocks;
            if !c.keep.get(o).copied().unwrap_or(true) {
                return;
            }
            // SAFETY: item (f, o, block) owns these elements (see the caller).
            unsafe { Self::column_block(ws, fft, (src[f], dst[f]), &c, o, rest % blocks) };
        });
    }

    /// Transform block `blk` of the columns of group `o` (see [`Columns`]) of `src` into `dst`.
    ///
    /// # Safety
    /// As for [`Self::columns`]; no other task touches these columns meanwhile.
    unsafe fn column_block(
        ws: &mut Workspace,
        fft: &dyn Fft<f64>,
        (src, dst): (SharedPtr<Complex64>, SharedPtr<Complex64>),
        c: &Columns,
        o: usize,
        blk: usize,
    ) {
        let bw = block(c.len);
        let c0 = blk * bw;
        let b = bw.min(c.width - c0);
        let base = o * c.outer_stride + c0;
        let lines = &mut ws.lines[..b * c.len];
        let group = MIN_BLOCK * c.len;
        // SAFETY: the caller's: these columns are this task's.
        unsafe {
            if b.is_multiple_of(MIN_BLOCK) {
                for (g, part) in lines.chunks_exact_mut(group).enumerate() {
                    gather::<MIN_BLOCK>(src.0, (base + g * MIN_BLOCK, c.stride), part);
                }
            } else {
                gather_any(src.0, (base, c.stride, b), lines);
            }
        }
        fft.process_with_scratch(lines, &mut ws.fft_scratch);
        // SAFETY: as for the gather.
        unsafe {
            if b.is_multiple_of(MIN_BLOCK) {
                for (g, part) in lines.chunks_exact(group).enumerate() {
                    scatter::<MIN_BLOCK>(part, dst.0, (base + g * MIN_BLOCK, c.stride));
                }
            } else {
                scatter_any(lines, dst.0, (base, c.stride, b));
            }
        }
    }

    /// Whether the y columns are transformed plane by plane together with the rows of the
    /// plane: in 3D a z plane's spectrum (`ny * nxh` values) stays in the cache between the
    /// row and the column transforms, so the spectrum crosses memory once less each way. 2D
    /// has one plane and keeps the separate passes, which share rows and columns out.
    fn by_planes(&self, fields: usize) -> bool {
        self.fz.is_some() && fields * self.grid.nz >= self.workspaces.len()
    }

    /// Unnormalised forward transform of `real` into `spec`.
    pub fn forward(&mut self, real: &[f64], spec: &mut [Complex64]) {
        let g = self.grid;
        assert_eq!(real.len(), g.cells());
        let nx = g.nx;
        self.forward_rows(
            &mut [spec],
            |_, r, out| out.copy_from_slice(&real[r * nx..(r + 1) * nx]),
            Modes::All,
        );
    }

    /// Unnormalised forward transforms of several real fields, given row by row:
    /// `row(f, r, out)` writes row `r` (`nx` values, `r = z * ny + y`) of field `f` into
    /// `out`, and its transform goes to `specs[f]`. All fields share one parallel pass per
    /// axis, and a field need not be stored (a product can be formed row by row). A row of
    /// zeros is not transformed (its spectrum row is zero, up to the sign of zero). `modes`
    /// may restrict which modes are finished.
    pub fn forward_rows(
        &mut self,
        specs: &mut [&mut [Complex64]],
        row: impl Fn(usize, usize, &mut [f64]) + Sync,
        modes: Modes,
    ) {
        let g = self.grid;
        let k = specs.len();
        assert!(
            (1..=MAX_BATCH).contains(&k),
            "forward_rows: 1..={MAX_BATCH} fields"
        );
        assert!(specs.iter().all(|s| s.len() == g.modes()));
        let (nxh, rows) = (g.nxh(), g.rows());
        let mut ptrs = [SharedPtr(std::ptr::null_mut()); MAX_BATCH];
        for (p, s) in ptrs.iter_mut().zip(specs.iter_mut()) {
            *p = SharedPtr(s.as_mut_ptr());
        }
        let ptrs = &ptrs[..k];
        let active = self.active(k);
        let r2c = &self.r2c;
        let (width, ky): (usize, &[bool]) = match modes {
            Modes::All => (nxh, &[]),
            Modes::Band { kx, ky } => (kx.min(nxh), if g.dims == 3 { ky } else { &[] }),
        };
        let (ycols, zcols) = (self.y_columns(width), self.z_columns(width, ky));
        let one_row = |ws: &mut Workspace, f: usize, r: usize| {
            // SAFETY: row r of spectrum f is written by this item only; the spectra
            // are distinct exclusive borrows of the grid's size (asserted above).
            let srow = unsafe { std::slice::from_raw_parts_mut(ptrs[f].0.add(r * nxh), nxh) };
            row(f, r, &mut ws.row);
            if all_zero(&ws.row) {
                srow.fill(Complex64::default());
            } else {
                // Lengths are right by construction; realfft reports nothing else.
                let _ = r2c.process_with_scratch(&mut ws.row, srow, &mut ws.fft_scratch);
            }
        };
        if self.by_planes(k) {
            let (ny, nz) = (g.ny, g.nz);
            let blocks = width.div_ceil(block(ny));
            let fy = &*self.fy[0];
            share_items(&mut self.workspaces[..active], k * nz, |ws, item| {
                let (f, z) = (item / nz, item % nz);
                for y in 0..ny {
                    one_row(ws, f, z * ny + y);
                }
                for blk in 0..blocks {
                    // SAFETY: plane z of spectrum f belongs to this item only.
                    unsafe { Self::column_block(ws, fy, (ptrs[f], ptrs[f]), &ycols, z, blk) };
                }
            });
        } else {
            share_items(&mut self.workspaces[..active], k * rows, |ws, item| {
                one_row(ws, item / rows, item % rows)
            });
            // SAFETY: as for the rows.
            unsafe {
                Self::columns(
                    &mut self.workspaces[..active],
                    &*self.fy[0],
                    ptrs,
                    ptrs,
                    ycols,
                )
            };
        }
        if let Some(fz) = &self.fz {
            // SAFETY: as for the rows.
            unsafe { Self::columns(&mut self.workspaces[..active], &*fz[0], ptrs, ptrs, zcols) };
        }
    }

    /// Inverse transform of `spec` into `real`, divided by the number of cells. `spec` is
    /// left untouched. The imaginary parts that a real field's spectrum cannot have (kx = 0
    /// and, for even nx, the Nyquist column after the y and z transforms) are dropped.
    pub fn inverse(&mut self, spec: &[Complex64], real: &mut [f64]) {
        self.inverse_many(&[spec], &mut [real]);
    }

    /// [`Transform::inverse`] of several fields, `specs[f]` into `reals[f]`, sharing one
    /// parallel pass per axis among as many fields as [`Transform::with_batch`] allows.
    pub fn inverse_many(&mut self, specs: &[&[Complex64]], reals: &mut [&mut [f64]]) {
        self.inverse_rows(specs, reals, &[]);
    }

    /// [`Transform::inverse_many`] that writes only the rows `r` of the real fields with
    /// `rows[r]` set (`rows` empty: all); the other rows are left as they were. The strided
    /// passes are whole, so a written row is exactly what a full inverse gives.
    pub fn inverse_rows(
        &mut self,
        specs: &[&[Complex64]],
        reals: &mut [&mut [f64]],
        rows: &[bool],
    ) {
        let g = self.grid;
        assert!(rows.is_empty() || rows.len() == g.rows());
        assert_eq!(specs.len(), reals.len());
        assert!(specs.iter().all(|s| s.len() == g.modes()));
        assert!(reals.iter().all(|r| r.len() == g.cells()));
        let batch = self.work.len();
        for (specs, reals) in specs.chunks(batch).zip(reals.chunks_mut(batch)) {
            self.inverse_batch(
                specs,
                reals,
                rows,
                None::<&fn(usize, usize, &[f64], &mut [f64])>,
            );
        }
    }

    /// Inverse transforms of `specs[f]` whose real rows are not stored but handed over as
    /// they are finished: `combine(f, r, row, out)` with `row` row `r` of field f's inverse
    /// and `out` row `r` of `outs[f]` (e.g. `out = -ψ row`, a product formed without a
    /// stored field). Batched as [`Transform::inverse_many`].
    pub fn inverse_combine(
        &mut self,
        specs: &[&[Complex64]],
        outs: &mut [&mut [f64]],
        combine: impl Fn(usize, usize, &[f64], &mut [f64]) + Sync,
    ) {
        let g = self.grid;
        assert_eq!(specs.len(), outs.len());
        assert!(specs.iter().all(|s| s.len() == g.modes()));
        assert!(outs.iter().all(|r| r.len() == g.cells()));
        let batch = self.work.len();
        for (i, (specs, outs)) in specs.chunks(batch).zip(outs.chunks_mut(batch)).enumerate() {
            let shifted = |f: usize, r: usize, row: &[f64], out: &mut [f64]| {
                combine(i * batch + f, r, row, out)
            };
            self.inverse_batch(specs, outs, &[], Some(&shifted));
        }
    }

    fn inverse_batch<C: Fn(usize, usize, &[f64], &mut [f64]) + Sync>(
        &mut self,
        specs: &[&[Complex64]],
        reals: &mut [&mut [f64]],
        only: &[bool],
        combine: Option<&C>,
    ) {
        let g = self.grid;
        let k = specs.len();
        let mut src = [SharedPtr(std::ptr::null_mut()); MAX_BATCH];
        let mut w = [SharedPtr(std::ptr::null_mut()); MAX_BATCH];
        for f in 0..k {
            src[f] = SharedPtr(specs[f].as_ptr() as *mut Complex64);
            w[f] = SharedPtr(self.work[f].as_mut_ptr());
        }
        let (src, w) = (&src[..k], &w[..k]);
        let nxh = g.nxh();
        let (ycols, zcols) = (self.y_columns(nxh), self.z_columns(nxh, &[]));
        let active = self.active(k);
        let by_planes = self.by_planes(k);
        let ws = &mut self.workspaces[..active];
        // SAFETY: sizes asserted by the caller; `src` is only read, `work` is owned by self.
        unsafe {
            if let Some(fz) = &self.fz {
                Self::columns(ws, &*fz[1], src, w, zcols);
                if !by_planes {
                    Self::columns(ws, &*self.fy[1], w, w, ycols);
                }
            } else {
                Self::columns(ws, &*self.fy[1], src, w, ycols);
            }
        }
        let (nx, rows) = (g.nx, g.rows());
        let mut out = [SharedPtr(std::ptr::null_mut()); MAX_BATCH];
        for (o, r) in out.iter_mut().zip(reals.iter_mut()) {
            *o = SharedPtr(r.as_mut_ptr());
        }
        let out = &out[..k];
        let scale = 1.0 / g.cells() as f64;
        let c2r = &self.c2r;
        let even = nx % 2 == 0;
        let wanted = |r: usize| only.get(r).copied().unwrap_or(true);
        let one_row = |ws: &mut Workspace, f: usize, r: usize| {
            if !wanted(r) {
                return;
            }
            // SAFETY: row r of work spectrum f and of real field f belong to this item
            // only; the work spectra are self's, the fields distinct exclusive borrows.
            let (srow, rrow) = unsafe {
                (
                    std::slice::from_raw_parts_mut(w[f].0.add(r * nxh), nxh),
                    std::slice::from_raw_parts_mut(out[f].0.add(r * nx), nx),
                )
            };
            srow[0].im = 0.0;
            if even {
                srow[nxh - 1].im = 0.0;
            }
            match combine {
                None => {
                    let _ = c2r.process_with_scratch(srow, rrow, &mut ws.fft_scratch);
                    for v in rrow.iter_mut() {
                        *v *= scale;
                    }
                }
                Some(combine) => {
                    let row = &mut ws.row;
                    let _ = c2r.process_with_scratch(srow, row, &mut ws.fft_scratch);
                    for v in row.iter_mut() {
                        *v *= scale;
                    }
                    combine(f, r, row, rrow);
                }
            }
        };
        if by_planes {
            // Plane by plane: the y columns, then the rows, while the plane is in the cache;
            // a plane none of whose rows is wanted is skipped.
            let (ny, nz) = (g.ny, g.nz);
            let blocks = nxh.div_ceil(block(ny));
            let fy = &*self.fy[1];
            share_items(&mut self.workspaces[..active], k * nz, |ws, item| {
                let (f, z) = (item / nz, item % nz);
                if !(0..ny).any(|y| wanted(z * ny + y)) {
                    return;
                }
                for blk in 0..blocks {
                    // SAFETY: plane z of work spectrum f belongs to this item only.
                    unsafe { Self::column_block(ws, fy, (w[f], w[f]), &ycols, z, blk) };
                }
                for y in 0..ny {
                    one_row(ws, f, z * ny + y);
                }
            });
        } else {
            share_items(&mut self.workspaces[..active], k * rows, |ws, item| {
                one_row(ws, item / rows, item % rows)
            });
        }
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
    fn all_zero_is_the_elementwise_test() {
        for n in [0, 1, 7, 8, 9, 16, 23, 256] {
            let mut row = vec![0.0; n];
            assert!(all_zero(&row), "{n} zeros");
            for i in 0..n {
                for (v, zero) in [(-0.0, true), (1e-300, false), (f64::NAN, false)] {
                    row[i] = v;
                    assert_eq!(all_zero(&row), zero, "n = {n}, row[{i}] = {v}");
                    assert_eq!(all_zero(&row), row.iter().all(|&x| x == 0.0));
                    row[i] = 0.0;
                }
            }
        }
    }

    #[test]
    fn fixed_width_column_copies_match_the_general_ones() {
        // 8 columns of 5 values, 11 apart, starting at 3, in a spectrum of 60 values.
        let (base, stride, len) = (3, 11, 5);
        let spec: Vec<Complex64> = (0..60)
            .map(|i| Complex64::new(i as f64, -(i as f64) / 7.0))
            .collect();
        let (mut fixed, mut any) = (
            vec![Complex64::default(); 40],
            vec![Complex64::default(); 40],
        );
        // SAFETY: the columns lie within `spec` (3 + 4 * 11 + 7 < 60).
        unsafe {
            gather::<8>(spec.as_ptr(), (base, stride), &mut fixed);
            gather_any(spec.as_ptr(), (base, stride, 8), &mut any);
        }
        assert_eq!(fixed, any);
        assert_eq!(fixed[2 * len + 4], spec[base + 4 * stride + 2]);
        let lines: Vec<Complex64> = (0..40).map(|i| Complex64::new(-(i as f64), 0.5)).collect();
        let (mut a, mut b) = (spec.clone(), spec.clone());
        // SAFETY: as above.
        unsafe {
            scatter::<8>(&lines, a.as_mut_ptr(), (base, stride));
            scatter_any(&lines, b.as_mut_ptr(), (base, stride, 8));
        }
        assert_eq!(a, b);
        assert_eq!(a[base + 4 * stride + 2], lines[2 * len + 4]);
        assert_eq!(a[base + 8], spec[base + 8], "outside the block");
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

    /// The forward transform by its definition, O(cells * modes), in the spectrum's layout.
    fn naive_dft(g: Grid, a: &[f64]) -> Vec<Complex64> {
        let two_pi = 2.0 * std::f64::consts::PI;
        let mut s = vec![Complex64::default(); g.modes()];
        for kz in 0..g.nz {
            for ky in 0..g.ny {
                for kx in 0..g.nxh() {
                    let mut sum = Complex64::default();
                    for z in 0..g.nz {
                        for y in 0..g.ny {
                            for x in 0..g.nx {
                                let ph = -two_pi
                                    * ((kx * x) as f64 / g.nx as f64
                                        + (ky * y) as f64 / g.ny as f64
                                        + (kz * z) as f64 / g.nz as f64);
                                sum += Complex64::from_polar(a[g.index(x, y, z)], ph);
                            }
                        }
                    }
                    s[(kz * g.ny + ky) * g.nxh() + kx] = sum;
                }
            }
        }
        s
    }

    /// Batched transforms give each field the bits of its own transform; a banded forward
    /// transform gives those bits on the kept modes; rows of zeros come out as zeros.
    #[test]
    fn batches_and_bands_keep_each_fields_bits() {
        use crate::grid::Wavenumbers;
        let same = |a: &[Complex64], b: &[Complex64]| {
            a.iter()
                .zip(b)
                .all(|(x, y)| x.re.to_bits() == y.re.to_bits() && x.im == y.im)
        };
        for g in [Grid::new(2, [24, 18, 1]), Grid::new(3, [12, 10, 9])] {
            let fields: Vec<Vec<f64>> = (0..3)
                .map(|f| {
                    let mut a = field(g);
                    a.iter_mut().for_each(|v| *v *= 1.0 + f as f64);
                    // Some rows of zeros.
                    a[..g.nx * (f + 1)].fill(0.0);
                    a
                })
                .collect();
            let mut t = Transform::with_batch(g, 0, 2);
            let single: Vec<Vec<Complex64>> = fields
                .iter()
                .map(|a| {
                    let mut s = vec![Complex64::default(); g.modes()];
                    t.forward(a, &mut s);
                    s
                })
                .collect();
            let mut batch = vec![vec![Complex64::default(); g.modes()]; 3];
            let mut specs: Vec<&mut [Complex64]> = batch.iter_mut().map(|v| &mut v[..]).collect();
            let nx = g.nx;
            t.forward_rows(
                &mut specs,
                |f, r, out| out.copy_from_slice(&fields[f][r * nx..(r + 1) * nx]),
                Modes::All,
            );
            for (s, b) in single.iter().zip(&batch) {
                assert!(same(s, b), "{g:?}: batched forward");
            }
            // Skipping the rows of zeros leaves the transform right: a plain DFT.
            for (a, s) in fields.iter().zip(&single) {
                let err = naive_dft(g, a)
                    .iter()
                    .zip(s)
                    .map(|(x, y)| (x - y).norm())
                    .fold(0.0, f64::max);
                assert!(err < 1e-11, "{g:?}: against the plain DFT {err:e}");
            }
            let w = Wavenumbers::new(g);
            let kx = w.x.keep.iter().take_while(|&&k| k).count();
            let mut banded = vec![Complex64::default(); g.modes()];
            t.forward_rows(
                &mut [&mut banded[..]],
                |_, r, out| out.copy_from_slice(&fields[1][r * nx..(r + 1) * nx]),
                Modes::Band { kx, ky: &w.y.keep },
            );
            let nxh = g.nxh();
            for (i, (a, b)) in banded.iter().zip(&single[1]).enumerate() {
                let (ix, r) = (i % nxh, i / nxh);
                let (iy, iz) = g.row_yz(r);
                if w.x.keep[ix] && w.y.keep[iy] && w.z.keep[iz] {
                    assert!(same(&[*a], &[*b]), "{g:?}: banded mode {i}");
                }
            }
            // Inverse: three fields through a batch of two, against one at a time.
            let mut one = vec![vec![0.0; g.cells()]; 3];
            for (s, o) in single.iter().zip(one.iter_mut()) {
                t.inverse(s, o);
            }
            let mut many = vec![vec![0.0; g.cells()]; 3];
            let specs: Vec<&[Complex64]> = single.iter().map(|v| &v[..]).collect();
            let mut reals: Vec<&mut [f64]> = many.iter_mut().map(|v| &mut v[..]).collect();
            t.inverse_many(&specs, &mut reals);
            for (a, b) in one.iter().zip(&many) {
                assert!(a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()));
            }
            // Rows handed over as finished: out -= 0.5 * row, against the stored inverse.
            let mut combined = vec![vec![1.0; g.cells()]; 3];
            let mut outs: Vec<&mut [f64]> = combined.iter_mut().map(|v| &mut v[..]).collect();
            t.inverse_combine(&specs, &mut outs, |f, _, row, out| {
                assert_eq!(row.len(), nx);
                for (o, v) in out.iter_mut().zip(row) {
                    *o -= 0.5 * (f as f64 + 1.0) * v;
                }
            });
            for (f, (a, b)) in one.iter().zip(&combined).enumerate() {
                let want = a.iter().map(|v| 1.0 - 0.5 * (f as f64 + 1.0) * v);
                assert!(
                    want.zip(b).all(|(x, y)| x.to_bits() == y.to_bits()),
                    "field {f}"
                );
            }
        }
    }

    /// 3D inverse transforms plane by plane write exactly the wanted rows, with the bits of
    /// the full inverse, and skip planes with none; forward by planes = separate passes
    /// (64 workspaces for 9 planes take the separate passes).
    #[test]
    fn planes_keep_the_bits_of_separate_passes() {
        let g = Grid::new(3, [12, 10, 9]);
        let a = field(g);
        let (mut planes, mut passes) = (Transform::new(g, 2), Transform::new(g, 64));
        assert!(planes.by_planes(1) && !passes.by_planes(1));
        let mut s = vec![Complex64::default(); g.modes()];
        let mut s2 = s.clone();
        planes.forward(&a, &mut s);
        passes.forward(&a, &mut s2);
        let bits = |v: &[Complex64]| -> Vec<(u64, u64)> {
            v.iter().map(|c| (c.re.to_bits(), c.im.to_bits())).collect()
        };
        assert_eq!(bits(&s), bits(&s2));
        let mut full = vec![0.0; g.cells()];
        passes.inverse(&s, &mut full);
        // Rows wanted in planes 2 and 5 only.
        let rows: Vec<bool> = (0..g.rows())
            .map(|r| matches!(g.row_yz(r), (y, 2) if y % 3 == 0) || g.row_yz(r).1 == 5)
            .collect();
        let mut part = vec![7.0; g.cells()];
        planes.inverse_rows(&[&s], &mut [&mut part], &rows);
        for (i, (p, f)) in part.iter().zip(&full).enumerate() {
            let want = if rows[i / g.nx] { *f } else { 7.0 };
            assert_eq!(p.to_bits(), want.to_bits(), "cell {i}");
        }
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
