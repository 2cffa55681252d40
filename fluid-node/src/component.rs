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
//!
//! With `[fluid.binary]` a third phase comes first, `fluid-phase-field` (step n): read the
//! bead states of step n (positions n), advance ψ by one Cahn–Hilliard step advected by uⁿ
//! and report `mean_psi`, `max_abs_psi`, ...; the momentum exchange then adds the capillary
//! force with ψⁿ⁺¹ and φⁿ⁺¹ to uⁿ -> u* (L2020 eq. 34; [`crate::binary_fluid`]).
use crate::binary_fluid::BinaryFluid;
use crate::config::{parse_scene, FluidConfig, InitialVelocity};
use crate::grain_tuner::GrainTuner;
use crate::grid::Grid;
use crate::spectral_ns::SpectralNs;
use crate::spm::Spm;
use crate::stability::{self, CFL_ABORT};
use crate::start_geometry::{StartBox, StartCheck, WallFaces};
use crate::walls::Walls;
use cosim::description::{parameter as param, ModelDescription, PortDescription};
use cosim::{
    effects, BeadImpulse, BeadState, Component, ComponentError, Configured, Detail, Exchange,
    Phase, PhaseReport, Port,
};
use rustfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Diagnostics after `fluid-penalty`, in their fixed order (`max_divergence` in a full report
/// only, [`cosim::Detail`]); with walls, in a full report, [`COUETTE_DIAGNOSTIC`] follows.
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
    /// Chooses the parallel grain from the time of the steps (grain_tuner.rs).
    tuner: Option<GrainTuner>,
    /// A grain set with [`FluidComponent::fix_grain`], kept instead of tuning.
    fixed_grain: Option<usize>,
    /// Time spent in this step's phases so far (s).
    step_seconds: f64,
}

struct Run {
    cfg: FluidConfig,
    ns: SpectralNs,
    spm: Spm,
    total_beads: usize,
    /// `Some(n)`: u* of step n computed, penalty pending.
    pending: Option<u64>,
    states: Vec<BeadState>,
    /// The step of the bead states in `states` (and in the placed profiles).
    states_step: Option<u64>,
    impulses: Vec<BeadImpulse>,
    /// Plane-averaged u_x per y (Couette diagnostic).
    profile: Vec<f64>,
    /// `[fluid.binary]`: the phase field (`None`: a single fluid, no Cahn–Hilliard work).
    binary: Option<BinaryFluid>,
    /// The step whose `fluid-phase-field` ran last (binary fluids).
    psi_step: Option<u64>,
    /// Checks the first bead states of a run from step 0, then `None`.
    start: Option<StartCheck>,
}

#[derive(Serialize, Deserialize)]
struct StateHeader {
    format: String,
    dimensions: usize,
    grid: [usize; 3],
    pending: Option<u64>,
    /// Binary fluids: the step whose fluid-phase-field ran last (absent for a single fluid).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    psi_step: Option<u64>,
}

impl FluidComponent {
    pub fn new() -> Self {
        Self::default()
    }

    /// Run every phase with the parallel grain `elements` (elements per rayon task) instead of
    /// choosing it from the time of the steps: for benchmarks that compare builds, and for
    /// the test that the grain changes no result. Also after a later `configure`.
    pub fn fix_grain(&mut self, elements: usize) {
        self.fixed_grain = Some(elements.max(1));
        self.tuner = None;
    }

    /// Tune the grain for a grid of `rows` rows of `row_len` elements, from its default
    /// (unless [`FluidComponent::fix_grain`] fixed it).
    fn start_tuner(&mut self, rows: usize, row_len: usize) {
        if self.fixed_grain.is_some() {
            return;
        }
        let tuner = GrainTuner::new(rows, row_len);
        crate::parallel::set_grain(tuner.grain());
        self.tuner = Some(tuner);
    }

