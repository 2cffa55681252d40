//! The Smoothed Profile Method coupling (L2020 sections 2.3, 2.5, 2.6): the fibre volume
//! fraction phi (eqs. 25–26), the momentum exchange per bead (eqs. 35–36) and the penalty
//! force (eqs. 37–38), with the walls as a solid of prescribed velocity.
//!
//! Overlaps. Where the profiles of several beads (and the walls) sum above one, every
//! contribution is divided by the sum, phi_i -> phi_i / max(1, phi): the solid fraction never
//! exceeds one and the rigid velocity there is the phi-weighted mean of the overlapping ones.
//! The same normalised phi_i enters eqs. 35–36 and eq. 38, so that with unchanged bead
//! velocities the penalty removes from the fluid exactly the momentum the beads receive.
//!
//! Bead kinematics: states carry X (positions at n+1), V and Omega (at n in the momentum
//! exchange, n+1 in the penalty). In 2D only x, y of X and V and the z component of Omega
//! are used; the angular impulse is along z.
use crate::grid::Grid;
use crate::parallel::min_len;
use crate::smoothed_profile::BeadProfile;
use crate::walls::Walls;
use cosim::{BeadImpulse, BeadState};
use rayon::prelude::*;

/// Profiles of all beads and walls, and the total solid fraction phi.
pub struct Spm {
    grid: Grid,
    rho: f64,
    xi: f64,
    cutoff: f64,
    beads: Vec<BeadProfile>,
    walls: Option<Walls>,
    /// Total solid fraction, eq. 26 plus the walls (before normalisation).
    phi: Vec<f64>,
    /// Positions the bead profiles were placed at (`None`: not placed).
    placed_at: Option<Vec<[f64; 3]>>,
    /// [`Spm::bead_volume`] at the placed positions: summed once per placement, since the
    /// momentum exchange reports it every step and it is on the path to the fibre node.
    bead_volume: f64,
    /// Grid rows where a wall or a placed bead's cut-off box lies: the rows the momentum
    /// exchange and the penalty read u* on.
    solid_rows: Vec<bool>,
}

/// Rigid-body velocity V + Omega x r of a bead at offset r (2D: Omega_z only).
#[inline]
fn rigid_velocity(s: &BeadState, r: [f64; 3], dims: usize) -> [f64; 3] {
    let v = s.velocity;
    let w = s.angular_velocity;
    if dims == 2 {
        [v[0] - w[2] * r[1], v[1] + w[2] * r[0], 0.0]
    } else {
        [
            v[0] + w[1] * r[2] - w[2] * r[1],
            v[1] + w[2] * r[0] - w[0] * r[2],
            v[2] + w[0] * r[1] - w[1] * r[0],
        ]
    }
}

impl Spm {
    /// Profiles for beads of the given radii (one per bead, fibres in order) and the walls.
    pub fn new(
        grid: Grid,
        rho: f64,
        xi: f64,
        cutoff: f64,
        radii: &[f64],
        walls: Option<Walls>,
    ) -> Self {
        let beads = radii
            .iter()
            .map(|&r| BeadProfile::new(r, cutoff, grid.dims))
            .collect();
        let mut s = Self {
            grid,
            rho,
            xi,
            cutoff,
            beads,
            walls,
            phi: vec![0.0; grid.cells()],
            placed_at: None,
            bead_volume: 0.0,
            solid_rows: vec![false; grid.rows()],
        };
        s.reset_phi();
        s.mark_solid_rows();
        s
    }

    pub fn walls(&self) -> Option<&Walls> {
        self.walls.as_ref()
    }

    pub fn bead_count(&self) -> usize {
        self.beads.len()
    }

    /// The beads' profiles (eq. 25) as last placed, in bead order.
    pub fn profiles(&self) -> &[BeadProfile] {
        &self.beads
    }

    /// Grid rows (`z * ny + y`) holding any solid: the walls' and the placed beads' cut-off
    /// boxes (a superset of the rows where phi > 0). Off these rows [`Spm::impulses`] and
    /// [`Spm::penalty_row`] do not read the velocity.
    pub fn solid_rows(&self) -> &[bool] {
        &self.solid_rows
    }

    fn mark_solid_rows(&mut self) {
        let g = self.grid;
        for (r, s) in self.solid_rows.iter_mut().enumerate() {
            *s = self.walls.as_ref().is_some_and(|w| w.phi(r % g.ny) > 0.0);
        }
        if self.placed_at.is_some() {
            for b in &self.beads {
                for r in b.rows(g) {
                    self.solid_rows[r] = true;
                }
            }
        }
    }

