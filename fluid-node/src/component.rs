//! The fluid node as a co-simulation component ([`cosim::Component`]): SPM phases 3 and 5 of
//! the fractional step (L2020 section 2.6).
//!
//! - `fluid-momentum-exchange` (step n): read the bead states (positions n+1, velocities n),
//!   build phi^{n+1} (eqs. 25–26), advance u^n to u* (eq. 34), integrate the impulses of
//!   eqs. 35–36 and publish them on [`Port::BeadImpulses`] with step n+1, beads in order.
//! - `fluid-penalty` (step n): read the bead states again (velocities n+1), add the projected
//!   penalty of eqs. 37–38 (beads and walls) to reach u^{n+1}, and report diagnostics.
//!
//! A scene without fibres runs the same two phases without reading bead states.
use crate::config::{parse_scene, FluidConfig, InitialVelocity};
use crate::grid::Grid;
use crate::spectral_ns::SpectralNs;
use crate::spm::Spm;
use crate::stability::{self, CFL_ABORT};
use crate::walls::Walls;
use cosim::description::{parameter as param, ModelDescription, PortDescription};
use cosim::{
    effects, BeadImpulse, BeadState, Component, ComponentError, Configured, Exchange, Phase,
    PhaseReport, Port,
};
use rustfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Diagnostics after `fluid-penalty`, in their fixed order; with walls
/// [`COUETTE_DIAGNOSTIC`] follows.
pub const DIAGNOSTICS: [&str; 7] = [
    "fluid_kinetic_energy",
    "max_fluid_speed",
    "advective_cfl",
    "max_divergence",
    "mean_velocity_x",
    "mean_velocity_y",
    "mean_velocity_z",
];

/// Last diagnostic after `fluid-penalty` when the scene has walls.
pub const COUETTE_DIAGNOSTIC: &str = "couette_max_error";

/// Diagnostics after `fluid-momentum-exchange`, in their fixed order: the beads' share of the
/// solid volume and the sum of the impulses over all beads.
pub const EXCHANGE_DIAGNOSTICS: [&str; 4] = [
    "bead_volume",
    "total_impulse_x",
    "total_impulse_y",
    "total_impulse_z",
];

/// Tag of the saved-state format.
const STATE_FORMAT: &str = "fluid-node-state/1";

/// The fluid node: L2020 Smoothed Profile Method on a periodic pseudo-spectral solver.
#[derive(Default)]
pub struct FluidComponent {
    run: Option<Run>,
    /// `fluid.method = "fpd-lbm"`: the FPD lattice instead of the SPM solver.
    fpd: Option<crate::fpd_lbm::FpdRun>,
}

struct Run {
    cfg: FluidConfig,
    ns: SpectralNs,
    spm: Spm,
    total_beads: usize,
    /// `Some(n)`: u* of step n computed, penalty pending.
    pending: Option<u64>,
    states: Vec<BeadState>,
    impulses: Vec<BeadImpulse>,
    /// Plane-averaged u_x per y (Couette diagnostic).
    profile: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
struct StateHeader {
    format: String,
    dimensions: usize,
    grid: [usize; 3],
    pending: Option<u64>,
}

impl FluidComponent {
    pub fn new() -> Self {
        Self::default()
    }

    /// The grid (`None` before `configure`).
    pub fn grid(&self) -> Option<Grid> {
        self.run.as_ref().map(|r| r.ns.grid())
    }

    /// The validated scene (`None` before `configure`).
    pub fn config(&self) -> Option<&FluidConfig> {
        self.run.as_ref().map(|r| &r.cfg)
    }

    /// Real velocity components, x fastest ([`Grid::index`]); empty before `configure`.
    /// Between the two phases of a step this is u*.
    pub fn velocity(&self) -> &[Vec<f64>] {
        self.run
            .as_ref()
            .map_or(&[], |r| r.ns.velocity_components())
    }

    /// Total solid fraction per node (beads at the last placed positions and walls, before
    /// normalisation); empty before `configure`.
    pub fn solid_fraction(&self) -> &[f64] {
        self.run.as_ref().map_or(&[], |r| r.spm.phi())
    }

    /// Replace the velocity by `f(x, y, z)` at the nodes, projected to be divergence-free
    /// (e.g. an initial perturbation in a test). Does nothing before `configure`.
    pub fn set_velocity(&mut self, f: impl Fn(usize, usize, usize) -> [f64; 3]) {
        if let Some(r) = self.run.as_mut() {
            r.ns.set_velocity(f);
        }
    }

