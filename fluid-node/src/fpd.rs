//! Fluid particle dynamics (FPD) coupling of S2023 (Su et al. 2023, section II A and C) on
//! the MRT D2Q9 solver of [`crate::mrt_d2q9`]: a bead is a disc of a fluid much more viscous
//! than its surroundings, tied to the flow by three maps.
//!
//! - Profile (S2023 eq. 2, [`profile`]): phi_i = 1/2 {tanh[(a - |r - R_i|)/xi] + 1}, with
//!   xi = r_xi d, evaluated only in the bead's cut-off box.
//! - Viscosity (S2023 eq. 1): eta = eta_f + (eta_s - eta_f) phi, eta_s = r_eta eta_f. The
//!   solver takes a kinematic viscosity, so the field written is
//!   nu = nu_f + (nu_s - nu_f) phi with nu = eta / rho0 (rho0 the lattice's reference
//!   density; density variations are O(Ma^2)).
//! - Force density (S2023 eq. 4): f(r) = sum_i F_i phi_i(r) / sum_r phi_i, the integral
//!   taken as the grid sum of the same truncated profile (cell volume 1), so that the force
//!   the fluid receives from bead i is F_i to round-off. A uniform background force density
//!   ([`FpdConfig::background_force`]) is added on every node: in a periodic box it balances
//!   the bead forces, as a mean pressure gradient does in a periodic array.
//! - Bead velocity (S2023 eq. 5): V_i = sum_r phi_i v / sum_r phi_i, v the solver's velocity
//!   (rho u = sum f c + F/2), read only at the nodes of the bead's box.
//!
//! Overlap. Where the profiles of several beads overlap (neighbours in a fibre touch, so
//! near the contact sum_i phi_i exceeds 1), the total phi entering eq. 1 is the sum clamped
//! to 1: it keeps eta <= eta_s, so the slowest relaxation rate of the lattice is the one
//! checked when planning, and a contact is no more rigid than a bead's interior. Eqs. 4 and
//! 5 keep each bead's own unclamped phi_i: the force of each bead stays exact and its
//! velocity stays the mean over its own profile.
//!
//! Order and reproducibility. Every sum runs serially over a bead's box in a fixed order
//! (rows, then columns), and sums over beads run in index order. The parallel loops are the
//! node-wise viscosity update of the solver and, where the boxes are large enough
//! (`PARALLEL_BOX_NODES`), the profiles and velocities of the beads, a bead to a task,
//! each computed as it would be serially. Results are therefore bitwise the same for any
//! number of threads.
//!
//! Plan once, call every step: [`FpdCoupling::new`] validates an [`FpdConfig`] against the
//! lattice and allocates every buffer (the total-phi field, each bead's box, the list of
//! nodes the force spread writes); [`FpdCoupling::apply`] (S2023's step (1)) and
//! [`FpdCoupling::bead_velocities`] (the first half of step (3)) allocate nothing.
//!
//! Lattice geometry and units are those of [`crate::mrt_d2q9`]: lattice units (dx = dt = 1),
//! node (x, y) at integer coordinates, periodic in x; in y periodic or closed by walls at
//! y = -1/2 and ny - 1/2. Bead positions are off-lattice; x wraps, and y wraps when the
//! lattice is periodic in y, otherwise it must lie between the wall planes.
pub mod profile;

use crate::mrt_d2q9::{check_viscosity, MrtD2q9};
use profile::{max_extent, BeadBox};
use rayon::prelude::*;

/// Box nodes of all beads together (at their largest) from which the beads' profiles and
/// velocities are computed in parallel, a bead to a task: below, a bead's box is a few
/// microseconds of work, about what handing it to another thread costs (S2023's d = 4:
/// 1000 nodes for ten beads; d = 8: 3600).
const PARALLEL_BOX_NODES: usize = 2048;

