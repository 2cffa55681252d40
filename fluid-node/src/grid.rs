//! The periodic Eulerian grid: grid units (spacing 1), nodes at integer coordinates
//! `0..n` along each axis, x fastest in memory.
use std::f64::consts::PI;

/// Sizes of a periodic 2D (`nz = 1`) or 3D grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Grid {
    /// 2 or 3.
    pub dims: usize,
    pub nx: usize,
    pub ny: usize,
    /// 1 in 2D.
    pub nz: usize,
}

impl Grid {
    /// `n = [nx, ny, nz]`; `nz` is taken as 1 in 2D.
    pub fn new(dims: usize, n: [usize; 3]) -> Self {
        Self {
            dims,
            nx: n[0],
            ny: n[1],
            nz: if dims == 2 { 1 } else { n[2] },
        }
    }

    /// Sizes as an array.
    pub fn sizes(&self) -> [usize; 3] {
        [self.nx, self.ny, self.nz]
    }

    /// Number of cells (grid nodes).
    pub fn cells(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    /// Number of x rows, `ny * nz`.
    pub fn rows(&self) -> usize {
        self.ny * self.nz
    }

    /// Complex values per spectral row, `nx / 2 + 1`.
    pub fn nxh(&self) -> usize {
        self.nx / 2 + 1
    }

    /// `(y index, z index)` of row `r` (real or spectral; rows run over y, then z).
    #[inline]
    pub fn row_yz(&self, r: usize) -> (usize, usize) {
        (r % self.ny, r / self.ny)
    }

    /// Number of stored Fourier modes, `nxh * ny * nz`.
    pub fn modes(&self) -> usize {
        self.nxh() * self.ny * self.nz
    }

    /// Index of node (x, y, z) in a real field.
    #[inline]
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.ny + y) * self.nx + x
    }
}

/// Wavenumbers of one axis of `n` nodes, for spectral index `m` in storage order.
#[derive(Debug, Clone)]
pub struct Axis {
    /// Wavenumber used for first derivatives: `2 pi m' / n` with `m'` the signed index, and
    /// 0 at the Nyquist index of an even axis (its derivative of a real field is not real).
    pub k: Vec<f64>,
    /// Square of the true wavenumber (Nyquist included), for the Laplacian.
    pub k2: Vec<f64>,
    /// 2/3 rule: keep a mode of the advection term when `3 |m'| < n`.
    pub keep: Vec<bool>,
}

impl Axis {
    /// Axis of `n` nodes whose spectrum stores `stored` indices (`n / 2 + 1` for the
    /// half-spectrum axis of a real transform, `n` otherwise).
    pub fn new(n: usize, stored: usize) -> Self {
        let mut k = Vec::with_capacity(stored);
        let mut k2 = Vec::with_capacity(stored);
        let mut keep = Vec::with_capacity(stored);
        for m in 0..stored {
            let signed = if m <= n / 2 {
                m as i64
            } else {
                m as i64 - n as i64
            };
            let kk = 2.0 * PI * signed as f64 / n as f64;
            let nyquist = n & 1 == 0 && m == n / 2;
            k.push(if nyquist { 0.0 } else { kk });
            k2.push(kk * kk);
            keep.push(3 * signed.unsigned_abs() < n as u64);
        }
        Self { k, k2, keep }
    }
}

/// The three axes of a grid's spectrum (in 2D the z axis has the single index 0).
#[derive(Debug, Clone)]
pub struct Wavenumbers {
    pub x: Axis,
    pub y: Axis,
    pub z: Axis,
}

impl Wavenumbers {
    pub fn new(g: Grid) -> Self {
        Self {
            x: Axis::new(g.nx, g.nxh()),
            y: Axis::new(g.ny, g.ny),
            z: Axis::new(g.nz, g.nz),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axis_wavenumbers_nyquist_and_dealiasing() {
        let a = Axis::new(8, 8);
        assert_eq!(a.k[4], 0.0);
        assert!((a.k2[4] - PI * PI).abs() < 1e-15);
        assert!((a.k[5] + 2.0 * PI * 3.0 / 8.0).abs() < 1e-15);
        // 3 |m| < 8: m = -2..=2 kept.
        assert_eq!(
            a.keep,
            vec![true, true, true, false, false, false, true, true]
        );
        let odd = Axis::new(9, 5);
        assert!(odd.k[4] > 0.0);
        assert_eq!(odd.keep, vec![true, true, true, false, false]);
    }
}