    fn run_mut(&mut self) -> Result<&mut Run, ComponentError> {
        self.run
            .as_mut()
            .ok_or_else(|| ComponentError::new("fluid-node: configure must come first"))
    }
}

impl Run {
    /// Read the bead states of step `step`'s phase `phase` and place the profiles.
    fn read_states(
        &mut self,
        step: u64,
        phase: Phase,
        exchange: &mut dyn Exchange,
    ) -> Result<(), ComponentError> {
        let h = exchange.read_states(Port::BeadStates, &mut self.states)?;
        if h.step != step + 1 {
            return Err(ComponentError(format!(
                "fluid-node: {phase} of step {step} expects the bead states of step {}, \
                 the latest publication is of step {}",
                step + 1,
                h.step
            )));
        }
        if self.states.len() != self.total_beads {
            return Err(ComponentError(format!(
                "fluid-node: {} bead states received, the scene's fibres have {} beads",
                self.states.len(),
                self.total_beads
            )));
        }
        self.spm.place(&self.states).map_err(ComponentError)
    }

    fn report(&mut self, step: u64) -> Result<PhaseReport, ComponentError> {
        let rho = self.cfg.density;
        let dt = self.cfg.dt;
        let ke = self.ns.kinetic_energy(rho);
        let vmax = self.ns.max_speed();
        let cfl = vmax * dt;
        if cfl.is_nan() || cfl > CFL_ABORT {
            return Err(ComponentError(format!(
                "fluid-node: the flow became unstable at step {step} (advective CFL limit): \
                 max|u| dt = {vmax:.6e} * {dt} = {cfl:.6e} exceeds {CFL_ABORT}; lower \
                 time.dt or the driving (fluid.body_force, walls.velocity)"
            )));
        }
        let div = self.ns.max_divergence();
        let mean = self.ns.mean_velocity();
        let mut values = vec![ke, vmax, cfl, div, mean[0], mean[1], mean[2]];
        let mut names: Vec<&str> = DIAGNOSTICS.to_vec();
        if let Some(w) = self.spm.walls() {
            self.ns.plane_average(0, &mut self.profile);
            values.push(w.couette_error(&self.profile));
            names.push(COUETTE_DIAGNOSTIC);
        }
        Ok(PhaseReport {
            diagnostics: names
                .iter()
                .zip(values)
                .map(|(n, v)| (n.to_string(), v))
                .collect(),
        })
    }
}

impl Component for FluidComponent {
    fn describe(&self) -> ModelDescription {
        let len = "length";
        ModelDescription {
            name: "fluid-node".into(),
            version: env!("CARGO_PKG_VERSION").into(),
            summary: "Eulerian flow around bead chains: L2020 Smoothed Profile Method on a \
                      periodic pseudo-spectral Navier-Stokes solver (exact viscous decay, \
                      2/3-dealiased advection), 2D or 3D, with optional moving walls"
                .into(),
            kind: "fluid".into(),
            models: vec!["spm".into(), "fpd-lbm".into()],
            coupling_schemes: vec!["spm".into(), "fpd".into()],
            effects: vec![effects::HYDRODYNAMICS.into(), effects::WALLS.into()],
            phases: vec![
                Phase::FluidMomentumExchange,
                Phase::FluidPenalty,
                Phase::FluidLatticeStep,
            ],
            parameters: vec![
                param("dimensions", "1", Some("3"), "2 (x-y plane) or 3"),
                param("time.dt", "time", None, "time step of the fractional step"),
                param("fluid.method", "1", None, "\"spm\" (Smoothed Profile Method, L2020) or \"fpd-lbm\" (fluid particle dynamics on MRT lattice Boltzmann D2Q9, S2023; 2D, lattice units, time.dt = 1)"),
                param("fluid.viscosity_ratio", "1", Some("100"), "fpd-lbm: r_eta = eta_s / eta_f (S2023 eq. 1)"),
                param("fluid.interface_ratio", "1", Some("0.125"), "fpd-lbm: r_xi = xi / d of the bead profile (S2023 eq. 2)"),
                param("fluid.profile_cutoff", "1", Some("5"), "fpd-lbm: profile cut-off in interface thicknesses xi"),
                param("fluid.grid", "1", None, "[nx, ny] (2D) or [nx, ny, nz] (3D) nodes, spacing 1 (grid units); each >= 8, any size"),
                param("fluid.viscosity", "mass / (length time)", None, "dynamic viscosity eta"),
                param("fluid.density", "mass / length^3", Some("1.0"), "density rho"),
                param("fluid.xi", len, Some("1.0"), "interface width xi of the smoothed profile (L2020 eq. 25)"),
                param("fluid.xi_cutoff", len, Some("3 xi"), "cut-off xi_c of the profile (L2020 eq. 25; L2020 uses xi = 1, xi_c = 3 and xi = 2, xi_c = 5)"),
                param("fluid.body_force", "mass / (length^2 time^2)", Some("[0.0, 0.0(, 0.0)]"), "uniform force density driving the flow (e.g. through a periodic array)"),
                param("fluid.initial_velocity", "1", Some("\"rest\""), "\"rest\" or \"couette\" (the linear profile between the walls)"),
                param("walls.velocity", "length / time", None, "[bottom, top] x-velocities of two solid slabs normal to y (absent: no walls, fully periodic)"),
                param("walls.thickness", len, Some("4.0"), "slab thickness T: inner faces at y = T - 1/2 and y = ny - T - 1/2, gap ny - 2 T"),
                param("fibre.N.beads", "1", None, "beads of fibre N (read for the number of bead records)"),
                param("fibre.N.bead_radius", len, None, "bead radius r_b of fibre N (eq. 25)"),
            ],
            inputs: vec![
            PortDescription {
                port: Port::BeadStates,
                record: "BeadState".into(),
                description: "all beads, fibres in order: positions n+1 with velocities n \
                              (fluid-momentum-exchange) and n+1 (fluid-penalty), published \
                              with step n+1; read only when the scene has fibres"
                    .into(),
            },
            PortDescription {
                port: Port::BeadForces,
                record: "BeadForce".into(),
                description: "fpd-lbm: force on each bead at the step's positions, read in \
                              fluid-lattice-step and spread as a force density (S2023 eq. 4)"
                    .into(),
            }],
            outputs: vec![
            PortDescription {
                port: Port::BeadImpulses,
                record: "BeadImpulse".into(),
                description: "time-integrated hydrodynamic force and torque per bead over \
                              step n (L2020 eqs. 35-36), published with step n+1 after \
                              fluid-momentum-exchange; in 2D the angular impulse is along z"
                    .into(),
            },
            PortDescription {
                port: Port::BeadVelocities,
                record: "BeadState".into(),
                description: "fpd-lbm: profile-weighted bead velocities of the new flow \
                              (S2023 eq. 5), published with step n+1 after fluid-lattice-step"
                    .into(),
            }],
            notes: vec![
                "no viscous time-step limit (the viscous term is integrated exactly); \
                 configure refuses a time step above the advective CFL limit (0.5) and \
                 the explicit-advection limit u^2 dt <= 2 nu for the wall speeds, and a run \
                 stops with an error when max|u| dt exceeds 1"
                    .into(),
                "SPM accuracy depends on nu dt / xi^2 (reported as fluid.spm_diffusion_number; \
                 keep it fixed when refining): the penalty acts once per step on a velocity \
                 that diffused sqrt(nu dt) into the solid, so the no-slip surface moves into \
                 the fluid for small values and into the solid for large ones. Measured with \
                 xi = 1, xi_c = 3: periodic-array drag within 2.5 % of Sangani-Acrivos \
                 (cylinders, c = 0.1) and Zick-Homsy (spheres, c = 0.064, 0.125) at 0.7 \
                 (+7 % at 0.5, -10 % at 1); Couette walls within 0.6 % at 0.7, 0.05 % at 1"
                    .into(),
                "walls are penalised like beads of prescribed velocity; no impulse is \
                 published for them"
                    .into(),
                "fpd-lbm: one phase per step, fluid-lattice-step (read bead positions and \
                 forces, S2023 eqs. 1, 2, 4; one MRT step; publish the bead velocities of \
                 eq. 5 on bead-velocities). Walls are half-way bounce-back planes at y = -1/2 \
                 and ny - 1/2; configure refuses wall Mach numbers above 0.3 and a run stops \
                 above 0.7"
                    .into(),
                "Cahn-Hilliard (fluid.binary, phase fluid-phase-field) is not coupled yet"
                    .into(),
            ],
        }
    }