    /// [`Component::configure`] for `fluid.method = "spm"`: the spectral solver, the
    /// smoothed profiles and walls, the binary fluid if any; the time-step limits, effects,
    /// derived values and notes the node reports.
    fn configure_spm(&mut self, scene_toml: &str) -> Result<Configured, ComponentError> {
        let cfg = parse_scene(scene_toml).map_err(ComponentError)?;
        let mut limits = stability::check(&cfg).map_err(ComponentError)?;
        let grid = Grid::new(cfg.dimensions, cfg.grid);
        self.start_tuner(grid.rows(), grid.nx);
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
        let binary = match &cfg.binary {
            None => None,
            Some(b) => {
                let psi0: Vec<f64> = cfg
                    .fibres
                    .iter()
                    .flat_map(|f| std::iter::repeat_n(f.affinity, f.beads))
                    .collect();
                let fluid = BinaryFluid::new(grid, b, &psi0, cfg.walls.is_some())
                    .map_err(ComponentError)?;
                limits.extend(
                    fluid
                        .check_time_step(stability::initial_speed(&cfg), cfg.density, cfg.viscosity)
                        .map_err(ComponentError)?,
                );
                ns.enable_force_density();
                Some(fluid)
            }
        };

        let mut active = Vec::new();
        if !cfg.fibres.is_empty() {
            active.push(effects::HYDRODYNAMICS.to_string());
        }
        if cfg.walls.is_some() {
            active.push(effects::WALLS.to_string());
        }
        if binary.is_some() {
            active.push(effects::CAPILLARITY.to_string());
        }

        let mut derived = spm_derived_values(&cfg, grid, spm.walls());
        if let Some(b) = &cfg.binary {
            derived.extend(crate::binary_fluid::derived::numbers(&cfg, b, grid));
        }

        let mut notes = cfg
            .binary
            .as_ref()
            .map_or_else(Vec::new, crate::binary_fluid::derived::notes);
        notes.extend(cosim::profile::truncation_note(cfg.xi, cfg.xi_cutoff));
        notes.extend(cfg.fibres.iter().enumerate().filter_map(|(n, f)| {
            cosim::profile::small_bead_note(
                &format!("fibre.{n}"),
                f.bead_radius,
                cfg.xi,
                cfg.xi_cutoff,
                grid.dims,
            )
        }));
        let total_beads = radii.len();
        let start = spm_start_check(grid, &spm, &cfg, radii);
        let configured = Configured {
            beads_per_fibre: Vec::new(),
            effects: active,
            time_step_limits: limits
                .iter()
                .map(|l| (l.name.to_string(), l.dt_max))
                .collect(),
            derived,
            notes,
        };
        self.run = Some(Run {
            profile: vec![0.0; grid.ny],
            cfg,
            ns,
            spm,
            total_beads,
            pending: None,
            states: Vec::with_capacity(total_beads),
            states_step: None,
            impulses: vec![BeadImpulse::default(); total_beads],
            binary,
            psi_step: None,
            start: Some(start),
        });
        Ok(configured)
    }