    /// Total solid fraction (beads and walls, before normalisation) per node.
    pub fn phi(&self) -> &[f64] {
        &self.phi
    }

    /// Whether a penalty has anything to do (beads or walls).
    pub fn has_solids(&self) -> bool {
        !self.beads.is_empty() || self.walls.is_some()
    }

    /// phi := the walls' profile (or 0).
    fn reset_phi(&mut self) {
        let g = self.grid;
        let nx = g.nx;
        let walls = &self.walls;
        self.phi
            .par_chunks_mut(nx)
            .with_min_len(min_len(g.rows(), nx))
            .enumerate()
            .for_each(|(r, row)| {
                let p = walls.as_ref().map_or(0.0, |w| w.phi(r % g.ny));
                row.fill(p);
            });
    }

    /// Forget the placed profiles (e.g. after a restore): the next [`Spm::place`] rebuilds.
    pub fn invalidate(&mut self) {
        self.placed_at = None;
    }

    /// Build phi^{n+1} from the bead positions (eqs. 25–26), unless the profiles are
    /// already placed at exactly these positions. Refuses non-finite positions.
    pub fn place(&mut self, states: &[BeadState]) -> Result<(), String> {
        let d = self.grid.dims;
        if let Some(p) = &self.placed_at {
            if p.len() == states.len()
                && p.iter().zip(states).all(|(a, s)| {
                    a[..d]
                        .iter()
                        .zip(&s.position[..d])
                        .all(|(x, y)| x.to_bits() == y.to_bits())
                })
            {
                return Ok(());
            }
        }
        if let Some((i, s)) = states
            .iter()
            .enumerate()
            .find(|(_, s)| s.position[..d].iter().any(|x| !x.is_finite()))
        {
            return Err(format!(
                "fluid-node: bead {i} has a non-finite position {:?}",
                s.position
            ));
        }
        let (g, xi, cutoff) = (self.grid, self.xi, self.cutoff);
        self.beads
            .par_iter_mut()
            .zip(states.par_iter())
            .for_each(|(b, s)| b.place(g, s.position, xi, cutoff));
        self.reset_phi();
        // Eq. 26, in bead order (overlapping boxes: sequential).
        for b in &self.beads {
            let phi = &mut self.phi;
            b.for_each(g, |i, _, p| phi[i] += p);
        }
        self.bead_volume = {
            let mut v = 0.0;
            for b in &self.beads {
                b.for_each(g, |i, _, p| v += p / self.phi[i].max(1.0));
            }
            v
        };
        let mut at = self.placed_at.take().unwrap_or_default();
        at.clear();
        at.extend(states.iter().map(|s| s.position));
        self.placed_at = Some(at);
        self.mark_solid_rows();
        Ok(())
    }

    /// Eqs. 35–36: J_i = rho ∫ phi_i (u* - u_i*) dV and L_i = rho ∫ phi_i r × (u* - u_i*) dV
    /// with u_i* = V_i + Omega_i × r, r = x - X_i (minimum image), for every bead, from the
    /// real intermediate velocity `u` (components). Beads run in parallel; each sum runs over
    /// its box in a fixed order.
    pub fn impulses(&self, u: &[Vec<f64>], states: &[BeadState], out: &mut [BeadImpulse]) {
        let (g, rho, d) = (self.grid, self.rho, self.grid.dims);
        let phi = &self.phi;
        self.beads
            .par_iter()
            .zip(states.par_iter())
            .zip(out.par_iter_mut())
            .for_each(|((b, s), o)| {
                let mut j = [0.0; 3];
                let mut l = [0.0; 3];
                b.for_each(g, |i, r, p| {
                    let w = p / phi[i].max(1.0);
                    let ub = rigid_velocity(s, r, d);
                    let mut du = [0.0; 3];
                    for c in 0..d {
                        du[c] = w * (u[c][i] - ub[c]);
                        j[c] += du[c];
                    }
                    if d == 2 {
                        l[2] += r[0] * du[1] - r[1] * du[0];
                    } else {
                        l[0] += r[1] * du[2] - r[2] * du[1];
                        l[1] += r[2] * du[0] - r[0] * du[2];
                        l[2] += r[0] * du[1] - r[1] * du[0];
                    }
                });
                *o = BeadImpulse {
                    impulse: j.map(|v| rho * v),
                    angular_impulse: l.map(|v| rho * v),
                };
            });
    }