/// Parameters of the coupling, all in lattice units. [`FpdConfig::new`] gives the defaults
/// for the fields not named.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FpdConfig {
    /// Bead radius a = d/2 (lattice units, at least 1/2).
    pub radius: f64,
    /// Kinematic viscosity of the fluid nu_f = eta_f / rho0 (lattice units).
    pub fluid_viscosity: f64,
    /// r_eta = eta_s / eta_f, at least 1. Default 100 (S2023's choice, section III).
    pub viscosity_ratio: f64,
    /// r_xi = xi / d, positive. Default 0.125 (S2023's choice, section III).
    pub interface_ratio: f64,
    /// Cut-off of a profile in interface thicknesses: phi_i = 0 beyond a + cutoff xi.
    /// Default 5, where eq. 2 has fallen to 4.5e-5.
    pub cutoff: f64,
    /// Uniform force density added on every node to the spread bead forces (lattice units).
    /// Default zero.
    pub background_force: [f64; 2],
}

impl FpdConfig {
    /// Beads of radius `radius` in a fluid of kinematic viscosity `fluid_viscosity`, with
    /// S2023's r_eta = 100 and r_xi = 0.125, a cut-off at 5 xi and no background force.
    pub fn new(radius: f64, fluid_viscosity: f64) -> Self {
        Self {
            radius,
            fluid_viscosity,
            viscosity_ratio: 100.0,
            interface_ratio: cosim::profile::DEFAULT_FPD_INTERFACE_RATIO,
            cutoff: 5.0,
            background_force: [0.0; 2],
        }
    }

    /// Interface thickness xi = r_xi d = 2 r_xi a.
    pub fn xi(&self) -> f64 {
        2.0 * self.interface_ratio * self.radius
    }

    /// Half-width of a bead's box, a + cutoff xi.
    pub fn reach(&self) -> f64 {
        self.radius + self.cutoff * self.xi()
    }

    /// Kinematic viscosity inside a bead, nu_s = r_eta nu_f.
    pub fn solid_viscosity(&self) -> f64 {
        self.viscosity_ratio * self.fluid_viscosity
    }
}

/// What the coupling refuses.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FpdError {
    #[error("{name} = {} is invalid: {why}", cosim::scene_keys::Num(*.value))]
    Parameter {
        name: &'static str,
        value: f64,
        why: String,
    },
    #[error(
        "the {nx} x {ny} lattice is too small for the bead box: a + cutoff xi = {} \
         needs {extent} nodes along x{}",
        cosim::scene_keys::Num(*.reach),
        if *.periodic_y { " and y (periodic)" } else { "" }
    )]
    LatticeTooSmall {
        nx: usize,
        ny: usize,
        reach: f64,
        extent: usize,
        periodic_y: bool,
    },
    #[error(
        "the lattice is {nx} x {ny} ({}), the coupling was planned for {planned_nx} x \
         {planned_ny} ({})",
        if *.periodic_y { "periodic in y" } else { "walls in y" },
        if *.planned_periodic_y { "periodic in y" } else { "walls in y" }
    )]
    LatticeMismatch {
        nx: usize,
        ny: usize,
        periodic_y: bool,
        planned_nx: usize,
        planned_ny: usize,
        planned_periodic_y: bool,
    },
    #[error("{what}: {got} values for {expected} beads")]
    Count {
        what: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("bead {bead}: {what} ({}, {}) is not finite", .value[0], .value[1])]
    NotFinite {
        bead: usize,
        what: &'static str,
        value: [f64; 2],
    },
    #[error(
        "bead {bead} at y = {y} is outside the lattice: between walls its centre must lie in \
         [-1/2, {ny} - 1/2]"
    )]
    BeadOutside { bead: usize, y: f64, ny: usize },
    #[error("bead {bead} does not exist: the coupling has {beads} beads")]
    NoSuchBead { bead: usize, beads: usize },
    #[error("the bead profiles have not been placed yet")]
    NotPlaced,
    #[error("the flow solver refused the FPD fields: {0}")]
    Solver(String),
}