    /// [`Component::run_phase`] without the timing the grain tuner uses.
    fn run_phase_untimed(
        &mut self,
        step: u64,
        phase: Phase,
        detail: Detail,
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
        match phase {
            Phase::FluidPhaseField => run.phase_field(step, detail, exchange),
            Phase::FluidMomentumExchange => run.momentum_exchange(step, exchange),
            Phase::FluidPenalty => run.penalty(step, detail, exchange),
            other => Err(ComponentError(format!(
                "fluid-node: phase {other} does not belong to fluid.method = \"spm\" (it \
                 serves fluid-phase-field, fluid-momentum-exchange and fluid-penalty)"
            ))),
        }
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
    /// Between the two phases of an SPM step with solids it is u* only on the solids' rows
    /// (the others still hold u^n; see `SpectralNs::velocity`).
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
    /// `fluid-phase-field` of step n: the ternary Cahn-Hilliard step to psi^{n+1}.
    fn phase_field(
        &mut self,
        step: u64,
        detail: Detail,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        let no_binary = || {
            ComponentError(
                "fluid-node: fluid-phase-field needs a binary fluid ([fluid.binary])".into(),
            )
        };
        if self.binary.is_none() {
            return Err(no_binary());
        }
        if let Some(p) = self.pending {
            return Err(ComponentError(format!(
                "fluid-node: fluid-phase-field of step {step} requested while the \
                 penalty of step {p} is still pending"
            )));
        }
        // The states of step n are those the penalty of step n - 1 read. Read them
        // only if not held: in a pipelined run the fibre node may publish those of
        // step n + 1 meanwhile (coordinator/src/pipeline.rs).
        if self.total_beads > 0 && self.states_step != Some(step) {
            self.read_states(step, Phase::FluidPhaseField, exchange)?;
        }
        let (spm, ns) = (&self.spm, &self.ns);
        let Some(b) = self.binary.as_mut() else {
            return Err(no_binary());
        };
        b.phase_field_step(spm, ns.velocity_components())
            .map_err(|e| ComponentError(format!("{e} (at step {step})")))?;
        self.psi_step = Some(step);
        Ok(PhaseReport {
            diagnostics: b.report(spm, detail),
            detail,
        })
    }

    /// `fluid-momentum-exchange` of step n: u^n -> u* and the beads' impulses, published
    /// for step n + 1 (L2020 eqs. 34-36).
    fn momentum_exchange(
        &mut self,
        step: u64,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        let has_beads = self.total_beads > 0;
        if let Some(p) = self.pending {
            return Err(ComponentError(format!(
                "fluid-node: fluid-momentum-exchange of step {step} requested while \
                 the penalty of step {p} is still pending"
            )));
        }
        if self.binary.is_some() && self.psi_step != Some(step) {
            return Err(ComponentError(format!(
                "fluid-node: fluid-momentum-exchange of step {step} requested before \
                 fluid-phase-field of step {step} (a binary fluid runs it first)"
            )));
        }
        if has_beads {
            self.read_states(step, Phase::FluidMomentumExchange, exchange)?;
        }
        if let Some(b) = self.binary.as_mut() {
            // Eq. 34's capillary terms with psi^{n+1} and phi^{n+1}.
            b.load_capillary_force(&self.spm, &mut self.ns, self.cfg.density)
                .map_err(ComponentError)?;
        }
        // Eq. 34: u^n -> u*. With solids the penalty rebuilds the whole real field,
        // and until then u* is read only on the solids' rows.
        if self.spm.has_solids() {
            self.ns.advance_intermediate_on(self.spm.solid_rows());
        } else {
            self.ns.advance_intermediate();
        }
        let mut total = [0.0; 3];
        if has_beads {
            // Eqs. 35-36.
            self.spm.impulses(
                self.ns.velocity_components(),
                &self.states,
                &mut self.impulses,
            );
            for (i, j) in self.impulses.iter().enumerate() {
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
            exchange.publish_impulses(Port::BeadImpulses, step + 1, &self.impulses)?;
        }
        self.pending = Some(step);
        let values = [self.spm.bead_volume(), total[0], total[1], total[2]];
        Ok(PhaseReport {
            diagnostics: EXCHANGE_DIAGNOSTICS
                .iter()
                .zip(values)
                .map(|(n, v)| (n.to_string(), v))
                .collect(),
            detail: Detail::Full,
        })
    }

    /// `fluid-penalty` of step n: the rigid-body penalty with the beads' new velocities and
    /// the projection to u^{n+1} (L2020 eqs. 37-38).
    fn penalty(
        &mut self,
        step: u64,
        detail: Detail,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        if self.pending != Some(step) {
            return Err(ComponentError(format!(
                "fluid-node: fluid-penalty of step {step} requested before \
                 fluid-momentum-exchange of step {step}"
            )));
        }
        if self.total_beads > 0 {
            self.read_states(step, Phase::FluidPenalty, exchange)?;
        }
        if self.spm.has_solids() {
            // Eqs. 37-38. The penalty reads u* on the solids' rows at the new
            // positions; a sub-cycled fibre may have moved a bead onto a row the
            // impulses did not read, and the solver brings such rows up to date.
            let (spm, states) = (&self.spm, &self.states);
            self.ns.add_projected(spm.solid_rows(), |c, r, u_c, out| {
                spm.penalty_row((c, r), u_c, states, out)
            });
        }
        self.pending = None;
        self.report(step, detail)
    }

    /// Read the bead states of step `step`'s phase `phase` and place the profiles: the
    /// states published with step `step + 1` (positions n+1), or with `step` for
    /// `fluid-phase-field` (positions n).
    fn read_states(
        &mut self,
        step: u64,
        phase: Phase,
        exchange: &mut dyn Exchange,
    ) -> Result<(), ComponentError> {
        let port = if phase == Phase::FluidMomentumExchange {
            Port::BeadPositions
        } else {
            Port::BeadStates
        };
        let h = exchange.read_states(port, &mut self.states)?;
        let expect = if phase == Phase::FluidPhaseField {
            step
        } else {
            step + 1
        };
        if h.step != expect {
            return Err(ComponentError(format!(
                "fluid-node: {phase} of step {step} expects the bead states of step {expect}, \
                 the latest publication is of step {}",
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
        if step == 0 {
            if let Some(c) = self.start.take() {
                c.check(&self.states)
                    .map_err(|e| ComponentError(format!("fluid-node: {e}")))?;
            }
        }
        self.states_step = None;
        self.spm.place(&self.states).map_err(ComponentError)?;
        self.states_step = Some(h.step);
        Ok(())
    }

    /// The penalty's diagnostics ([`DIAGNOSTICS`], then [`COUETTE_DIAGNOSTIC`] with walls); a
    /// brief report leaves out `max_divergence` (an inverse transform, 10-15 % of a 2D step)
    /// and the Couette error (a pass over one component).
    fn report(&mut self, step: u64, detail: Detail) -> Result<PhaseReport, ComponentError> {
        let rho = self.cfg.density;
        let dt = self.cfg.dt;
        let (ke, vmax) = self.ns.energy_and_max_speed(rho);
        let cfl = vmax * dt;
        if cfl.is_nan() || cfl > CFL_ABORT {
            return Err(ComponentError(format!(
                "fluid-node: the flow became unstable at step {step} (advective CFL limit): \
                 max|u| dt = {} * {} = {} exceeds {CFL_ABORT}; lower \
                 time.dt or the driving (fluid.body_force, walls.velocity)",
                cosim::scene_keys::Sig(vmax),
                cosim::scene_keys::Num(dt),
                cosim::scene_keys::Sig(cfl)
            )));
        }
        let full = detail == Detail::Full;
        let div = full.then(|| self.ns.max_divergence());
        let mean = self.ns.mean_velocity();
        let values = [ke, vmax, cfl].map(Some).into_iter().chain([div]);
        let values = values.chain(mean.map(Some));
        let mut diagnostics: Vec<(String, f64)> = DIAGNOSTICS
            .iter()
            .zip(values)
            .filter_map(|(n, v)| v.map(|v| (n.to_string(), v)))
            .collect();
        if let (Some(w), true) = (self.spm.walls(), full) {
            self.ns.plane_average(0, &mut self.profile);
            let error = w.couette_error(&self.profile);
            diagnostics.push((COUETTE_DIAGNOSTIC.to_string(), error));
        }
        Ok(PhaseReport {
            diagnostics,
            detail,
        })
    }
}

/// The check of the first bead states in the periodic box, with the walls' faces where the
/// scene has walls.
fn spm_start_check(grid: Grid, spm: &Spm, cfg: &FluidConfig, radii: Vec<f64>) -> StartCheck {
    StartCheck {
        geometry: StartBox {
            dims: grid.dims,
            size: [grid.nx as f64, grid.ny as f64, grid.nz as f64],
            periodic: [true, true, grid.dims == 3],
            walls: spm.walls().map(|w| WallFaces {
                bottom: w.faces[0],
                top: w.faces[1],
            }),
        },
        beads_per_fibre: cfg.fibres.iter().map(|f| f.beads).collect(),
        radius: radii,
    }
}

/// The numbers an SPM scene reports when configured ("derived" in the summary): the
/// kinematic viscosity, the profile's diffusion number nu dt / xi^2, the beads' volume
/// fraction, and between walls the gap, the shear rate, Re on fibre 0's length (else the
/// gap), S2023's C and Re_ps (eq. 18) and L2020's stiffness k0 / (L0 eta0 gamma0).
fn spm_derived_values(cfg: &FluidConfig, grid: Grid, walls: Option<&Walls>) -> Vec<(String, f64)> {
    let nu = cfg.kinematic_viscosity();
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
    if let Some(w) = walls {
        let gamma = w.shear_rate();
        derived.push(("fluid.gap".into(), w.gap));
        derived.push(("fluid.shear_rate".into(), gamma));
        let l = cfg.fibres.first().map_or(w.gap, |f| f.length());
        // Walls at one speed shear nothing: no shear Reynolds numbers.
        if gamma != 0.0 {
            derived.push((
                "fluid.reynolds".into(),
                cfg.density * gamma.abs() * l * l / cfg.viscosity,
            ));
        }
        if let Some(f) = cfg.fibres.first() {
            // S2023 eq. 18 with l_c = N d (the fibre's length for touching beads) and H the
            // gap between the slabs, as the FPD fluid reports them.
            let lc = f.beads as f64 * 2.0 * f.bead_radius;
            derived.push(("fluid.confinement".into(), lc / w.gap));
            if gamma != 0.0 {
                derived.push((
                    "fluid.particle_shear_reynolds".into(),
                    cfg.density * gamma.abs() * lc * lc / (4.0 * cfg.viscosity),
                ));
            }
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
    derived
}

impl Component for FluidComponent {
    fn describe(&self) -> ModelDescription {
        let len = "length";
        ModelDescription {
            name: "fluid-node".into(),
            version: env!("CARGO_PKG_VERSION").into(),
            summary: "Eulerian flow around bead chains, two methods: `spm`, L2020's Smoothed \
                      Profile Method on a periodic pseudo-spectral Navier-Stokes solver (exact \
                      viscous decay, 2/3-dealiased advection), 2D or 3D, with optional moving \
                      walls and a ternary Cahn-Hilliard second fluid; `fpd-lbm`, S2023's Fluid \
                      Particle Dynamics on an MRT D2Q9 lattice Boltzmann solver, 2D, periodic or \
                      between moving walls"
                .into(),
            kind: "fluid".into(),
            models: vec!["spm".into(), "fpd-lbm".into()],
            coupling_schemes: vec!["spm".into(), "fpd".into()],
            effects: vec![
                effects::HYDRODYNAMICS.into(),
                effects::WALLS.into(),
                effects::CAPILLARITY.into(),
            ],
            phases: vec![
                Phase::FluidPhaseField,
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
                param("fluid.confinement", "1", Some("absent"), "2D, with walls: C = l_c / H (S2023 eq. 18, l_c = N d of fibre 0) in place of the gap: fluid.grid = [nx] becomes [nx, round(l_c / C + 2 T)], H = ny under fpd-lbm (T = 0) and ny - 2 T between the spm wall slabs (resolved by the coordinator before the nodes are configured; a rounded gap gets a note)"),
                param("fluid.particle_shear_reynolds", "1", Some("absent"), "with walls: Re_ps = rho gamma l_c^2 / (4 eta_f) (S2023 eq. 18) in place of fluid.viscosity, gamma = (top - bottom) / H (resolved by the coordinator)"),
                param("fluid.solid_layers", "1", Some("absent"), "fpd-lbm, table {thickness, interface}: S2023's Couette sandwich (eq. 14), a layer of the solid viscosity on each wall (no fibres)"),
                param("fluid.stream", "1", Some("absent"), "fpd-lbm, table {velocity, sponge, sponge_rate}: a uniform stream U along x past held beads (S2023 Fig. 4); walls, if any, slide at U"),
                param("fluid.stream.velocity", "length / time", None, "stream speed U (lattice units; |U| sqrt 3 <= 0.3)"),
                param("fluid.stream.sponge", len, None, "width of the sponge at the right end of the box that returns the wake to the stream (lattice columns)"),
                param("fluid.stream.sponge_rate", "1 / time", Some("0.1"), "largest relaxation rate of the sponge, reached over its first half (sin^2 ramp)"),
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
                param("fibre.N.affinity", "1", Some("0.0"), "[fluid.binary]: wetting affinity psi0 in [-1, 1] of fibre N's beads; psi* = (2 psi0 + psi0^3) / 3 (L2020 eq. 31)"),
                param("fluid.binary", "1", Some("absent"), "table: a binary fluid A (psi = +1) / B (psi = -1), ternary Cahn-Hilliard of L2020 eqs. 27-34 (absent: a single fluid)"),
                param("fluid.binary.xi", len, Some("2.0"), "Cahn-Hilliard interfacial length xi (eq. 28); L2020 uses the same xi as fluid.xi, and the contact-angle reference needs them equal"),
                param("fluid.binary.e0", "mass / (length time^2)", Some("1.0"), "energy density scale e0 = kB T0 / v0 (eq. 27); or give fluid.binary.sigma"),
                param("fluid.binary.sigma", "mass / time^2", Some("(2 sqrt 2 / 3) e0 xi"), "A/B surface tension sigma_AB instead of e0: e0 = 3 sigma / (2 sqrt 2 xi)"),
                param("fluid.binary.mobility", "length^4 time / mass", Some("1.0"), "mobility M (eq. 32), D0 = e0 M; or give fluid.binary.peclet"),
                param("fluid.binary.peclet", "1", Some("absent"), "Pe = U0 L0 / (e0 M) (eq. 41, L0 = 1) instead of mobility; needs U0"),
                param("fluid.binary.velocity_scale", "length / time", Some("max |walls.velocity|"), "reference velocity U0 of eqs. 39-41 (for peclet and the reported Re, We, Pe)"),
                param("fluid.binary.stabilisation", "1", Some("3.0"), "linear stabilisation S of the semi-implicit step (>= 2.815: no diffusive time-step limit)"),
                param("fluid.binary.wall_affinity", "1", Some("0.0"), "psi0 of the walls' solid (eq. 31)"),
                param("fluid.binary.initial", "1", None, "\"flat\" (normal, position, width), \"droplet\" (centre, radius, inside) or \"half-droplet\" (centre, normal, radius, inside; L2020 section 3.5)"),
                param("fluid.binary.normal", "1", Some("last axis"), "flat: axis index or a vector along an axis, pointing into fluid A; half-droplet: direction from the base into the droplet"),
                param("fluid.binary.position", len, None, "flat: coordinate of the interface where fluid A begins along the normal"),
                param("fluid.binary.width", len, Some("half the box"), "flat: thickness of the periodic slab of fluid A (a second interface closes it)"),
                param("fluid.binary.centre", len, None, "droplet: centre; half-droplet: centre of the base"),
                param("fluid.binary.radius", len, None, "droplet, half-droplet: radius"),
                param("fluid.binary.inside", "1", Some("\"A\""), "droplet, half-droplet: the fluid inside, \"A\" or \"B\""),
            ],
            inputs: vec![
            PortDescription {
                port: Port::BeadStates,
                record: "BeadState".into(),
                description: "all beads, fibres in order: positions and velocities n+1, \
                              published with step n+1, read in fluid-penalty (and in \
                              fluid-phase-field on a run's first step); only with fibres"
                    .into(),
            },
            PortDescription {
                port: Port::BeadPositions,
                record: "BeadState".into(),
                description: "all beads, fibres in order: positions n+1 with velocities n, \
                              published with step n+1, read in fluid-momentum-exchange; only \
                              with fibres"
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
                "fluid.binary: phase fluid-phase-field (first in the step) advances psi by one \
                 semi-implicit Cahn-Hilliard step advected by u^n with phi at X^n (mean psi \
                 conserved to round-off); fluid-momentum-exchange adds the capillary force \
                 -psi grad mu_psi - phi grad mu_phi (L2020 eqs. 33-34) with phi at X^(n+1) to \
                 u^n -> u*, so the impulses of eqs. 35-36 carry the capillary force. configure \
                 refuses a time step above the Cahn-Hilliard limits or the capillary limit \
                 (Galusinski & Vigneaux 2008)"
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
        self.tuner = None;
        self.step_seconds = 0.0;
        let table = cosim::scene_keys::parse_table(scene_toml).map_err(ComponentError)?;
        let method = table
            .get("fluid")
            .and_then(|f| f.get("method"))
            .and_then(|m| m.as_str());
        if method == Some("fpd-lbm") {
            let (run, configured) = crate::fpd_lbm::FpdRun::configure(scene_toml)?;
            self.start_tuner(run.scene.ny, run.scene.nx);
            self.fpd = Some(run);
            return Ok(configured);
        }
        self.configure_spm(scene_toml)
    }

    fn run_phase(
        &mut self,
        step: u64,
        phase: Phase,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        self.run_phase_with(step, phase, Detail::Full, exchange)
    }

    fn run_phase_with(
        &mut self,
        step: u64,
        phase: Phase,
        detail: Detail,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        if let Some(g) = self.fixed_grain {
            crate::parallel::set_grain(g);
        }
        let started = std::time::Instant::now();
        let report = self.run_phase_untimed(step, phase, detail, exchange);
        self.step_seconds += started.elapsed().as_secs_f64();
        // The step's last phase: the penalty (SPM) or the lattice step (FPD).
        if matches!(phase, Phase::FluidPenalty | Phase::FluidLatticeStep) {
            if let Some(t) = self.tuner.as_mut() {
                t.end_step(self.step_seconds);
                crate::parallel::set_grain(t.grain());
            }
            self.step_seconds = 0.0;
        }
        report
    }

    fn check_start(&mut self, exchange: &mut dyn Exchange) -> Result<(), ComponentError> {
        let check = match (&self.fpd, &self.run) {
            (Some(f), _) => f.start_check(),
            (None, Some(r)) => r.start.as_ref().filter(|_| r.total_beads > 0),
            (None, None) => {
                return Err(ComponentError::new("fluid-node: configure must come first"))
            }
        };
        let Some(check) = check else {
            return Ok(());
        };
        let mut states = Vec::new();
        exchange.read_states(Port::BeadStates, &mut states)?;
        check
            .check(&states)
            .map_err(|e| ComponentError(format!("fluid-node: {e}")))
    }

    fn write_fields(
        &mut self,
        step: u64,
        _time: f64,
        dir: &std::path::Path,
    ) -> Result<Vec<String>, ComponentError> {
        let name = crate::field_output::file_name(step);
        if let Some(fpd) = &self.fpd {
            return fpd.write_fields(dir, &name);
        }
        let run = self.run.as_ref().ok_or_else(|| {
            ComponentError::new("fluid-node: no fields to write before configure")
        })?;
        let g = run.ns.grid();
        let n = g.nx * g.ny * g.nz;
        let components: Vec<&[f64]> = run
            .ns
            .velocity_components()
            .iter()
            .map(|c| &c[..])
            .collect();
        let velocity = crate::field_output::interleave(&components, n);
        let mut arrays = vec![
            cosim::vtk::Array::vector("velocity", &velocity),
            cosim::vtk::Array::scalar("solid_fraction", run.spm.phi()),
        ];
        if let Some(b) = &run.binary {
            arrays.push(cosim::vtk::Array::scalar("psi", b.solver().psi()));
        }
        crate::field_output::write(dir, &name, g.sizes(), &arrays)
    }

    fn save_state(&self) -> Result<Vec<u8>, ComponentError> {
        if let Some(fpd) = &self.fpd {
            return fpd.save();
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
            psi_step: run.psi_step,
        };
        let header = serde_json::to_vec(&header)
            .map_err(|e| ComponentError(format!("fluid-node: cannot serialise the state: {e}")))?;
        // The velocity spectra, then (a binary fluid) its spectral psi; re and im in turn.
        let mut spectra: Vec<&[Complex64]> = (0..g.dims).map(|c| run.ns.spectrum(c)).collect();
        if let Some(b) = &run.binary {
            spectra.push(b.spectrum());
        }
        let values: Vec<f64> = spectra
            .iter()
            .flat_map(|s| s.iter().flat_map(|v| [v.re, v.im]))
            .collect();
        Ok(crate::saved_state::join(&header, values.into_iter()))
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<(), ComponentError> {
        if let Some(fpd) = self.fpd.as_mut() {
            return fpd.restore(state);
        }
        let not_state =
            |why: &str| ComponentError(format!("fluid-node: not a saved fluid state: {why}"));
        let (header, body) =
            crate::saved_state::split(state).ok_or_else(|| not_state("no header"))?;
        let header: StateHeader =
            serde_json::from_slice(header).map_err(|e| not_state(&e.to_string()))?;
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
        let fields = g.dims + usize::from(run.binary.is_some());
        if body.len() != fields * g.modes() * 16 {
            return Err(not_state(&format!(
                "{} bytes of spectrum, expected {}",
                body.len(),
                fields * g.modes() * 16
            )));
        }
        let mut spectrum = vec![vec![Complex64::default(); g.modes()]; g.dims];
        let mut words = crate::saved_state::values(body);
        for comp in spectrum.iter_mut() {
            for v in comp.iter_mut() {
                v.re = words.next().unwrap_or(0.0);
                v.im = words.next().unwrap_or(0.0);
            }
        }
        run.ns.set_spectrum(&spectrum);
        if let Some(b) = run.binary.as_mut() {
            let psi: Vec<Complex64> = (0..g.modes())
                .map(|_| {
                    let re = words.next().unwrap_or(0.0);
                    Complex64::new(re, words.next().unwrap_or(0.0))
                })
                .collect();
            b.set_spectrum(&psi).map_err(ComponentError)?;
        }
        run.spm.invalidate();
        run.states_step = None;
        run.pending = header.pending;
        run.psi_step = header.psi_step;
        Ok(())
    }
}