    fn configure(
        &mut self,
        scene_toml: &str,
        _exchange: &mut dyn Exchange,
    ) -> Result<Configured, ComponentError> {
        self.run = None;
        self.fpd = None;
        let table = cosim::scene_keys::parse_table(scene_toml).map_err(ComponentError)?;
        let method = table
            .get("fluid")
            .and_then(|f| f.get("method"))
            .and_then(|m| m.as_str());
        if method == Some("fpd-lbm") {
            let (run, configured) = crate::fpd_lbm::FpdRun::configure(scene_toml)?;
            self.fpd = Some(run);
            return Ok(configured);
        }
        let cfg = parse_scene(scene_toml).map_err(ComponentError)?;
        let limits = stability::check(&cfg).map_err(ComponentError)?;
        let grid = Grid::new(cfg.dimensions, cfg.grid);
        let nu = cfg.kinematic_viscosity();
        let accel = cfg.body_force.map(|f| f / cfg.density);
        let mut ns = SpectralNs::new(grid, nu, cfg.dt, accel);
        let walls = cfg
            .walls
            .as_ref()
            .map(|w| Walls::new(grid.ny, w, cfg.xi, cfg.xi_cutoff));
        if cfg.initial_velocity == InitialVelocity::Couette {
            if let Some(w) = &walls {
                ns.set_velocity(|_, y, _| [w.couette_start(y), 0.0, 0.0]);
            }
        }
        let radii: Vec<f64> = cfg
            .fibres
            .iter()
            .flat_map(|f| std::iter::repeat_n(f.bead_radius, f.beads))
            .collect();
        let spm = Spm::new(grid, cfg.density, cfg.xi, cfg.xi_cutoff, &radii, walls);

        let mut active = Vec::new();
        if !cfg.fibres.is_empty() {
            active.push(effects::HYDRODYNAMICS.to_string());
        }
        if cfg.walls.is_some() {
            active.push(effects::WALLS.to_string());
        }

        let mut derived = vec![
            ("fluid.kinematic_viscosity".to_string(), nu),
            (
                "fluid.spm_diffusion_number".to_string(),
                nu * cfg.dt / (cfg.xi * cfg.xi),
            ),
        ];
        let cell_volume = grid.cells() as f64;
        if !cfg.fibres.is_empty() {
            let solid: f64 = cfg
                .fibres
                .iter()
                .map(|f| {
                    let r = f.bead_radius;
                    let v = if cfg.dimensions == 2 {
                        PI * r * r
                    } else {
                        4.0 / 3.0 * PI * r * r * r
                    };
                    v * f.beads as f64
                })
                .sum();
            derived.push(("fluid.solid_volume_fraction".into(), solid / cell_volume));
        }
        if let Some(w) = spm.walls() {
            let gamma = w.shear_rate();
            derived.push(("fluid.gap".into(), w.gap));
            derived.push(("fluid.shear_rate".into(), gamma));
            let l = cfg.fibres.first().map_or(w.gap, |f| f.length());
            derived.push((
                "fluid.reynolds".into(),
                cfg.density * gamma.abs() * l * l / cfg.viscosity,
            ));
            if let Some(f) = cfg.fibres.first() {
                derived.push(("fluid.confinement".into(), f.length() / w.gap));
                if let Some(e) = f.youngs_modulus {
                    if gamma != 0.0 {
                        // k0 = pi r_b E / 2 with L0 = 1 (grid units).
                        let k0 = PI * f.bead_radius * e / 2.0;
                        derived.push((
                            "fluid.k0_over_l0_eta_gamma".into(),
                            k0 / (cfg.viscosity * gamma.abs()),
                        ));
                    }
                }
            }
        }

        let total_beads = radii.len();
        let configured = Configured {
            beads_per_fibre: Vec::new(),
            effects: active,
            time_step_limits: limits
                .iter()
                .map(|l| (l.name.to_string(), l.dt_max))
                .collect(),
            derived,
        };
        self.run = Some(Run {
            profile: vec![0.0; grid.ny],
            cfg,
            ns,
            spm,
            total_beads,
            pending: None,
            states: Vec::with_capacity(total_beads),
            impulses: vec![BeadImpulse::default(); total_beads],
        });
        Ok(configured)
    }

