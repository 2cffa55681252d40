//! The binary fluid of an SPM run: the ternary Cahn–Hilliard phase field of L2020
//! (sections 2.4–2.6, eqs. 27–34) coupled into the fractional step.
//!
//! Where ψ lives in the step n -> n+1 (L2020 section 2.6):
//!
//! 1. `fluid-phase-field` ([`BinaryFluid::phase_field_step`]): φ and ψ* from the bead
//!    profiles at Xⁿ (and the walls), then one semi-implicit step of eq. 32 advected by uⁿ:
//!    ψⁿ -> ψⁿ⁺¹. The mean of ψ is conserved to round-off (the k = 0 mode is untouched).
//! 2. `fluid-momentum-exchange` ([`BinaryFluid::load_capillary_force`]): with φⁿ⁺¹ (the beads at
//!    Xⁿ⁺¹) the capillary force density `-ψⁿ⁺¹ ∇μ_ψ - φⁿ⁺¹ ∇μ_φ` (eqs. 33–34) is loaded into
//!    the flow solver, which adds it to uⁿ -> u* before the projection; the momentum
//!    exchange (eqs. 35–36) then hands the part inside each bead to the fibre with the
//!    hydrodynamic impulse, exactly as L2020 writes it.
//!
//! φ given to the phase field is the SPM solid fraction clipped to 1 (the normalisation of
//! overlapping profiles, [`crate::spm`]); ψ* is the φ-weighted mean of the overlapping
//! solids' ψ* (eq. 31 of `fibre.N.affinity` per bead, of `fluid.binary.wall_affinity` for
//! the walls), set once when every solid has the same affinity. Everything is allocated in
//! [`BinaryFluid::new`]; the two calls above allocate nothing.
pub mod derived;
pub mod droplet;
pub mod scene;

use crate::cahn_hilliard::{
    self, check_time_step, droplet, half_droplet, psi_star, stratified, CahnHilliard, Fluid,
};
use crate::grid::Grid;
use crate::spectral_ns::SpectralNs;
use crate::spm::Spm;
use crate::stability::TimeStepLimit;
use cosim::scene_keys::Num;
use cosim::Detail;
use rustfft::num_complex::Complex64;
pub use scene::{BinaryConfig, InitialPsi};

/// Diagnostics after `fluid-phase-field`, in their fixed order (`free_energy` only in a full
/// report, [`cosim::Detail`]); with a flat initial interface [`INTERFACE_DIAGNOSTICS`] follow,
/// and with beads besides [`CONTACT_ANGLE_DIAGNOSTICS`]; with an initial droplet, in a full
/// report, [`droplet::DROPLET_DIAGNOSTICS`].
pub const PHASE_FIELD_DIAGNOSTICS: [&str; 3] = ["mean_psi", "max_abs_psi", "free_energy"];
/// Position of the flat interface (along its normal, grid units) away from bead 0.
pub const INTERFACE_DIAGNOSTICS: [&str; 1] = ["interface_position"];
/// Bead 0's signed height above the interface (towards fluid A, grid units) and the
/// geometric contact angle through fluid A, `acos(h / r_b)` in degrees (L2020 section 3.3).
pub const CONTACT_ANGLE_DIAGNOSTICS: [&str; 2] = ["bead_height", "contact_angle_deg"];

/// Galusinski & Vigneaux (J. Comput. Phys. 227, 2008, 6140) constants of the capillary
/// time-step limit `Δt <= ½ (C2 τ_μ + sqrt((C2 τ_μ)² + 4 C1 τ_ρ²))`.
pub const GV_C1: f64 = 0.01;
pub const GV_C2: f64 = 10.0;