    /// Row `r` of component `c` of the penalty of eq. 38, phi (u_p - u*) = Σ_i phi_i (u_i -
    /// u*) plus the walls' phi_w (u_w - u*), each phi normalised by max(1, phi), into `out`
    /// (every element written). `u_c` is row `r` of component c of u*; `states` carry the
    /// velocities at n+1. The walls' share comes first, then the beads' in bead order.
    pub fn penalty_row(
        &self,
        (c, r): (usize, usize),
        u_c: &[f64],
        states: &[BeadState],
        out: &mut [f64],
    ) {
        let g = self.grid;
        let nx = g.nx;
        let phi = &self.phi[r * nx..(r + 1) * nx];
        let pw = self.walls.as_ref().map_or(0.0, |w| w.phi(r % g.ny));
        match &self.walls {
            Some(w) if pw > 0.0 => {
                let uw = if c == 0 { w.speed(r % g.ny) } else { 0.0 };
                for x in 0..nx {
                    out[x] = pw / phi[x].max(1.0) * (uw - u_c[x]);
                }
            }
            _ => out.fill(0.0),
        }
        for (b, s) in self.beads.iter().zip(states) {
            b.for_each_in_row(g, r, |x, rr, p| {
                let w = p / phi[x].max(1.0);
                out[x] += w * (rigid_velocity(s, rr, g.dims)[c] - u_c[x]);
            });
        }
    }

    /// Σ_i ∫ phi_i / max(1, phi) dV: the beads' share of the solid volume.
    /// (0 before the first placement.)
    pub fn bead_volume(&self) -> f64 {
        self.bead_volume
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::WallsConfig;

    #[test]
    fn overlapping_profiles_are_normalised() {
        let g = Grid::new(2, [32, 32, 1]);
        let walls = Walls::new(
            32,
            &WallsConfig {
                velocity: [0.0, 0.0],
                thickness: 4.0,
            },
            1.0,
            3.0,
        );
        let mut spm = Spm::new(g, 1.0, 1.0, 3.0, &[3.0, 3.0, 3.0], Some(walls));
        // Two beads overlapping each other, one overlapping the bottom wall.
        let states = [
            BeadState::at_rest([10.0, 16.0, 0.0]),
            BeadState::at_rest([13.5, 16.0, 0.0]),
            BeadState::at_rest([20.0, 5.0, 0.0]),
        ];
        spm.place(&states).unwrap();
        let max = spm.phi().iter().fold(0.0f64, |m, &p| m.max(p));
        assert!(max > 1.5, "{max}");
        // Every node with a solid lies on a row flagged as solid.
        for (i, &p) in spm.phi().iter().enumerate() {
            assert!(p == 0.0 || spm.solid_rows()[i / g.nx], "node {i}: phi {p}");
        }
        assert!(spm.solid_rows().iter().any(|&s| !s));
        // Normalised weights: the solid fraction Σ phi_k / max(1, phi) stays in [0, 1].
        let mut sum = vec![0.0; g.cells()];
        for y in 0..32 {
            let pw = spm.walls().unwrap().phi(y);
            for x in 0..32 {
                let i = g.index(x, y, 0);
                sum[i] += pw / spm.phi()[i].max(1.0);
            }
        }
        for b in &spm.beads {
            b.for_each(g, |i, _, p| sum[i] += p / spm.phi()[i].max(1.0));
        }
        for (i, s) in sum.iter().enumerate() {
            assert!((0.0..=1.0 + 1e-15).contains(s), "{i}: {s}");
            assert!((s - spm.phi()[i].min(1.0)).abs() < 1e-15);
        }
        // Penalty with the whole solid at rest drives u to 0 where phi >= 1.
        let u = vec![1.0; g.cells()];
        let mut f = vec![0.0; g.cells()];
        for (r, (fr, ur)) in f.chunks_mut(g.nx).zip(u.chunks(g.nx)).enumerate() {
            spm.penalty_row((0, r), ur, &states, fr);
        }
        for i in 0..g.cells() {
            let after = u[i] + f[i];
            assert!((after - (1.0 - spm.phi()[i].min(1.0))).abs() < 1e-14);
        }
    }
}