/// The FPD coupling of a fixed number of beads to one [`MrtD2q9`] lattice.
#[derive(Debug, Clone)]
pub struct FpdCoupling {
    cfg: FpdConfig,
    nx: usize,
    ny: usize,
    periodic_y: bool,
    beads: Vec<BeadBox>,
    placed: bool,
    /// Total phi = min(1, sum_i phi_i) per node, `[y][x]`: what eq. 1 is evaluated with.
    phi: Vec<f64>,
    /// Nodes whose force the last spread wrote (with repeats where boxes overlap).
    touched: Vec<usize>,
    /// Nodes whose phi the last [`FpdCoupling::place`] may have changed: the previous and
    /// the new boxes (with repeats), where eq. 1 has to be re-evaluated.
    changed: Vec<usize>,
    /// Whether the lattice's viscosity field already holds eq. 1 of the placed phi outside
    /// `changed` (set by the first full update).
    viscosity_current: bool,
}

fn parameter(name: &'static str, value: f64, why: impl Into<String>) -> FpdError {
    FpdError::Parameter {
        name,
        value,
        why: why.into(),
    }
}

impl FpdCoupling {
    /// Plan the coupling of `beads` beads to `lattice`: validate the configuration, allocate
    /// every buffer, and write the fluid viscosity nu_f and the background force into the
    /// whole lattice (no bead is placed yet). The lattice's size and y boundary are fixed
    /// from here on.
    pub fn new(cfg: FpdConfig, lattice: &mut MrtD2q9, beads: usize) -> Result<Self, FpdError> {
        let finite_pos = |name, v: f64, min: f64, why: &str| {
            if v.is_finite() && v >= min {
                Ok(())
            } else {
                Err(parameter(name, v, why))
            }
        };
        finite_pos(
            "radius",
            cfg.radius,
            0.5,
            "the bead radius must be at least half a lattice spacing",
        )?;
        finite_pos(
            "viscosity_ratio",
            cfg.viscosity_ratio,
            1.0,
            "r_eta = eta_s / eta_f must be at least 1 (a bead is the more viscous fluid)",
        )?;
        if !(cfg.interface_ratio.is_finite() && cfg.interface_ratio > 0.0) {
            return Err(parameter(
                "interface_ratio",
                cfg.interface_ratio,
                "r_xi = xi / d must be positive",
            ));
        }
        if !(cfg.cutoff.is_finite() && cfg.cutoff > 0.0) {
            return Err(parameter(
                "cutoff",
                cfg.cutoff,
                "the cut-off (in interface thicknesses) must be positive",
            ));
        }
        check_viscosity(cfg.fluid_viscosity)
            .map_err(|e| parameter("fluid_viscosity", cfg.fluid_viscosity, e))?;
        check_viscosity(cfg.solid_viscosity()).map_err(|e| {
            parameter(
                "viscosity_ratio",
                cfg.viscosity_ratio,
                format!("nu_s = r_eta nu_f: {e}"),
            )
        })?;
        for (k, &f) in cfg.background_force.iter().enumerate() {
            if !f.is_finite() {
                let name = ["background_force.x", "background_force.y"][k];
                return Err(parameter(name, f, "must be finite"));
            }
        }
        let (nx, ny) = (lattice.nx(), lattice.ny());
        let periodic_y = lattice.wall_velocities().is_none();
        let reach = cfg.reach();
        let extent = max_extent(reach);
        // A box wider than a periodic axis would wrap onto itself and count nodes twice.
        if extent > nx || (periodic_y && extent > ny) {
            return Err(FpdError::LatticeTooSmall {
                nx,
                ny,
                reach,
                extent,
                periodic_y,
            });
        }
        lattice
            .set_uniform_viscosity(cfg.fluid_viscosity)
            .map_err(FpdError::Solver)?;
        lattice.set_uniform_force(cfg.background_force[0], cfg.background_force[1]);
        Ok(Self {
            cfg,
            nx,
            ny,
            periodic_y,
            beads: (0..beads).map(|_| BeadBox::new(reach)).collect(),
            placed: false,
            phi: vec![0.0; nx * ny],
            touched: Vec::with_capacity(beads * extent * extent),
            changed: Vec::with_capacity(2 * beads * extent * extent),
            viscosity_current: false,
        })
    }

    pub fn config(&self) -> &FpdConfig {
        &self.cfg
    }

    /// Number of beads.
    pub fn beads(&self) -> usize {
        self.beads.len()
    }