/// The capillary time-step limit of an explicit surface-tension force (Galusinski &
/// Vigneaux 2008; with viscosity → 0 it is Brackbill's capillary-wave limit): `τ_μ = η Δx / σ`,
/// `τ_ρ = sqrt(ρ Δx³ / σ)`, Δx = 1.
pub fn capillary_limit(rho: f64, eta: f64, sigma: f64) -> TimeStepLimit {
    let tau_mu = eta / sigma;
    let tau_rho2 = rho / sigma;
    let a = GV_C2 * tau_mu;
    TimeStepLimit {
        name: "capillary",
        dt_max: 0.5 * (a + (a * a + 4.0 * GV_C1 * tau_rho2).sqrt()),
        detail: format!(
            "dt <= (C2 tau_mu + sqrt((C2 tau_mu)^2 + 4 C1 tau_rho^2)) / 2, Galusinski & \
             Vigneaux 2008, C1 = {GV_C1}, C2 = {GV_C2}, tau_mu = eta dx / sigma = {}, \
             tau_rho = sqrt(rho dx^3 / sigma) = {}, sigma = {}",
            cosim::scene_keys::Sig(tau_mu),
            cosim::scene_keys::Sig(tau_rho2.sqrt()),
            cosim::scene_keys::Sig(sigma)
        ),
    }
}

/// The phase field of an SPM run, with its scratch.
pub struct BinaryFluid {
    ch: CahnHilliard,
    cfg: BinaryConfig,
    /// ψ* of each bead (eq. 31 of its fibre's ψ0).
    bead_psi_star: Vec<f64>,
    wall_psi_star: f64,
    /// Every solid has the same ψ*: the field was set once.
    uniform: bool,
    /// Capillary force density per component (mass / (length² time²)).
    force: Vec<Vec<f64>>,
    /// Scratch of the droplet diagnostics, allocated at the first full report.
    droplet: Option<droplet::Scratch>,
}

/// The initial ψ field of `cfg` on `grid` (L2020 section 3: a flat interface, a droplet or a
/// half-droplet, tanh profiles of width √2 ξ).
pub fn initial_psi(cfg: &BinaryConfig, grid: Grid) -> Result<Vec<f64>, String> {
    let err = |e: cahn_hilliard::CahnHilliardError| format!("fluid.binary: {e}");
    let mut psi = vec![0.0; grid.cells()];
    let xi = cfg.ch.xi;
    match &cfg.initial {
        InitialPsi::Flat {
            axis,
            positive,
            position,
            width,
        } => {
            // Fluid A fills [position, position + width) (positive normal) or
            // [position - width, position) (negative normal), B the rest.
            let (from, to) = if *positive {
                (*position, position + width)
            } else {
                (position - width, *position)
            };
            stratified(grid, xi, *axis, from, to, Fluid::A, &mut psi).map_err(err)?;
        }
        InitialPsi::Droplet {
            centre,
            radius,
            inside,
        } => droplet(grid, xi, *centre, *radius, *inside, &mut psi).map_err(err)?,
        InitialPsi::HalfDroplet {
            centre,
            normal,
            radius,
            inside,
        } => half_droplet(grid, xi, *centre, *normal, *radius, *inside, &mut psi).map_err(err)?,
    }
    Ok(psi)
}

impl BinaryFluid {
    /// The phase field on `grid` with the initial ψ of `cfg`, for beads of affinities
    /// `bead_psi0` (one ψ0 per bead, fibres in order) and walls if `has_walls`.
    pub fn new(
        grid: Grid,
        cfg: &BinaryConfig,
        bead_psi0: &[f64],
        has_walls: bool,
    ) -> Result<Self, String> {
        let err = |e: cahn_hilliard::CahnHilliardError| format!("fluid.binary: {e}");
        let mut ch = CahnHilliard::new(grid, cfg.ch.clone()).map_err(err)?;
        let psi = initial_psi(cfg, grid)?;
        ch.set_psi(&psi).map_err(err)?;
        let bead_psi_star: Vec<f64> = bead_psi0.iter().map(|&p| psi_star(p)).collect();
        let wall_psi_star = psi_star(cfg.wall_affinity);
        let first = bead_psi_star.first().copied().unwrap_or(wall_psi_star);
        let uniform =
            bead_psi_star.iter().all(|&p| p == first) && (!has_walls || wall_psi_star == first);
        if uniform {
            ch.psi_star_mut().fill(first);
        }
        Ok(Self {
            force: vec![vec![0.0; grid.cells()]; grid.dims],
            ch,
            cfg: cfg.clone(),
            bead_psi_star,
            wall_psi_star,
            uniform,
            droplet: None,
        })
    }

    pub fn config(&self) -> &BinaryConfig {
        &self.cfg
    }

