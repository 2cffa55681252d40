//! One bead's interfacial profile of S2023 eq. 2 on the D2Q9 lattice,
//!
//! ```text
//! phi_i(r) = 1/2 { tanh[(a - |r - R_i|) / xi] + 1 },
//! ```
//!
//! evaluated only inside the bead's cut-off box, the nodes within `a + cutoff xi` of the
//! centre along each axis. Beyond that distance phi_i is set to 0: the jump there,
//! 1/2 (1 - tanh(cutoff)) ~ exp(-2 cutoff), is 4.5e-5 for the default cutoff of 5 interface
//! thicknesses, below what the viscosity field (eq. 1) can resolve, and it cannot bias the
//! force or velocity of the bead because eqs. 4 and 5 normalise by the grid sum of the same
//! truncated profile.
//!
//! Lattice geometry follows [`crate::mrt_d2q9`]: node (x, y) at integer coordinates, periodic
//! in x; in y either periodic or closed by walls at y = -1/2 and ny - 1/2, in which case the
//! rows beyond the walls are dropped from the box (the bead's profile is cut by the wall and
//! its grid sum shrinks accordingly).

/// S2023 eq. 2 at distance `r` from the centre of a bead of radius `a` and interface
/// thickness `xi`, without cut-off.
#[inline]
pub fn profile(r: f64, a: f64, xi: f64) -> f64 {
    0.5 * (((a - r) / xi).tanh() + 1.0)
}

/// A bead's box: the lattice rows and columns it covers, their offsets from the centre, and
/// phi_i at each node. Buffers are sized once, for the largest box the bead can have.
#[derive(Debug, Clone)]
pub struct BeadBox {
    /// Centre, wrapped into the lattice (x always; y when periodic).
    centre: [f64; 2],
    /// (wrapped column index, x offset from the centre) per box column.
    cols: Vec<(usize, f64)>,
    /// (row index, y offset from the centre) per box row inside the lattice.
    rows: Vec<(usize, f64)>,
    /// phi_i per box node, row by row.
    values: Vec<f64>,
    /// Grid sum of phi_i (cell volume 1): the discrete ∫ phi_i dr of eqs. 4 and 5.
    volume: f64,
}

/// Largest number of box nodes along one axis for a reach (half-width) `reach`.
pub fn max_extent(reach: f64) -> usize {
    // Saturating: a reach too large to count must stay larger than any lattice.
    ((2.0 * reach).floor() as usize).saturating_add(1)
}

impl BeadBox {
    /// An empty box with room for `max_extent(reach)` nodes per axis.
    pub fn new(reach: f64) -> Self {
        let n = max_extent(reach);
        Self {
            centre: [0.0; 2],
            cols: Vec::with_capacity(n),
            rows: Vec::with_capacity(n),
            values: Vec::with_capacity(n * n),
            volume: 0.0,
        }
    }

    /// Centre as placed (wrapped into the lattice along periodic axes).
    pub fn centre(&self) -> [f64; 2] {
        self.centre
    }

    /// Grid sum of phi_i.
    pub fn volume(&self) -> f64 {
        self.volume
    }

    /// Evaluate eq. 2 around `centre` (already checked to lie in the lattice and wrapped
    /// along periodic axes) for radius `a`, thickness `xi`, cut-off distance `reach - a`.
    #[allow(clippy::too_many_arguments)]
    pub fn place(
        &mut self,
        centre: [f64; 2],
        a: f64,
        xi: f64,
        reach: f64,
        nx: usize,
        ny: usize,
        periodic_y: bool,
    ) {
        self.centre = centre;
        axis(&mut self.cols, centre[0], reach, nx, true);
        axis(&mut self.rows, centre[1], reach, ny, periodic_y);
        self.values.clear();
        // Summed row by row in box order: a fixed order, so the volume is reproducible.
        let mut volume = 0.0;
        for &(_, ry) in &self.rows {
            for &(_, rx) in &self.cols {
                let r = (rx * rx + ry * ry).sqrt();
                let p = if r > reach { 0.0 } else { profile(r, a, xi) };
                self.values.push(p);
                volume += p;
            }
        }
        self.volume = volume;
    }

    /// Call `f(x, y, [rx, ry], phi_i)` for every box node (x, y), in a fixed order (rows,
    /// then columns), with (rx, ry) its offset from the centre (minimum image along periodic
    /// axes).
    #[inline]
    pub fn for_each(&self, mut f: impl FnMut(usize, usize, [f64; 2], f64)) {
        let mut v = 0;
        for &(y, ry) in &self.rows {
            for &(x, rx) in &self.cols {
                f(x, y, [rx, ry], self.values[v]);
                v += 1;
            }
        }
    }
}

/// Nodes within `reach` of coordinate `c` along an axis of `n` nodes: (index, offset) pairs,
/// wrapped when `periodic`, otherwise only those inside 0..n.
fn axis(out: &mut Vec<(usize, f64)>, c: f64, reach: f64, n: usize, periodic: bool) {
    out.clear();
    let lo = (c - reach).ceil() as i64;
    let hi = (c + reach).floor() as i64;
    for k in lo..=hi {
        let offset = k as f64 - c;
        if periodic {
            out.push((k.rem_euclid(n as i64) as usize, offset));
        } else if (0..n as i64).contains(&k) {
            out.push((k as usize, offset));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_is_half_at_the_surface_and_bounded() {
        assert_eq!(profile(3.0, 3.0, 0.5), 0.5);
        for r in [0.0, 1.0, 2.9, 3.1, 10.0] {
            let p = profile(r, 3.0, 0.5);
            assert!((0.0..=1.0).contains(&p));
        }
        // Symmetric about the surface: phi(a - s) + phi(a + s) = 1.
        for s in [0.1, 0.7, 2.0] {
            assert!((profile(3.0 - s, 3.0, 0.5) + profile(3.0 + s, 3.0, 0.5) - 1.0).abs() < 1e-15);
        }
    }

    /// The box wraps in x, is clipped at the walls in y, and visits each node once.
    #[test]
    fn box_wraps_in_x_and_is_clipped_by_walls() {
        let (nx, ny) = (12, 10);
        let reach = 3.5;
        let mut b = BeadBox::new(reach);
        b.place([0.25, 0.5], 2.0, 0.5, reach, nx, ny, false);
        let mut seen = vec![0; nx * ny];
        b.for_each(|x, y, r, _| {
            let k = y * nx + x;
            let (x, y) = (x as f64, y as f64);
            assert!(r[0].abs() <= reach && r[1].abs() <= reach);
            assert_eq!((x - 0.25 - r[0]).rem_euclid(nx as f64), 0.0);
            assert_eq!(y - 0.5, r[1]);
            seen[k] += 1;
        });
        assert!(seen.iter().all(|&s| s <= 1));
        // Columns -3..=3 wrapped, rows 0..=4 (rows -3..=-1 are beyond the bottom wall).
        assert_eq!(seen.iter().sum::<usize>(), 7 * 5);
        assert_eq!(seen[11], 1);
        let clipped = b.volume();
        b.place([0.25, 5.5], 2.0, 0.5, reach, nx, ny, false);
        assert!(b.volume() > clipped);
    }
}