    fn run_phase(
        &mut self,
        step: u64,
        phase: Phase,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        if let Some(fpd) = self.fpd.as_mut() {
            return match phase {
                Phase::FluidLatticeStep => fpd.lattice_step(step, exchange),
                other => Err(ComponentError(format!(
                    "fluid-node: phase {other} does not belong to fluid.method = \"fpd-lbm\" \
                     (it runs fluid-lattice-step)"
                ))),
            };
        }
        let run = self.run_mut()?;
        let has_beads = run.total_beads > 0;
        match phase {
            Phase::FluidMomentumExchange => {
                if let Some(p) = run.pending {
                    return Err(ComponentError(format!(
                        "fluid-node: fluid-momentum-exchange of step {step} requested while \
                         the penalty of step {p} is still pending"
                    )));
                }
                if has_beads {
                    run.read_states(step, phase, exchange)?;
                }
                // Eq. 34: u^n -> u*.
                run.ns.advance_intermediate();
                let mut total = [0.0; 3];
                if has_beads {
                    // Eqs. 35-36.
                    run.spm
                        .impulses(run.ns.velocity_components(), &run.states, &mut run.impulses);
                    for (i, j) in run.impulses.iter().enumerate() {
                        if j.impulse
                            .iter()
                            .chain(&j.angular_impulse)
                            .any(|v| !v.is_finite())
                        {
                            return Err(ComponentError(format!(
                                "fluid-node: the impulse on bead {i} is not finite at step \
                                 {step}: the flow or the bead velocities blew up"
                            )));
                        }
                        for (t, v) in total.iter_mut().zip(j.impulse) {
                            *t += v;
                        }
                    }
                    exchange.publish_impulses(Port::BeadImpulses, step + 1, &run.impulses)?;
                }
                run.pending = Some(step);
                let values = [run.spm.bead_volume(), total[0], total[1], total[2]];
                Ok(PhaseReport {
                    diagnostics: EXCHANGE_DIAGNOSTICS
                        .iter()
                        .zip(values)
                        .map(|(n, v)| (n.to_string(), v))
                        .collect(),
                })
            }
            Phase::FluidPenalty => {
                if run.pending != Some(step) {
                    return Err(ComponentError(format!(
                        "fluid-node: fluid-penalty of step {step} requested before \
                         fluid-momentum-exchange of step {step}"
                    )));
                }
                if has_beads {
                    run.read_states(step, phase, exchange)?;
                }
                if run.spm.has_solids() {
                    // Eqs. 37-38.
                    let (spm, states) = (&run.spm, &run.states);
                    run.ns
                        .add_projected(|c, u_c, out| spm.penalty(c, u_c, states, out));
                }
                run.pending = None;
                run.report(step)
            }
            other => Err(ComponentError(format!(
                "fluid-node does not serve phase {other} (it serves fluid-momentum-exchange \
                 and fluid-penalty; Cahn-Hilliard and the FPD coupling are not available yet)"
            ))),
        }
    }