    /// The phase-field solver (read access: ψ, φ, ψ*).
    pub fn solver(&self) -> &CahnHilliard {
        &self.ch
    }

    /// The finite time-step limits of the phase field and of the explicit capillary force,
    /// refusing `time.dt` above any, with the limit named: the Cahn–Hilliard limits of
    /// [`cahn_hilliard::limits`] for φ ≤ 1 and the largest speed known before the run
    /// (`wall_speed`; as for the flow, faster capillary flows are caught during the run by
    /// the advective CFL watch and the divergence check of ψ), and [`capillary_limit`].
    pub fn check_time_step(
        &self,
        wall_speed: f64,
        rho: f64,
        eta: f64,
    ) -> Result<Vec<TimeStepLimit>, String> {
        let sigma = self.cfg.sigma();
        let mut all = check_time_step(self.ch.grid(), &self.cfg.ch, wall_speed, 1.0)
            .map_err(|e| format!("fluid.binary: {e}; lower time.dt"))?;
        let cap = capillary_limit(rho, eta, sigma);
        if self.cfg.ch.dt > cap.dt_max {
            return Err(format!(
                "time step too large for the binary fluid (capillary limit): time.dt = {} \
                 exceeds {} ({}); lower time.dt or fluid.binary.e0 / sigma, or raise \
                 fluid.viscosity",
                Num(self.cfg.ch.dt),
                cosim::scene_keys::Sig(cap.dt_max),
                cap.detail
            ));
        }
        all.push(cap);
        Ok(all)
    }

    /// φ := the SPM solid fraction clipped to 1 and, for mixed affinities, ψ* := the
    /// φ-weighted mean of the solids' ψ* (see the module docs).
    fn load_solids(&mut self, spm: &Spm) {
        let g = self.ch.grid();
        let phi = spm.phi();
        for (d, &p) in self.ch.phi_mut().iter_mut().zip(phi) {
            *d = p.min(1.0);
        }
        if self.uniform {
            return;
        }
        let ps = self.ch.psi_star_mut();
        match spm.walls() {
            Some(w) => {
                for (r, row) in ps.chunks_mut(g.nx).enumerate() {
                    row.fill(w.phi(r % g.ny) * self.wall_psi_star);
                }
            }
            None => ps.fill(0.0),
        }
        for (b, &s) in spm.profiles().iter().zip(&self.bead_psi_star) {
            b.for_each(g, |i, _, p| ps[i] += p * s);
        }
        for (v, &p) in ps.iter_mut().zip(phi) {
            *v = if p > 0.0 { *v / p } else { 0.0 };
        }
    }

    /// Phase `fluid-phase-field`: ψⁿ -> ψⁿ⁺¹ by eq. 32 advected by `velocity` (uⁿ), with the
    /// solids of `spm` (placed at Xⁿ).
    pub fn phase_field_step(&mut self, spm: &Spm, velocity: &[Vec<f64>]) -> Result<(), String> {
        self.load_solids(spm);
        self.ch
            .step_advected(velocity)
            .map_err(|e| format!("fluid-node: {e}"))
    }

    /// Phase `fluid-momentum-exchange`, before uⁿ -> u*: the capillary force density of
    /// eqs. 33–34 with ψⁿ⁺¹ and the solids of `spm` (placed at Xⁿ⁺¹), loaded into `ns`.
    pub fn load_capillary_force(
        &mut self,
        spm: &Spm,
        ns: &mut SpectralNs,
        rho: f64,
    ) -> Result<(), String> {
        self.load_solids(spm);
        self.ch
            .capillary_force(&mut self.force)
            .map_err(|e| format!("fluid-node: {e}"))?;
        ns.set_force_density(&self.force, rho)
    }

    /// The capillary force density last loaded (one field per component).
    pub fn force(&self) -> &[Vec<f64>] {
        &self.force
    }