    /// Interface thickness xi (lattice units).
    pub fn xi(&self) -> f64 {
        self.cfg.xi()
    }

    /// S2023's step (1) for given bead positions R_i and forces F_i (lattice units): place
    /// the profiles (eq. 2), write the viscosity field (eq. 1) and the force density (eq. 4)
    /// into `lattice`. Nothing changes on an error.
    pub fn apply(
        &mut self,
        lattice: &mut MrtD2q9,
        positions: &[[f64; 2]],
        forces: &[[f64; 2]],
    ) -> Result<(), FpdError> {
        self.check_lattice(lattice)?;
        self.check_forces(forces)?;
        self.place(positions)?;
        self.update_viscosity(lattice)?;
        self.spread_forces(lattice, forces)
    }

    /// Place the profiles at `positions` (eq. 2) and rebuild the total phi. Only the nodes of
    /// the previous and new boxes are written. Nothing changes on an error.
    pub fn place(&mut self, positions: &[[f64; 2]]) -> Result<(), FpdError> {
        self.check_count("positions", positions.len())?;
        for (bead, p) in positions.iter().enumerate() {
            if !(p[0].is_finite() && p[1].is_finite()) {
                return Err(FpdError::NotFinite {
                    bead,
                    what: "position",
                    value: *p,
                });
            }
            if !self.periodic_y && !(-0.5..=self.ny as f64 - 0.5).contains(&p[1]) {
                return Err(FpdError::BeadOutside {
                    bead,
                    y: p[1],
                    ny: self.ny,
                });
            }
        }
        let nx = self.nx;
        self.changed.clear();
        if self.placed {
            for b in &self.beads {
                b.for_each(|x, y, _, _| {
                    self.phi[y * nx + x] = 0.0;
                    self.changed.push(y * nx + x);
                });
            }
        }
        let (a, xi, reach) = (self.cfg.radius, self.cfg.xi(), self.cfg.reach());
        let (ny, periodic_y) = (self.ny, self.periodic_y);
        let place = |(b, p): (&mut BeadBox, &[f64; 2])| {
            let x = wrap(p[0], nx);
            let y = if periodic_y { wrap(p[1], ny) } else { p[1] };
            b.place([x, y], a, xi, reach, nx, ny, periodic_y);
        };
        if self.beads_in_parallel() {
            self.beads.par_iter_mut().zip(positions).for_each(place);
        } else {
            self.beads.iter_mut().zip(positions).for_each(place);
        }
        // Sum in bead order, then clamp (module docs: overlap).
        for b in &self.beads {
            b.for_each(|x, y, _, p| self.phi[y * nx + x] += p);
        }
        for b in &self.beads {
            b.for_each(|x, y, _, _| {
                let v = &mut self.phi[y * nx + x];
                *v = v.min(1.0);
                self.changed.push(y * nx + x);
            });
        }
        self.placed = true;
        Ok(())
    }

    /// Write eq. 1, nu = nu_f + (nu_s - nu_f) phi, into the lattice's viscosity field: the
    /// whole lattice the first time, then only the nodes of the previous and the new boxes
    /// (elsewhere phi is 0 before and after, and the field keeps the nu_f that
    /// [`FpdCoupling::new`] wrote: nothing else may write it once beads are placed).
    pub fn update_viscosity(&mut self, lattice: &mut MrtD2q9) -> Result<(), FpdError> {
        self.check_lattice(lattice)?;
        let (nu_f, nu_s) = (self.cfg.fluid_viscosity, self.cfg.solid_viscosity());
        if self.viscosity_current {
            lattice.set_viscosity_from_fraction_at(&self.changed, &self.phi, nu_f, nu_s)
        } else {
            lattice.set_viscosity_from_fraction(&self.phi, nu_f, nu_s)
        }
        .map_err(FpdError::Solver)?;
        self.viscosity_current = self.placed;
        Ok(())
    }