    fn save_state(&self) -> Result<Vec<u8>, ComponentError> {
        if self.fpd.is_some() {
            return Err(ComponentError::new(
                "fluid-node: saving the state of an fpd-lbm fluid is not implemented yet",
            ));
        }
        let run = self
            .run
            .as_ref()
            .ok_or_else(|| ComponentError::new("fluid-node: nothing to save before configure"))?;
        let g = run.ns.grid();
        let header = StateHeader {
            format: STATE_FORMAT.into(),
            dimensions: g.dims,
            grid: g.sizes(),
            pending: run.pending,
        };
        let mut out = serde_json::to_vec(&header)
            .map_err(|e| ComponentError(format!("fluid-node: cannot serialise the state: {e}")))?;
        out.push(b'\n');
        out.reserve(g.dims * g.modes() * 16);
        for c in 0..g.dims {
            for v in run.ns.spectrum(c) {
                out.extend_from_slice(&v.re.to_le_bytes());
                out.extend_from_slice(&v.im.to_le_bytes());
            }
        }
        Ok(out)
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<(), ComponentError> {
        let not_state =
            |why: &str| ComponentError(format!("fluid-node: not a saved fluid state: {why}"));
        let nl = state
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| not_state("no header"))?;
        let header: StateHeader =
            serde_json::from_slice(&state[..nl]).map_err(|e| not_state(&e.to_string()))?;
        if header.format != STATE_FORMAT {
            return Err(ComponentError(format!(
                "fluid-node: saved state has format {:?}, expected {STATE_FORMAT:?}",
                header.format
            )));
        }
        let run = self.run.as_mut().ok_or_else(|| {
            ComponentError::new(
                "fluid-node: configure with the same scene before restoring a state",
            )
        })?;
        let g = run.ns.grid();
        if header.dimensions != g.dims || header.grid != g.sizes() {
            return Err(ComponentError(format!(
                "fluid-node: saved state is of a {}D grid {:?}, the configured scene has a {}D grid {:?}",
                header.dimensions,
                header.grid,
                g.dims,
                g.sizes()
            )));
        }
        let body = &state[nl + 1..];
        if body.len() != g.dims * g.modes() * 16 {
            return Err(not_state(&format!(
                "{} bytes of spectrum, expected {}",
                body.len(),
                g.dims * g.modes() * 16
            )));
        }
        let mut spectrum = vec![vec![Complex64::default(); g.modes()]; g.dims];
        let mut words = body
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().unwrap_or([0; 8])));
        for comp in spectrum.iter_mut() {
            for v in comp.iter_mut() {
                v.re = words.next().unwrap_or(0.0);
                v.im = words.next().unwrap_or(0.0);
            }
        }
        run.ns.set_spectrum(&spectrum);
        run.spm.invalidate();
        run.pending = header.pending;
        Ok(())
    }
}