    /// Diagnostics after `fluid-phase-field` (names and values, see
    /// [`PHASE_FIELD_DIAGNOSTICS`]); `spm` gives bead 0 for the contact angle. The free
    /// energy and the droplet's diagnostics cost whole-field passes of their own (the droplet's
    /// about two phase-field steps): only a full report has them.
    pub fn report(&mut self, spm: &Spm, detail: Detail) -> Vec<(String, f64)> {
        let full = detail == Detail::Full;
        let mean = self.ch.mean_psi();
        let max_abs = self.ch.max_abs_psi();
        let mut out: Vec<(String, f64)> = PHASE_FIELD_DIAGNOSTICS[..2]
            .iter()
            .zip([mean, max_abs])
            .map(|(n, v)| (n.to_string(), v))
            .collect();
        // The free energy costs a transform of the gradient.
        if full {
            let energy = self.ch.free_energy().total;
            out.push((PHASE_FIELD_DIAGNOSTICS[2].to_string(), energy));
        }
        if let InitialPsi::Flat {
            axis,
            positive,
            position,
            ..
        } = self.cfg.initial
        {
            let bead = spm.profiles().first().map(|b| (b.centre(), b.radius));
            let g = self.ch.grid();
            let n = g.sizes();
            // The column half a box away from bead 0 across the normal: the flat interface,
            // away from the meniscus.
            let mut at = [0usize; 3];
            for (c, a) in at.iter_mut().enumerate().take(g.dims) {
                if c != axis {
                    let x = bead.map_or(0.0, |(centre, _)| centre[c]) + 0.5 * n[c] as f64;
                    *a = (x.round() as usize) % n[c];
                }
            }
            let level = interface_level(&self.ch, axis, at, position, positive);
            // No crossing on that line (the interface broke up): nothing to report, rather
            // than a NaN the coordinator would take for an unstable run.
            if level.is_finite() {
                out.push((INTERFACE_DIAGNOSTICS[0].into(), level));
            }
            if let (Some((centre, r)), true) = (bead, level.is_finite()) {
                let len = n[axis] as f64;
                let mut h = centre[axis] - level;
                h -= len * (h / len).round();
                if !positive {
                    h = -h;
                }
                let angle = (h / r).clamp(-1.0, 1.0).acos().to_degrees();
                out.push((CONTACT_ANGLE_DIAGNOSTICS[0].into(), h));
                out.push((CONTACT_ANGLE_DIAGNOSTICS[1].into(), angle));
            }
        }
        if let (&InitialPsi::Droplet { inside, .. }, true) = (&self.cfg.initial, full) {
            let g = self.ch.grid();
            let scratch = self.droplet.get_or_insert_with(|| droplet::Scratch::new(g));
            if let Some(d) = droplet::measure(&mut self.ch, inside, scratch) {
                let values = [d.radius, d.pressure_jump, d.pressure_jump_mu];
                for (n, v) in droplet::DROPLET_DIAGNOSTICS.iter().zip(values) {
                    out.push((n.to_string(), v));
                }
            }
        }
        out
    }

    /// Spectral ψ (for saving the state).
    pub fn spectrum(&self) -> &[Complex64] {
        self.ch.psi_spectrum()
    }

    /// Restore ψ from a saved spectrum.
    pub fn set_spectrum(&mut self, s: &[Complex64]) -> Result<(), String> {
        self.ch
            .set_psi_spectrum(s)
            .map_err(|e| format!("fluid-node: {e}"))
    }
}

/// The ψ = 0 crossing (linear interpolation) along `axis` on the grid line through `at`
/// nearest to `guess` (periodic), where ψ rises towards the + side (`rising`) or falls.
fn interface_level(
    ch: &CahnHilliard,
    axis: usize,
    at: [usize; 3],
    guess: f64,
    rising: bool,
) -> f64 {
    let g = ch.grid();
    let n = g.sizes()[axis];
    let psi = ch.psi();
    let value = |j: usize| {
        let mut p = at;
        p[axis] = j % n;
        psi[g.index(p[0], p[1], p[2])]
    };
    let len = n as f64;
    let mut best = f64::NAN;
    let mut best_d = f64::INFINITY;
    for j in 0..n {
        let (a, b) = (value(j), value(j + 1));
        let crosses = if rising {
            a < 0.0 && b >= 0.0
        } else {
            a >= 0.0 && b < 0.0
        };
        if crosses {
            let x = j as f64 + a / (a - b);
            let mut d = x - guess;
            d -= len * (d / len).round();
            if d.abs() < best_d {
                best_d = d.abs();
                best = guess + d;
            }
        }
    }
    best
}