    /// Write the force density of eq. 4 plus the background into the lattice's force field
    /// at the nodes of the current boxes, and restore the background at the nodes the
    /// previous spread wrote. Other nodes are left as they are: a caller may force them
    /// (e.g. a sponge layer), provided it keeps away from the boxes. Nothing changes on an
    /// error.
    pub fn spread_forces(
        &mut self,
        lattice: &mut MrtD2q9,
        forces: &[[f64; 2]],
    ) -> Result<(), FpdError> {
        self.check_lattice(lattice)?;
        self.check_forces(forces)?;
        if !self.placed {
            return Err(FpdError::NotPlaced);
        }
        let nx = self.nx;
        let [bx, by] = self.cfg.background_force;
        let (fx, fy) = lattice.force_mut();
        for &k in &self.touched {
            fx[k] = bx;
            fy[k] = by;
        }
        self.touched.clear();
        // Capacity was planned for every bead's largest box: no reallocation here.
        for b in &self.beads {
            b.for_each(|x, y, _, _| {
                let k = y * nx + x;
                fx[k] = bx;
                fy[k] = by;
                self.touched.push(k);
            });
        }
        for (b, f) in self.beads.iter().zip(forces) {
            // A bead's box holds at least the nodes within 1/2 of its centre (the centre is
            // in the lattice and the reach exceeds 1/2), so the volume is positive.
            let inv = 1.0 / b.volume();
            let (gx, gy) = (f[0] * inv, f[1] * inv);
            b.for_each(|x, y, _, p| {
                let k = y * nx + x;
                fx[k] += gx * p;
                fy[k] += gy * p;
            });
        }
        Ok(())
    }

    /// S2023 eq. 5: each bead's velocity V_i, the phi_i-weighted mean of the fluid velocity
    /// over its box, into `out`.
    pub fn bead_velocities(&self, lattice: &MrtD2q9, out: &mut [[f64; 2]]) -> Result<(), FpdError> {
        self.check_lattice(lattice)?;
        self.check_count("velocity buffer", out.len())?;
        if !self.placed {
            return Err(FpdError::NotPlaced);
        }
        let velocity = |(b, v): (&BeadBox, &mut [f64; 2])| {
            let (mut sx, mut sy) = (0.0, 0.0);
            b.for_each(|x, y, _, p| {
                let (_, ux, uy) = lattice.node(x, y);
                sx += p * ux;
                sy += p * uy;
            });
            *v = [sx / b.volume(), sy / b.volume()];
        };
        if self.beads_in_parallel() {
            self.beads.par_iter().zip(out).for_each(velocity);
        } else {
            self.beads.iter().zip(out).for_each(velocity);
        }
        Ok(())
    }

    /// Rigid motion of bead `bead` seen by its profile: the velocity V of eq. 5 and the
    /// angular velocity omega = sum phi_i r x (v - V) / sum phi_i |r|^2 (the least-squares
    /// rigid rotation about the centre, weighted like eq. 5), r the offset from the centre.
    pub fn rigid_motion(
        &self,
        lattice: &MrtD2q9,
        bead: usize,
    ) -> Result<([f64; 2], f64), FpdError> {
        let b = self.bead(lattice, bead)?;
        let mut s = [0.0; 7]; // phi, phi vx, phi vy, phi rx, phi ry, phi r x v, phi r^2
        b.for_each(|x, y, r, p| {
            let (_, ux, uy) = lattice.node(x, y);
            s[0] += p;
            s[1] += p * ux;
            s[2] += p * uy;
            s[3] += p * r[0];
            s[4] += p * r[1];
            s[5] += p * (r[0] * uy - r[1] * ux);
            s[6] += p * (r[0] * r[0] + r[1] * r[1]);
        });
        let v = [s[1] / s[0], s[2] / s[0]];
        // sum phi r x (v - V) = sum phi r x v - (sum phi r) x V.
        let omega = (s[5] - (s[3] * v[1] - s[4] * v[0])) / s[6];
        Ok((v, omega))
    }

    /// Strength of the flow inside bead `bead` relative to a rigid motion (velocity V,
    /// angular velocity omega about the centre): S2023 eq. 15 generalised to a rotating
    /// bead, eps_v = sum phi_i |v - V - omega x r|^2 / sum phi_i. With omega = 0 it is eq. 15.
    pub fn internal_flow(
        &self,
        lattice: &MrtD2q9,
        bead: usize,
        velocity: [f64; 2],
        omega: f64,
    ) -> Result<f64, FpdError> {
        let b = self.bead(lattice, bead)?;
        let mut s = 0.0;
        b.for_each(|x, y, r, p| {
            let (_, ux, uy) = lattice.node(x, y);
            let dx = ux - (velocity[0] - omega * r[1]);
            let dy = uy - (velocity[1] + omega * r[0]);
            s += p * (dx * dx + dy * dy);
        });
        Ok(s / b.volume())
    }

    /// Total phi = min(1, sum_i phi_i) per node (`[y][x]`), the field of eq. 1.
    pub fn solid_fraction(&self) -> &[f64] {
        &self.phi
    }

    /// Grid sum of bead `bead`'s profile, the discrete ∫ phi_i dr of eqs. 4 and 5 (zero
    /// before placement).
    pub fn profile_volume(&self, bead: usize) -> f64 {
        self.beads.get(bead).map_or(0.0, |b| b.volume())
    }

    /// Centre of bead `bead` as placed, wrapped into the lattice along periodic axes.
    pub fn centre(&self, bead: usize) -> Option<[f64; 2]> {
        self.beads
            .get(bead)
            .filter(|_| self.placed)
            .map(|b| b.centre())
    }

    /// Call `f(x, y, [rx, ry], phi_i)` for every node of bead `bead`'s box in the fixed order
    /// the coupling sums in; (rx, ry) is the node's offset from the centre.
    pub fn for_each_node(
        &self,
        bead: usize,
        f: impl FnMut(usize, usize, [f64; 2], f64),
    ) -> Result<(), FpdError> {
        if !self.placed {
            return Err(FpdError::NotPlaced);
        }
        let b = self.beads.get(bead).ok_or(FpdError::NoSuchBead {
            bead,
            beads: self.beads.len(),
        })?;
        b.for_each(f);
        Ok(())
    }

    fn bead(&self, lattice: &MrtD2q9, bead: usize) -> Result<&BeadBox, FpdError> {
        self.check_lattice(lattice)?;
        if !self.placed {
            return Err(FpdError::NotPlaced);
        }
        self.beads.get(bead).ok_or(FpdError::NoSuchBead {
            bead,
            beads: self.beads.len(),
        })
    }

    fn check_count(&self, what: &'static str, got: usize) -> Result<(), FpdError> {
        if got != self.beads.len() {
            return Err(FpdError::Count {
                what,
                expected: self.beads.len(),
                got,
            });
        }
        Ok(())
    }

    fn check_forces(&self, forces: &[[f64; 2]]) -> Result<(), FpdError> {
        self.check_count("forces", forces.len())?;
        if let Some(bead) = forces
            .iter()
            .position(|f| !(f[0].is_finite() && f[1].is_finite()))
        {
            return Err(FpdError::NotFinite {
                bead,
                what: "force",
                value: forces[bead],
            });
        }
        Ok(())
    }

    /// Whether the beads' boxes are large enough to share out among threads.
    fn beads_in_parallel(&self) -> bool {
        self.beads.len() * max_extent(self.cfg.reach()).pow(2) >= PARALLEL_BOX_NODES
    }

    fn check_lattice(&self, lattice: &MrtD2q9) -> Result<(), FpdError> {
        let periodic_y = lattice.wall_velocities().is_none();
        if (lattice.nx(), lattice.ny(), periodic_y) != (self.nx, self.ny, self.periodic_y) {
            return Err(FpdError::LatticeMismatch {
                nx: lattice.nx(),
                ny: lattice.ny(),
                periodic_y,
                planned_nx: self.nx,
                planned_ny: self.ny,
                planned_periodic_y: self.periodic_y,
            });
        }
        Ok(())
    }
}

/// `v` modulo `n`, in [0, n).
fn wrap(v: f64, n: usize) -> f64 {
    let len = n as f64;
    let w = v.rem_euclid(len);
    // rem_euclid of a tiny negative number rounds up to len.
    if w >= len {
        0.0
    } else {
        w
    }
}
