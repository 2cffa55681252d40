//! The fibre node as a co-simulation component ([`cosim::Component`]).
use crate::config::{parse_scene, Coupling, SceneConfig};
use crate::fibre::{together, BeadKinematics, Fibre, Model};
use crate::fibre_contact::FibreContact;
use crate::fibre_overlap::FibreOverlap;
use crate::fibre_setup;
use crate::quaternion::{from_array, to_array, Vec3};
use crate::self_overlap::SelfOverlap;
use crate::wall_contact::overlaps;
use cosim::description::{parameter as param, ModelDescription, PortDescription};
use cosim::{
    effects, BeadForce, BeadImpulse, BeadState, Component, ComponentError, Configured, Exchange,
    Phase, PhaseReport, Port,
};
use serde::{Deserialize, Serialize};

/// Names of the diagnostics of every [`PhaseReport`], in their fixed order.
pub const DIAGNOSTICS: [&str; 11] = [
    "kinetic_energy",
    "stretch_energy",
    "bend_energy",
    "twist_energy",
    "contact_energy",
    "elastic_energy",
    "max_speed",
    "max_net_force",
    "wall_overlap",
    "self_overlap",
    "fibre_overlap",
];

/// Tag of the saved-state format.
const STATE_FORMAT: &str = "fibre-node-state/2";

/// f64 values saved per bead (see [`SavedState::data`]).
const SAVED_PER_BEAD: usize = 32;

/// Position, orientation, velocity and angular velocity as 13 numbers.
fn kinematics_values(b: &BeadKinematics) -> [f64; 13] {
    let q = to_array(&b.quat);
    [
        b.pos.x, b.pos.y, b.pos.z, q[0], q[1], q[2], q[3], b.vel.x, b.vel.y, b.vel.z, b.omega.x,
        b.omega.y, b.omega.z,
    ]
}

/// The fibre node: cohesive-beam (L2020) and bead-spring (S2023) fibres; SPM phases, and FPD
/// phases for bead-spring fibres.
#[derive(Default)]
pub struct FibreComponent {
    run: Option<Run>,
}

struct Run {
    scene: SceneConfig,
    fibres: Vec<Fibre>,
    /// Per fibre, the watch over its beads reaching into each other (`self_overlap`).
    self_overlaps: Vec<SelfOverlap>,
    /// The `self_overlap` last measured, at the end of the last step.
    self_overlap: f64,
    /// The watch over beads of different fibres reaching into each other (`fibre_overlap`;
    /// `None` with one fibre), and its last value.
    fibre_overlaps: Option<FibreOverlap>,
    fibre_overlap: f64,
    /// The contact between fibres (`fibre.N.fibre_contact` on two fibres or more).
    fibre_contact: Option<FibreContact>,
    /// Where each fibre's beads start among all beads (one more entry: the total).
    offsets: Vec<usize>,
    total_beads: usize,
    /// How the fluid, if any, moves the fibres: SPM impulses are read in
    /// `FibreVelocities`; FPD runs `FibreForces` and `FibreAdvance` instead.
    coupling: Coupling,
    /// Read hydrodynamic impulses in `FibreVelocities` (SPM coupling).
    use_impulses: bool,
    /// The fibres' force buffers hold F(X) at the current positions.
    forces_current: bool,
    /// `Some(n)`: positions of step n advanced, velocities pending.
    pending: Option<u64>,
    /// The step of the last bead states published.
    published: u64,
    /// After `restore_state`: the step whose bead states to publish again.
    restored_publication: Option<u64>,
    states: Vec<BeadState>,
    impulses: Vec<BeadImpulse>,
    /// FPD: the bead forces published in `FibreForces`.
    forces: Vec<BeadForce>,
    /// FPD: the bead velocities read in `FibreAdvance`.
    velocities: Vec<BeadState>,
}

#[derive(Serialize, Deserialize)]
struct SavedState {
    format: String,
    beads_per_fibre: Vec<usize>,
    pending: Option<u64>,
    /// The step of the last bead states published (absent in states saved before it was
    /// kept: nothing is republished then).
    #[serde(default)]
    published: Option<u64>,
    /// Under FPD, each bead's held displacement (3 per bead, bit patterns; see
    /// `Fibre::hold_under_fpd`); empty in states saved before it was kept.
    #[serde(default)]
    held: Vec<u64>,
    /// Per bead: position (3), orientation (4), velocity (3), angular velocity (3), the
    /// previous step's hydrodynamic impulse (3) and angular impulse (3), and the same 13
    /// kinematic values at the start of the step (the corrector's, see `fibre.rs`), as the
    /// bit patterns of the f64 values.
    data: Vec<u64>,
}

impl FibreComponent {
    pub fn new() -> Self {
        Self::default()
    }

    /// The configured fibres (empty before `configure`).
    pub fn fibres(&self) -> &[Fibre] {
        self.run.as_ref().map_or(&[], |r| &r.fibres)
    }

    /// Mutable access to the fibres, e.g. to set an initial perturbation in a test. Marks
    /// the cached forces stale.
    pub fn fibres_mut(&mut self) -> &mut [Fibre] {
        match self.run.as_mut() {
            Some(r) => {
                r.forces_current = false;
                &mut r.fibres
            }
            None => &mut [],
        }
    }

    /// Current bead states, all fibres concatenated in order.
    pub fn bead_states(&self) -> Vec<BeadState> {
        let mut out = Vec::new();
        if let Some(r) = &self.run {
            fill_states(&r.fibres, &mut out);
        }
        out
    }

    fn run_mut(&mut self) -> Result<&mut Run, ComponentError> {
        self.run
            .as_mut()
            .ok_or_else(|| ComponentError::new("fibre-node: configure must come first"))
    }
}

fn fill_states(fibres: &[Fibre], out: &mut Vec<BeadState>) {
    out.clear();
    for f in fibres {
        for k in 0..f.len() {
            out.push(BeadState {
                position: f.pos[k].into(),
                orientation: to_array(&f.quat[k]),
                velocity: f.vel[k].into(),
                angular_velocity: f.omega[k].into(),
            });
        }
    }
}

/// The effects a scene's fibres make active.
fn active_effects(fibres: &[Fibre]) -> Vec<String> {
    let mut active = vec![effects::BEAM_ELASTICITY.to_string()];
    let any = |pred: &dyn Fn(&Fibre) -> bool| fibres.iter().any(pred);
    if any(&|f| matches!(f.model, Model::CohesiveBeam(_)) && !f.planar) {
        active.push(effects::TWIST.into());
    }
    if any(&|f| f.rotates) {
        active.push(effects::BEAD_ROTATION.into());
    }
    if any(&|f| !f.loads.is_empty()) {
        active.push(effects::EXTERNAL_LOADS.into());
    }
    if any(&|f| f.clamped.iter().any(|&c| c)) {
        active.push(effects::CLAMP.into());
    }
    if any(&|f| f.damping > 0.0) {
        active.push(effects::DAMPING.into());
    }
    active
}

impl Run {
    /// `fibre-forces` of step n (FPD): the beads' forces F^n, published for the lattice.
    fn fpd_forces(
        &mut self,
        step: u64,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        self.forces.clear();
        if let Some(c) = &mut self.fibre_contact {
            c.apply(&mut self.fibres);
        }
        for f in self.fibres.iter_mut() {
            f.fpd_forces();
            self.forces
                .extend(f.force.iter().map(|v| BeadForce { force: (*v).into() }));
        }
        exchange.publish_forces(Port::BeadForces, step, &self.forces)?;
        Ok(self.report(false))
    }

    /// `fibre-advance` of step n (FPD): R^{n+1} = R^n + dt V^{n+1} with the lattice's bead
    /// velocities of step n + 1.
    fn fpd_advance(
        &mut self,
        step: u64,
        exchange: &mut dyn Exchange,
    ) -> Result<(), ComponentError> {
        let header = exchange.read_states(Port::BeadVelocities, &mut self.velocities)?;
        if self.velocities.len() != self.total_beads {
            return Err(ComponentError(format!(
                "fibre-node: {} bead velocities received for {} beads",
                self.velocities.len(),
                self.total_beads
            )));
        }
        if header.step != step + 1 {
            return Err(ComponentError(format!(
                "fibre-node: fibre-advance of step {step} read bead velocities of \
                 step {} (expected {})",
                header.step,
                step + 1
            )));
        }
        let dt = self.scene.dt;
        let mut offset = 0;
        for f in self.fibres.iter_mut() {
            let n = f.len();
            f.fpd_advance(dt, &self.velocities[offset..offset + n]);
            offset += n;
        }
        Ok(())
    }

    /// `fibre-positions` of step n (SPM): the first half of the split step, positions to
    /// n + 1.
    fn advance_positions(&mut self, step: u64) -> Result<(), ComponentError> {
        if let Some(p) = self.pending {
            return Err(ComponentError(format!(
                "fibre-node: fibre-positions of step {step} requested while the \
                 velocities of step {p} are still pending"
            )));
        }
        let dt = self.scene.dt;
        match &mut self.fibre_contact {
            Some(c) => together::advance_positions(&mut self.fibres, c, dt),
            None => {
                for f in self.fibres.iter_mut() {
                    f.advance_positions(dt);
                }
            }
        }
        self.forces_current = true;
        self.pending = Some(step);
        Ok(())
    }

    /// `fibre-velocities` of step n (SPM): the second half, velocities to n + 1 with the
    /// fluid's impulses where the scene has a fluid.
    fn advance_velocities(
        &mut self,
        step: u64,
        exchange: &mut dyn Exchange,
    ) -> Result<(), ComponentError> {
        if self.pending != Some(step) {
            return Err(ComponentError(format!(
                "fibre-node: fibre-velocities of step {step} requested before \
                 fibre-positions of step {step}"
            )));
        }
        let impulses = if self.use_impulses {
            exchange.read_impulses(Port::BeadImpulses, &mut self.impulses)?;
            if self.impulses.len() != self.total_beads {
                return Err(ComponentError(format!(
                    "fibre-node: {} bead impulses received for {} beads",
                    self.impulses.len(),
                    self.total_beads
                )));
            }
            Some(&self.impulses[..])
        } else {
            None
        };
        let dt = self.scene.dt;
        match &mut self.fibre_contact {
            Some(c) => together::advance_velocities(
                &mut self.fibres,
                c,
                dt,
                impulses,
                &self.offsets,
                self.forces_current,
            ),
            None => {
                for (k, f) in self.fibres.iter_mut().enumerate() {
                    let (a, b) = (self.offsets[k], self.offsets[k + 1]);
                    f.advance_velocities(dt, impulses.map(|j| &j[a..b]), self.forces_current);
                }
            }
        }
        self.forces_current = true;
        self.pending = None;
        Ok(())
    }

    /// The run of `fibres` (set up from `scene`): the watches over overlaps, the contact
    /// between fibres (its forces at the start computed) and buffers for every bead.
    fn new(scene: SceneConfig, mut fibres: Vec<Fibre>) -> Self {
        let fpd = scene.coupling == Coupling::Fpd;
        let total_beads = fibres.iter().map(|f| f.len()).sum();
        let self_overlaps = fibres
            .iter()
            .zip(&scene.fibres)
            .map(|(f, cfg)| {
                let dims = if f.planar { 2 } else { 3 };
                SelfOverlap::new(f.len(), cfg.bead_radius, cfg.spacing, dims)
            })
            .collect();
        let dims = scene.dimensions as usize;
        let fibre_overlaps = FibreOverlap::new(
            &fibres
                .iter()
                .zip(&scene.fibres)
                .map(|(f, cfg)| (f.len(), cfg.bead_radius))
                .collect::<Vec<_>>(),
            scene.periodic_box,
            dims,
        );
        let mut fibre_contact = FibreContact::new(
            &fibres
                .iter()
                .zip(&scene.fibres)
                .map(|(f, cfg)| {
                    let k = cfg.fibre_contact.then_some(f.contact_stiffness);
                    (f.len(), cfg.bead_radius, k)
                })
                .collect::<Vec<_>>(),
            scene.periodic_box,
            dims,
        );
        if let Some(c) = &mut fibre_contact {
            together::compute_forces(&mut fibres, c);
        }
        let mut offsets = vec![0];
        for f in &fibres {
            offsets.push(offsets.last().copied().unwrap_or(0) + f.len());
        }
        Run {
            coupling: scene.coupling,
            use_impulses: scene.coupling == Coupling::Spm,
            scene,
            fibres,
            self_overlaps,
            self_overlap: 0.0,
            fibre_overlaps,
            fibre_overlap: 0.0,
            fibre_contact,
            offsets,
            total_beads,
            forces_current: true,
            pending: None,
            published: 0,
            restored_publication: None,
            states: Vec::with_capacity(total_beads),
            impulses: Vec::with_capacity(total_beads),
            forces: Vec::with_capacity(if fpd { total_beads } else { 0 }),
            velocities: Vec::with_capacity(if fpd { total_beads } else { 0 }),
        }
    }

    /// The phase's diagnostics. `step_ends`: the phase leaves the step's positions
    /// (fibre-velocities, fibre-advance), which `self_overlap` is measured at; the other
    /// phases report the value of the step before (fibre-positions' predicted positions
    /// are provisional, fibre-forces moves nothing), since the coordinator keeps the last
    /// phase's value of a step.
    fn report(&mut self, step_ends: bool) -> PhaseReport {
        let mut ke = 0.0;
        let mut e = crate::energies::Energies::default();
        let mut vmax: f64 = 0.0;
        let mut fmax: f64 = 0.0;
        for f in &self.fibres {
            ke += f.kinetic_energy();
            e += f.energies;
            vmax = vmax.max(f.max_speed());
            fmax = fmax.max(f.max_net_force());
        }
        // How far the deepest bead's sphere reaches past a wall's face (0 without walls).
        let mut overlap: f64 = 0.0;
        if let Some(faces) = self.scene.wall_faces {
            for (f, cfg) in self.fibres.iter().zip(&self.scene.fibres) {
                for p in &f.pos {
                    let [bottom, top] = overlaps(faces, cfg.bead_radius, p.y);
                    overlap = overlap.max(bottom).max(top);
                }
            }
        }
        // How deep two beads of one fibre reach into each other (`crate::self_overlap`).
        if step_ends {
            self.self_overlap = 0.0;
            for (f, w) in self.fibres.iter().zip(&mut self.self_overlaps) {
                self.self_overlap = self.self_overlap.max(w.measure(&f.pos));
            }
            if let Some(w) = &mut self.fibre_overlaps {
                self.fibre_overlap = w.measure(self.fibres.iter().map(|f| &f.pos[..]));
            }
        }
        let values = [
            ke,
            e.stretch,
            e.bend,
            e.twist,
            e.contact,
            e.total(),
            vmax,
            fmax,
            overlap,
            self.self_overlap,
            self.fibre_overlap,
        ];
        PhaseReport {
            diagnostics: DIAGNOSTICS
                .iter()
                .zip(values)
                .map(|(n, v)| (n.to_string(), v))
                .collect(),
            // Sums over the beads, a small part of a step: always full.
            detail: cosim::Detail::Full,
        }
    }

    /// Publish the bead states of `step` on `port`: `bead-positions` after fibre-positions,
    /// `bead-states` otherwise.
    fn publish(
        &mut self,
        step: u64,
        port: Port,
        exchange: &mut dyn Exchange,
    ) -> Result<(), ComponentError> {
        fill_states(&self.fibres, &mut self.states);
        exchange.publish_states(port, step, &self.states)?;
        if port == Port::BeadStates {
            self.published = step;
        }
        Ok(())
    }
}

impl Component for FibreComponent {
    fn describe(&self) -> ModelDescription {
        let len = "length";
        ModelDescription {
            name: "fibre-node".into(),
            version: env!("CARGO_PKG_VERSION").into(),
            summary: "Lagrangian fibres as chains of beads: L2020 cohesive beam (quaternions; \
                      stretch, bend, twist) and S2023 bead-spring, 2D or 3D"
                .into(),
            kind: "fibre".into(),
            models: vec!["cohesive-beam".into(), "bead-spring".into()],
            coupling_schemes: vec!["none".into(), "spm".into(), "fpd".into()],
            effects: vec![
                effects::BEAM_ELASTICITY.into(),
                effects::TWIST.into(),
                effects::BEAD_ROTATION.into(),
                effects::EXTERNAL_LOADS.into(),
                effects::CLAMP.into(),
                effects::DAMPING.into(),
            ],
            phases: vec![
                Phase::FibrePositions,
                Phase::FibreVelocities,
                Phase::FibreForces,
                Phase::FibreAdvance,
            ],
            parameters: vec![
                param("dimensions", "1", Some("3"), "2 (x-y plane, rotation about z, no twist) or 3"),
                param("time.dt", "time", None, "fluid (outer) time step; the fibre takes fibre.N.substeps internal steps per dt"),
                param("fibre.N.model", "1", None, "\"cohesive-beam\" (L2020) or \"bead-spring\" (S2023)"),
                param("fibre.N.beads", "1", None, "number of beads N_b (1: a single rigid particle)"),
                param("fibre.N.bead_radius", len, None, "bead radius r_b"),
                param("fibre.N.youngs_modulus", "mass / (length time^2)", None, "Young's modulus E; EI with I = pi r_b^4 / 4; a bead-spring fibre reads it only for the constants its table leaves out (k_s, k_b), and one given both needs none"),
                param("fibre.N.shear_modulus", "mass / (length time^2)", Some("E / 2.6"), "shear modulus G (torsion, cohesive beam in 3D); the default is E / (2 (1 + nu)) with Poisson's ratio nu = 0.3"),
                param("fibre.N.density", "mass / length^3", Some("1.0"), "bead density; 3D sphere m = rho 4/3 pi r^3, 2D disc of unit thickness m = rho pi r^2"),
                param("fibre.N.start", len, Some("[0.0, 0.0, 0.0]"), "position of bead 0"),
                param("fibre.N.centred", "1", Some("false"), "true: start such that the fibre's midpoint lies at the centre of the gap between the walls, y = (ny - 1) / 2, x = nx / 2 (z = nz / 2), as S2023 place it; excludes start"),
                param("fibre.N.direction", "1", Some("[1.0, 0.0, 0.0]"), "direction of the straight initial fibre (normalised; z = 0 in 2D)"),
                param("fibre.N.spacing", len, Some("2 bead_radius"), "initial and rest distance between neighbouring beads"),
                param("fibre.N.fibre_contact", "1", Some("false"), "true: its beads and those of every other fibre with the key repel while their spheres overlap (minimum image across the periodic box), with the smaller of the two fibres' axial bond stiffnesses; needs two such fibres and the same fibre.N.substeps on every fibre (off by default; without it fibres pass through each other: watch the fibre_overlap diagnostic)"),
                param("fibre.N.self_contact", "1", Some("false"), "true: beads that are not neighbours along the chain repel while their spheres overlap, with the fibre's axial bond stiffness (excluded volume; neither paper has it, so off by default; without it a soft fibre that folds or coils can pass through itself: watch the self_overlap diagnostic)"),
                param("fibre.N.wall_contact", "1", Some("false"), "true (scenes with walls): a bead whose sphere reaches past a wall's face is pushed back along the wall's normal, with the fibre's axial bond stiffness (frictionless; neither paper has it, so off by default; without it an SPM bead can sink into a wall slab: watch the wall_overlap diagnostic)"),
                param("fibre.N.initial_bend", len, Some("0.0"), "amplitude of an S-shaped initial offset across direction (one sine wave along the fibre): seeds buckling; the fibre is at rest but not stress-free"),
                param("fibre.N.clamp", "1", Some("[]"), "indices of clamped beads (negative counts from the end): fixed position and orientation; under fpd-lbm held in place by a proportional-integral force (its steady value is minus the drag)"),
                param("fibre.N.loads", "1", Some("[]"), "constant point loads on free beads (a clamped bead is refused): tables { bead, force, torque }"),
                param("fibre.N.loads.M.bead", "1", None, "bead index (negative counts from the end)"),
                param("fibre.N.loads.M.force", "mass length / time^2", Some("[0.0, 0.0, 0.0]"), "force, laboratory frame"),
                param("fibre.N.loads.M.torque", "mass length^2 / time^2", Some("[0.0, 0.0, 0.0]"), "torque, laboratory frame (cohesive beam only)"),
                param("fibre.N.damping", "1 / time", Some("0.0"), "damping rate c: F = -c m V, T = -c I Omega"),
                param("fibre.N.internal_damping", "time", Some("0.0"), "Kelvin-Voigt damping time tau of the bonds: internal loads tau dF/dt (a mode of frequency omega decays at tau omega^2 / 2; rigid motion is not damped)"),
                param("fibre.N.substeps", "1", Some("1"), "internal fibre steps per time.dt"),
                param("fibre.N.stretch_stiffness", "mass length^2 / time^2", Some("E pi r^2 l0"), "bead-spring k_s (spring stiffness k_s / l0^2)"),
                param("fibre.N.bending_stiffness", "mass length^2 / time^2", Some("E I / l0"), "bead-spring k_b (U_b = -k_b sum t_i+1 . t_i; 0: freely jointed)"),
                param("fibre.N.affinity", "1", Some("0.0"), "wetting affinity psi0 of the fibre (read by the fluid node)"),
                param("fibre.N.bending_number", "1", Some("none"), "bead-spring in a wall shear (fpd-lbm or spm): bending number K = 2 k_b / (eta_f gamma l_c^2) (S2023 eq. 18; 0: freely jointed), converted to k_b with fluid.viscosity, the wall shear gamma = (top - bottom) / H (H = ny under fpd-lbm, ny - 2 T between the spm slabs) and l_c = N d; excludes bending_stiffness; reported for every bead-spring fibre in a wall shear"),
                param("fibre.N.stretch_number", "1", Some("none"), "bead-spring in a wall shear (fpd-lbm or spm): stretch number K_s = k_s / (eta_f V0 l0) (S2023 section II C), converted to k_s with fluid.viscosity, the wall speed V0 = |top - bottom| / 2 and l0 = spacing; excludes stretch_stiffness; reported for every bead-spring fibre in a wall shear"),
                param("fibre.N.bead_spin", "1", Some("\"free\""), "bead-spring under spm: \"free\" (each bead spins with the fluid, a train of rollers) or \"chord\" (each bead turns with its bonds, the fluid's torque on it passed to its neighbours as couples: a solid fibre; in 3D each bead keeps a free spin about the chain's tangent)"),
                param("fibre.N.exchange", "1", Some("\"explicit\""), "SPM momentum exchange: \"explicit\" (the fluid's impulse added as it comes, L2020 eqs. 35-36; beads must be at least half as heavy as their profile's fluid) or \"implicit\" (the same impulse taken as a drag towards the profile's fluid velocity at the new bead velocity: momentum-conserving with the penalty, stable for light beads and stiff fibres; with one sub-step it moves a bead as the explicit exchange moves a bead of mass M + m_phi, the profile's fluid added to its inertia)"),
                param("fibre.N.bead_inertia", "1", Some("\"solid\""), "bead moment of inertia: \"solid\" (sharp disc or sphere, as fibre.N.density says) or \"profile\" (density times the moment of the bead's smoothed profile, SPM only); under SPM a bead whose profile fluid has 2 or more times its mass or moment of inertia is refused (explicit exchange limit)"),
                param("fibre.N.beam_forces", "1", Some("\"paper\""), "cohesive beam: \"paper\" (L2020 eqs. 11-24) or \"energy-consistent\" (the same to leading order, exactly conservative to third order in the bead angles)"),
            ],
            inputs: vec![
                PortDescription {
                    port: Port::BeadImpulses,
                    record: "BeadImpulse".into(),
                    description: "time-integrated hydrodynamic force and torque per bead, read \
                                  in fibre-velocities (SPM coupling)"
                        .into(),
                },
                PortDescription {
                    port: Port::BeadVelocities,
                    record: "BeadState".into(),
                    description: "bead velocities from the flow (S2023 eq. 5), read in \
                                  fibre-advance (FPD coupling)"
                        .into(),
                },
            ],
            outputs: vec![
                PortDescription {
                    port: Port::BeadStates,
                    record: "BeadState".into(),
                    description: "all beads, fibres in order, after configure (step 0) and \
                                  after fibre-velocities and fibre-advance (step n + 1)"
                        .into(),
                },
                PortDescription {
                    port: Port::BeadPositions,
                    record: "BeadState".into(),
                    description: "all beads, fibres in order: positions n + 1 with velocities \
                                  n, after fibre-positions (step n + 1; SPM coupling)"
                        .into(),
                },
                PortDescription {
                    port: Port::BeadForces,
                    record: "BeadForce".into(),
                    description: "force on each bead at the step's positions (S2023 eqs. \
                                  10-12 plus point loads), after fibre-forces (FPD coupling)"
                        .into(),
                },
            ],
            notes: vec![
                "sub-cycling: with fibre.N.substeps = n the fibre takes n internal steps of \
                 dt / n per fluid step (n position updates in fibre-positions with n - 1 \
                 internal velocity kicks in between, the last kick in fibre-velocities). \
                 With a fluid the step is a predictor-corrector: fibre-positions predicts the \
                 positions with the previous step's impulses spread over the sub-steps; \
                 fibre-velocities takes the step again from its start with the step's own \
                 impulses spread over the sub-steps and publishes the corrected positions \
                 and velocities"
                    .into(),
                "configure refuses a time step above the beam-stiffness limit \
                 (symplectic Euler, h omega_max < 2) and says how to fix it"
                    .into(),
                "FPD coupling (fluid.method = \"fpd-lbm\", S2023 section II C): fibre-forces \
                 publishes -dU/dR per bead; fibre-advance moves each bead by dt times the \
                 velocity the flow gave it (S2023 eq. 5), overdamped, without bead rotation. \
                 Only bead-spring fibres, one sub-step: the cohesive beam needs bead \
                 rotations, which FPD does not give. A clamped bead stays at its place, held \
                 by a proportional-integral force on the velocity the flow gives it (a \
                 dashpot plus a spring on the integrated velocity), so in a steady state the \
                 holding force is minus the fluid's force on it"
                    .into(),
            ],
        }
    }

    fn configure(
        &mut self,
        scene_toml: &str,
        exchange: &mut dyn Exchange,
    ) -> Result<Configured, ComponentError> {
        self.run = None;
        let scene = parse_scene(scene_toml).map_err(ComponentError)?;
        let mut fibres = Vec::with_capacity(scene.fibres.len());
        let mut limits = Vec::new();
        let mut derived = Vec::new();
        let mut notes = Vec::new();
        for (n, cfg) in scene.fibres.iter().enumerate() {
            let setup = fibre_setup::set_up(n, cfg, &scene).map_err(ComponentError)?;
            limits.extend(setup.limits);
            derived.extend(setup.derived);
            notes.extend(setup.notes);
            fibres.push(setup.fibre);
        }
        let effects = active_effects(&fibres);
        for (n, f) in fibres.iter().enumerate() {
            notes.extend(fibre_setup::rollers_note(n, f, scene.coupling));
        }
        if scene.coupling == Coupling::None {
            // With a fluid, the fluid node checks the start against its walls and box.
            let starts: Vec<(&[Vec3], f64)> = fibres
                .iter()
                .zip(&scene.fibres)
                .map(|(f, cfg)| (&f.pos[..], cfg.bead_radius))
                .collect();
            crate::fibre_overlap::check_coincident(&starts)
                .map_err(|e| ComponentError(format!("fibre-node: the fibres' start: {e}")))?;
        }
        let mut run = Run::new(scene, fibres);
        run.publish(0, Port::BeadStates, exchange)?;
        let configured = Configured {
            beads_per_fibre: run.fibres.iter().map(|f| f.len()).collect(),
            effects,
            time_step_limits: limits,
            derived,
            notes,
        };
        self.run = Some(run);
        Ok(configured)
    }

    fn run_phase(
        &mut self,
        step: u64,
        phase: Phase,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        let run = self.run_mut()?;
        let fpd_phase = matches!(phase, Phase::FibreForces | Phase::FibreAdvance);
        if fpd_phase != (run.coupling == Coupling::Fpd) {
            return Err(ComponentError(format!(
                "fibre-node: phase {phase} does not belong to the {} coupling of this scene \
                 (SPM: fibre-positions, fibre-velocities; FPD: fibre-forces, fibre-advance)",
                run.coupling.name()
            )));
        }
        match phase {
            Phase::FibreForces => return run.fpd_forces(step, exchange),
            Phase::FibreAdvance => run.fpd_advance(step, exchange)?,
            Phase::FibrePositions => run.advance_positions(step)?,
            Phase::FibreVelocities => run.advance_velocities(step, exchange)?,
            other => {
                return Err(ComponentError(format!(
                    "fibre-node does not serve phase {other} (it serves fibre-positions, \
                     fibre-velocities, fibre-forces and fibre-advance)"
                )))
            }
        }
        // The predicted positions go on a port of their own: the bead states of step n + 1
        // that fibre-velocities publishes are what the fluid's penalty and the coordinator read,
        // and a pipelined fibre node may predict the next step before they have.
        let port = if phase == Phase::FibrePositions {
            Port::BeadPositions
        } else {
            Port::BeadStates
        };
        run.publish(step + 1, port, exchange)?;
        Ok(run.report(phase != Phase::FibrePositions))
    }

    fn save_state(&self) -> Result<Vec<u8>, ComponentError> {
        let run = self
            .run
            .as_ref()
            .ok_or_else(|| ComponentError::new("fibre-node: nothing to save before configure"))?;
        let mut data = Vec::with_capacity(SAVED_PER_BEAD * run.total_beads);
        for f in &run.fibres {
            for k in 0..f.len() {
                let now = BeadKinematics {
                    pos: f.pos[k],
                    quat: f.quat[k],
                    vel: f.vel[k],
                    omega: f.omega[k],
                };
                let start = f.start.get(k).copied().unwrap_or(now);
                let (j, l) = (f.predicted_impulse[k], f.predicted_angular_impulse[k]);
                let vals = kinematics_values(&now)
                    .into_iter()
                    .chain([j.x, j.y, j.z, l.x, l.y, l.z])
                    .chain(kinematics_values(&start));
                data.extend(vals.map(|v| v.to_bits()));
            }
        }
        let saved = SavedState {
            format: STATE_FORMAT.into(),
            beads_per_fibre: run.fibres.iter().map(|f| f.len()).collect(),
            pending: run.pending,
            published: Some(run.published),
            held: run
                .fibres
                .iter()
                .flat_map(|f| f.held_displacement.iter())
                .flat_map(|d| [d.x, d.y, d.z])
                .map(f64::to_bits)
                .collect(),
            data,
        };
        serde_json::to_vec(&saved)
            .map_err(|e| ComponentError(format!("fibre-node: cannot serialise the state: {e}")))
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<(), ComponentError> {
        let saved: SavedState = serde_json::from_slice(state)
            .map_err(|e| ComponentError(format!("fibre-node: not a saved fibre state: {e}")))?;
        let run = self.run.as_mut().ok_or_else(|| {
            ComponentError::new(
                "fibre-node: configure with the same scene before restoring a state",
            )
        })?;
        if saved.format != STATE_FORMAT {
            return Err(ComponentError(format!(
                "fibre-node: saved state has format {:?}, expected {STATE_FORMAT:?}",
                saved.format
            )));
        }
        let have: Vec<usize> = run.fibres.iter().map(|f| f.len()).collect();
        if saved.beads_per_fibre != have || saved.data.len() != SAVED_PER_BEAD * run.total_beads {
            return Err(ComponentError(format!(
                "fibre-node: saved state has beads per fibre {:?}, the configured scene has {have:?}",
                saved.beads_per_fibre
            )));
        }
        let mut it = saved.data.iter().map(|b| f64::from_bits(*b));
        let mut next = || it.next().unwrap_or(0.0);
        let kinematics = |next: &mut dyn FnMut() -> f64| BeadKinematics {
            pos: Vec3::new(next(), next(), next()),
            quat: from_array([next(), next(), next(), next()]),
            vel: Vec3::new(next(), next(), next()),
            omega: Vec3::new(next(), next(), next()),
        };
        for f in run.fibres.iter_mut() {
            let mid_step = saved.pending.is_some() && f.hydrodynamic && f.substeps > 1;
            f.start.clear();
            for k in 0..f.len() {
                let now = kinematics(&mut next);
                f.pos[k] = now.pos;
                f.quat[k] = now.quat;
                f.vel[k] = now.vel;
                f.omega[k] = now.omega;
                f.predicted_impulse[k] = Vec3::new(next(), next(), next());
                f.predicted_angular_impulse[k] = Vec3::new(next(), next(), next());
                let start = kinematics(&mut next);
                if mid_step {
                    f.start.push(start);
                }
            }
            f.compute_forces();
        }
        if let Some(c) = &mut run.fibre_contact {
            together::compute_forces(&mut run.fibres, c);
        }
        if saved.held.len() == 3 * run.total_beads {
            let mut held = saved.held.iter().map(|b| f64::from_bits(*b));
            for f in run.fibres.iter_mut() {
                for d in f.held_displacement.iter_mut() {
                    *d = Vec3::new(
                        held.next().unwrap_or(0.0),
                        held.next().unwrap_or(0.0),
                        held.next().unwrap_or(0.0),
                    );
                }
            }
        }
        run.forces_current = true;
        run.pending = saved.pending;
        run.restored_publication = saved.published;
        Ok(())
    }

    fn publish_restored(&mut self, exchange: &mut dyn Exchange) -> Result<(), ComponentError> {
        match self.run.as_mut() {
            Some(run) => match run.restored_publication.take() {
                Some(step) => run.publish(step, Port::BeadStates, exchange),
                None => Ok(()),
            },
            None => Ok(()),
        }
    }
}

/// What the FPD coupling cannot carry, refused before step 0 with the reason.
#[cfg(test)]
mod tests {
    use super::*;
    use crate::quaternion::rotation_angle;
    use cosim::InProcessExchange;
    use std::f64::consts::PI;

    /// Configure, and return the component with the exchange it publishes to. The SPM
    /// scenes below give their beads of radius 1-2 a thin profile (`fluid.xi = 0.1`): with the
    /// default xi = 1 the profile's fluid would outweigh such small beads several times over,
    /// which the explicit-exchange check refuses (`spm_exchange`).
    fn configure(scene: &str) -> (FibreComponent, InProcessExchange, Configured) {
        let mut c = FibreComponent::new();
        let mut x = InProcessExchange::new();
        let cfg = c.configure(scene, &mut x).unwrap_or_else(|e| panic!("{e}"));
        (c, x, cfg)
    }

    /// Largest stable dt of a scene (configure with a tiny dt and read the limit back).
    fn dt_limit(scene_without_time: &str) -> f64 {
        let (_, _, cfg) = configure(&format!("[time]\ndt = 1e-12\n{scene_without_time}"));
        cfg.time_step_limits
            .iter()
            .map(|(_, v)| *v)
            .fold(f64::INFINITY, f64::min)
    }

    fn step(c: &mut FibreComponent, x: &mut InProcessExchange, n: u64) -> PhaseReport {
        c.run_phase(n, Phase::FibrePositions, x).unwrap();
        c.run_phase(n, Phase::FibreVelocities, x).unwrap()
    }

    fn diag(r: &PhaseReport, name: &str) -> f64 {
        r.diagnostics.iter().find(|(n, _)| n == name).unwrap().1
    }

    /// Run a damped scene until the largest net force is below `tol`; return the component
    /// and the last report.
    fn to_rest(body: &str, tol: f64) -> (FibreComponent, PhaseReport) {
        let dt = 0.9 * dt_limit(body);
        let (mut c, mut x, _) = configure(&format!("[time]\ndt = {dt}\n{body}"));
        let mut r = PhaseReport::default();
        for n in 0..5_000_000 {
            r = step(&mut c, &mut x, n);
            if n % 100 == 99 && diag(&r, "max_net_force") < tol {
                eprintln!("  at rest after {} steps", n + 1);
                return (c, r);
            }
        }
        panic!("not at rest: {r:?}");
    }

    /// Fundamental bending frequency of a cantilever: 1.875² sqrt(EI / (mu L⁴)).
    fn cantilever_omega1(ei: f64, mass: f64, l0: f64, length: f64) -> f64 {
        1.875f64.powi(2) * (ei / (mass / l0 * length.powi(4))).sqrt()
    }

    struct Cantilever {
        dims: u8,
        model: &'static str,
        beads: usize,
        alpha: f64,
        clamp: &'static str,
        /// Load direction (unit, perpendicular to e_x).
        dir: [f64; 3],
        forces: &'static str,
    }

    /// Tip deflection over L (L = 2 (N_b − 1) r_b), the tip rotation, and the length.
    fn cantilever(cfg: &Cantilever) -> (f64, f64, f64) {
        let (r, e, rho): (f64, f64, f64) = (1.0, 1.0, 1.0);
        let ei = e * PI * r.powi(4) / 4.0;
        let length = 2.0 * (cfg.beads - 1) as f64 * r;
        let p = cfg.alpha * ei / (length * length);
        let (m, _) = crate::fibre::bead_mass_inertia(rho, r, cfg.dims == 2);
        let w1 = cantilever_omega1(ei, m, 2.0 * r, length);
        let body = format!(
            "dimensions = {}\n[[fibre]]\nmodel = \"{}\"\nbeads = {}\nbead_radius = {r}\nyoungs_modulus = {e}\ndensity = {rho}\nclamp = {}\ndamping = {}\nloads = [{{ bead = -1, force = [{}, {}, {}] }}]\n{}\n",
            cfg.dims,
            cfg.model,
            cfg.beads,
            cfg.clamp,
            2.0 * w1,
            p * cfg.dir[0],
            p * cfg.dir[1],
            p * cfg.dir[2],
            cfg.forces,
        );
        let (c, _) = to_rest(&body, 1e-9 * p);
        let f = &c.fibres()[0];
        let tip = f.pos[f.len() - 1] - f.pos[0];
        let defl = tip.y * cfg.dir[1] + tip.z * cfg.dir[2];
        (defl / length, rotation_angle(&f.quat[f.len() - 1]), length)
    }

    #[test]
    fn small_deflection_cantilever_2d_matches_alpha_over_3() {
        for beads in [5, 10] {
            let (d, _, _) = cantilever(&Cantilever {
                dims: 2,
                model: "cohesive-beam",
                beads,
                alpha: 0.1,
                clamp: "[0]",
                dir: [0.0, -1.0, 0.0],
                forces: "",
            });
            let rel = (d - 0.1 / 3.0).abs() / (0.1 / 3.0);
            eprintln!(
                "cohesive beam 2D N_b = {beads}: delta/L = {d:.6}, alpha/3 = {:.6}, rel {rel:.2e}",
                0.1 / 3.0
            );
            assert!(rel < 0.02);
        }
    }

    /// Elastica reference (REFERENCE.md §1; recomputed by shooting to 6 digits):
    /// alpha, delta_v / L, tip rotation.
    const ELASTICA: [(f64, f64, f64); 4] = [
        (1.0, 0.301721, 0.461352),
        (2.0, 0.493457, 0.781750),
        (5.0, 0.713792, 1.215368),
        (10.0, 0.810609, 1.430286),
    ];

    #[test]
    fn large_deflection_cantilever_converges_to_the_elastica() {
        // The error falls as 1/N_b² (L2020: N_b >= 10 needed for large deflections).
        for (beads, tol) in [(10, 0.012), (20, 0.003)] {
            for (alpha, dv, rot) in ELASTICA {
                let (d, r, _) = cantilever(&Cantilever {
                    dims: 2,
                    model: "cohesive-beam",
                    beads,
                    alpha,
                    clamp: "[0]",
                    dir: [0.0, -1.0, 0.0],
                    forces: "",
                });
                let (ed, er) = ((d - dv) / dv, (r - rot) / rot);
                eprintln!("N_b {beads} alpha {alpha}: delta_v/L {d:.5} ({ed:+.2e}), tip rotation {r:.5} ({er:+.2e})");
                assert!(ed.abs() < tol && er.abs() < tol);
            }
        }
    }

    #[test]
    fn bead_spring_cantilever_matches_the_discrete_beam() {
        // Clamping beads 0 and 1 clamps the first tangent. Joint k (bead k = 1..N-2) is a
        // rotational spring k_b = E I / l0 carrying the moment P (N − 1 − k) l0, so
        // delta = P l0³ M (M + 1) (2M + 1) / (6 E I), M = N_b − 2, i.e. P L³ / (3 E I) with
        // L³ = l0³ M (M + 1)(2M + 1) / 2 ≈ ((N_b − 3/2) l0)³: the effective length runs
        // from the middle of the clamped segment to the tip bead.
        for (beads, tol_eff) in [(5, 0.025), (10, 0.006), (20, 0.003)] {
            let (d, _, length) = cantilever(&Cantilever {
                dims: 2,
                model: "bead-spring",
                beads,
                alpha: 0.1,
                clamp: "[0, 1]",
                dir: [0.0, -1.0, 0.0],
                forces: "",
            });
            let (ei, l0): (f64, f64) = (PI / 4.0, 2.0);
            let p = 0.1 * ei / (length * length);
            let delta = d * length;
            let m = beads as f64 - 2.0;
            let discrete = p * l0.powi(3) * m * (m + 1.0) * (2.0 * m + 1.0) / (6.0 * ei);
            let l_eff = (beads as f64 - 1.5) * l0;
            let continuum = p * l_eff.powi(3) / (3.0 * ei);
            eprintln!(
                "bead-spring N_b {beads}: delta / discrete {:.5}, delta / (P L_eff³/3EI) {:.5}, delta / (P L³/3EI) with L = (N_b-1) l0 {:.5}",
                delta / discrete,
                delta / continuum,
                delta / (p * length.powi(3) / (3.0 * ei))
            );
            // the remaining 0.1 % is the geometric nonlinearity at alpha = 0.1
            assert!((delta / discrete - 1.0).abs() < 2e-3);
            assert!((delta / continuum - 1.0).abs() < tol_eff);
        }
    }

    #[test]
    fn out_of_plane_cantilever_equals_in_plane() {
        let run = |dir| {
            cantilever(&Cantilever {
                dims: 3,
                model: "cohesive-beam",
                beads: 10,
                alpha: 0.1,
                clamp: "[0]",
                dir,
                forces: "",
            })
        };
        let (dy, ry, _) = run([0.0, -1.0, 0.0]);
        let (dz, rz, _) = run([0.0, 0.0, -1.0]);
        eprintln!("3D: in-plane {dy:.12}, out-of-plane {dz:.12}");
        assert!((dy - dz).abs() <= 1e-9 * dy);
        assert!((ry - rz).abs() <= 1e-9 * ry);
        assert!((dy - 0.1 / 3.0).abs() < 0.02 * 0.1 / 3.0);
    }

    #[test]
    fn torsion_matches_tl_over_gj() {
        for (beads, phi) in [(5, 0.05), (10, 0.05), (10, 1.0)] {
            let (r, e, rho): (f64, f64, f64) = (1.0, 1.0, 1.0);
            let g = e / 2.6;
            let j = PI * r.powi(4) / 2.0;
            let length = 2.0 * (beads - 1) as f64 * r;
            let t = phi * g * j / length;
            let (_, inertia) = crate::fibre::bead_mass_inertia(rho, r, false);
            let w1 = PI / (2.0 * length) * (g * j * 2.0 * r / inertia).sqrt();
            let body = format!(
                "[[fibre]]\nmodel = \"cohesive-beam\"\nbeads = {beads}\nbead_radius = {r}\nyoungs_modulus = {e}\ndensity = {rho}\nclamp = [0]\ndamping = {}\nloads = [{{ bead = -1, torque = [{t}, 0, 0] }}]\n",
                2.0 * w1
            );
            let dt = 0.9 * dt_limit(&body);
            let (mut c, mut x, _) = configure(&format!("[time]\ndt = {dt}\n{body}"));
            let mut n = 0;
            loop {
                let rep = step(&mut c, &mut x, n);
                n += 1;
                if n % 100 == 0 && diag(&rep, "kinetic_energy") < 1e-24 * t * phi {
                    break;
                }
                assert!(n < 2_000_000, "not at rest");
            }
            let f = &c.fibres()[0];
            let q = f.quat[beads - 1];
            let twist = 2.0 * q.i.atan2(q.w);
            let rel = (twist - phi).abs() / phi;
            eprintln!("torsion N_b {beads}: twist {twist:.6} vs T L / (G J) = {phi} ({rel:.1e}) after {n} steps");
            assert!(rel < 0.02);
            // pure twist: the axis stays straight
            assert!((f.pos[beads - 1] - f.pos[0] - Vec3::new(length, 0.0, 0.0)).norm() < 1e-9);
        }
    }

    fn bits(states: &[BeadState]) -> Vec<u64> {
        states
            .iter()
            .flat_map(|s| {
                s.position
                    .iter()
                    .chain(&s.orientation)
                    .chain(&s.velocity)
                    .chain(&s.angular_velocity)
                    .map(|v| v.to_bits())
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    #[test]
    fn save_restore_is_bit_identical() {
        let scene = "[time]\ndt = 0.05\n[[fibre]]\nmodel = \"cohesive-beam\"\nbeads = 8\nbead_radius = 1\nyoungs_modulus = 1\nclamp = [0]\ndamping = 0.01\nsubsteps = 3\nloads = [{ bead = -1, force = [0, -0.01, 0.005], torque = [0.002, 0, 0] }]\n[[fibre]]\nmodel = \"bead-spring\"\nbeads = 5\nbead_radius = 1\nyoungs_modulus = 1\nstart = [0, 10, 0]\nloads = [{ bead = 2, force = [0.001, 0.01, 0] }]\n";
        let (mut a, mut xa, _) = configure(scene);
        let mut saved = Vec::new();
        let mut saved_mid = Vec::new();
        for n in 0..200 {
            if n == 100 {
                saved = a.save_state().unwrap();
            }
            a.run_phase(n, Phase::FibrePositions, &mut xa).unwrap();
            if n == 150 {
                saved_mid = a.save_state().unwrap();
            }
            a.run_phase(n, Phase::FibreVelocities, &mut xa).unwrap();
        }
        let end = bits(&a.bead_states());
        // restore at a step boundary
        let (mut b, mut xb, _) = configure(scene);
        b.restore_state(&saved).unwrap();
        let mut last = PhaseReport::default();
        for n in 100..200 {
            last = step(&mut b, &mut xb, n);
        }
        assert_eq!(bits(&b.bead_states()), end);
        let mut out = Vec::new();
        xb.read_states(Port::BeadStates, &mut out).unwrap();
        assert_eq!(bits(&out), end);
        assert!(diag(&last, "kinetic_energy") > 0.0);
        // restore between the two phases of a step
        let (mut c, mut xc, _) = configure(scene);
        c.restore_state(&saved_mid).unwrap();
        assert!(c.run_phase(150, Phase::FibrePositions, &mut xc).is_err());
        c.run_phase(150, Phase::FibreVelocities, &mut xc).unwrap();
        for n in 151..200 {
            step(&mut c, &mut xc, n);
        }
        assert_eq!(bits(&c.bead_states()), end);
        // a state from another scene is refused
        let (mut d, _, _) = configure(&scene.replace("beads = 8", "beads = 9"));
        let e = d.restore_state(&saved).unwrap_err();
        assert!(e.0.contains("beads per fibre"), "{e}");
        assert!(d.restore_state(b"not json").is_err());
    }

    /// With a fluid and sub-steps the step is a predictor and a corrector (`fibre.rs`): a
    /// state saved between them, or at a step boundary, carries the start state and the
    /// predicted impulses, and the restored run continues bit for bit.
    #[test]
    fn save_restore_with_fluid_impulses_is_bit_identical() {
        let scene =
            "dimensions = 2\n[time]\ndt = 0.1\n[fluid]\nmethod = \"spm\"\nxi = 0.1\n[[fibre]]\n\
                     model = \"cohesive-beam\"\nbeads = 5\nbead_radius = 1\nyoungs_modulus = 1\n\
                     substeps = 3\n";
        let impulses = |n: u64| -> Vec<BeadImpulse> {
            (0..5u64)
                .map(|k| BeadImpulse {
                    impulse: [
                        1e-3 * ((n + k) as f64).sin(),
                        1e-3 * ((n * k) as f64).cos(),
                        0.0,
                    ],
                    angular_impulse: [0.0, 0.0, 1e-4 * (k as f64 - 2.0) * (n as f64).cos()],
                })
                .collect()
        };
        let velocities = |c: &mut FibreComponent, x: &mut InProcessExchange, n: u64| {
            x.publish_impulses(Port::BeadImpulses, n + 1, &impulses(n))
                .unwrap();
            c.run_phase(n, Phase::FibreVelocities, x).unwrap();
        };
        let (mut a, mut xa, _) = configure(scene);
        let (mut saved, mut saved_mid) = (Vec::new(), Vec::new());
        for n in 0..100 {
            if n == 40 {
                saved = a.save_state().unwrap();
            }
            a.run_phase(n, Phase::FibrePositions, &mut xa).unwrap();
            if n == 60 {
                saved_mid = a.save_state().unwrap();
            }
            velocities(&mut a, &mut xa, n);
        }
        let end = bits(&a.bead_states());
        let (mut b, mut xb, _) = configure(scene);
        b.restore_state(&saved).unwrap();
        for n in 40..100 {
            b.run_phase(n, Phase::FibrePositions, &mut xb).unwrap();
            velocities(&mut b, &mut xb, n);
        }
        assert_eq!(bits(&b.bead_states()), end);
        let (mut c, mut xc, _) = configure(scene);
        c.restore_state(&saved_mid).unwrap();
        velocities(&mut c, &mut xc, 60);
        for n in 61..100 {
            c.run_phase(n, Phase::FibrePositions, &mut xc).unwrap();
            velocities(&mut c, &mut xc, n);
        }
        assert_eq!(bits(&c.bead_states()), end);
    }

    #[test]
    fn refuses_a_time_step_above_the_beam_stiffness_limit() {
        let body = "[[fibre]]\nmodel = \"cohesive-beam\"\nbeads = 10\nbead_radius = 1\nyoungs_modulus = 100\n";
        let limit = dt_limit(body);
        let mut c = FibreComponent::new();
        let mut x = InProcessExchange::new();
        let e = c
            .configure(&format!("[time]\ndt = {}\n{body}", 2.5 * limit), &mut x)
            .unwrap_err();
        eprintln!("{e}");
        for want in [
            "beam stiffness",
            "time.dt",
            "fibre.0.substeps",
            "lower time.dt",
            "at least 3",
        ] {
            assert!(e.0.contains(want), "missing {want:?} in: {e}");
        }
        // the advice works
        let ok = format!("[time]\ndt = {}\n{body}substeps = 3\n", 2.5 * limit);
        let cfg = c.configure(&ok, &mut x).unwrap();
        assert!((cfg.time_step_limits[0].1 - 3.0 * limit).abs() < 1e-12 * limit);
        // a parse error reaches the user as is
        let e = c
            .configure(&format!("[time]\ndt = 1e-9\n{body}clamp = [12]\n"), &mut x)
            .unwrap_err();
        assert_eq!(
            e.0,
            "fibre.0.clamp: bead index 12 is out of range for a fibre of 10 beads (expected -10..=9)"
        );
        assert!(c.run_phase(0, Phase::FibrePositions, &mut x).is_err());
    }

    #[test]
    fn effects_derived_values_and_initial_publication() {
        let base = "[time]\ndt = 1e-3\n[[fibre]]\nmodel = \"MODEL\"\nbeads = 4\nbead_radius = 2\nyoungs_modulus = 3\n";
        let effects_of = |scene: &str| configure(scene).2.effects;
        let cb = base.replace("MODEL", "cohesive-beam");
        let bs = base.replace("MODEL", "bead-spring");
        assert_eq!(
            effects_of(&cb),
            ["beam-elasticity", "twist", "bead-rotation"]
        );
        assert_eq!(
            effects_of(&format!("dimensions = 2\n{cb}")),
            ["beam-elasticity", "bead-rotation"]
        );
        assert_eq!(effects_of(&bs), ["beam-elasticity"]);
        assert_eq!(
            effects_of(&format!("{bs}[fluid]\nmethod = \"spm\"\nxi = 0.1\n")),
            ["beam-elasticity", "bead-rotation"]
        );
        assert_eq!(
            effects_of(&format!(
                "{cb}clamp = [0]\ndamping = 0.1\nloads = [{{ bead = -1, force = [0, 1, 0] }}]\n"
            )),
            [
                "beam-elasticity",
                "twist",
                "bead-rotation",
                "external-loads",
                "clamp",
                "damping"
            ]
        );
        // zero loads are no loads
        assert!(!effects_of(&format!("{cb}loads = [{{ bead = 1 }}]\n"))
            .contains(&"external-loads".to_string()));

        let (_, mut x, cfg) = configure(&cb);
        assert_eq!(cfg.beads_per_fibre, vec![4]);
        let get = |k: &str| cfg.derived.iter().find(|(n, _)| n == k).unwrap().1;
        assert_eq!(get("fibre.0.length"), 12.0);
        assert!((get("fibre.0.bending_rigidity") - 3.0 * PI * 16.0 / 4.0).abs() < 1e-12);
        assert!((get("fibre.0.bead_mass") - 4.0 / 3.0 * PI * 8.0).abs() < 1e-12);
        assert_eq!(cfg.time_step_limits[0].0, "beam stiffness (fibre.0)");
        let mut out = Vec::new();
        let h = x.read_states(Port::BeadStates, &mut out).unwrap();
        assert_eq!(h.step, 0);
        assert_eq!(out.len(), 4);
        assert_eq!(out[3].position, [12.0, 0.0, 0.0]);
        assert_eq!(out[3].orientation, [1.0, 0.0, 0.0, 0.0]);
    }

    /// S2023's K = 2 k_b / (eta gamma l_c^2) is reported for both models in a wall shear,
    /// with k_b = E I / l0 for the cohesive beam: a beam and a bead-spring chain of the same
    /// modulus report one K; walls at -+0.05 across a gap of 160 between SPM slabs of 4
    /// (gamma = 6.25e-4), eta = 2/3, l_c = 80.
    #[test]
    fn both_models_report_one_bending_number_for_one_rigidity() {
        let scene = |model: &str| {
            format!(
                "dimensions = 2\n[time]\ndt = 1e-3\n[fluid]\nmethod = \"spm\"\ngrid = [200, 168]\n\
                 viscosity = 0.6666666666666666\nxi = 0.1\n[walls]\nvelocity = [-0.05, 0.05]\n\
                 [[fibre]]\nmodel = \"{model}\"\nbeads = 10\nbead_radius = 4\n\
                 youngs_modulus = 0.17507\n"
            )
        };
        let k = |model: &str| {
            let (_, _, cfg) = configure(&scene(model));
            cfg.derived
                .iter()
                .find(|(n, _)| n == "fibre.0.bending_number")
                .unwrap_or_else(|| panic!("{model}: no bending number"))
                .1
        };
        let (beam, chain) = (k("cohesive-beam"), k("bead-spring"));
        // E I = E pi r^4 / 4 = 35.2, k_b = E I / 8 = 4.4: K = 4.4 / (0.5 x 2/3 x 6.25e-4 x 6400).
        let want =
            0.17507 * std::f64::consts::PI * 256.0 / 4.0 / 8.0 / (2.0 / 3.0 * 6.25e-4 * 3200.0);
        assert!((beam - want).abs() < 1e-12 * want, "{beam} vs {want}");
        assert!((chain - beam).abs() < 1e-12 * want, "{chain} vs {beam}");
    }

    #[test]
    fn phases_reports_and_impulses() {
        let scene = "dimensions = 2\n[time]\ndt = 1e-3\n[fluid]\nmethod = \"spm\"\nxi = 0.1\n[[fibre]]\nmodel = \"cohesive-beam\"\nbeads = 3\nbead_radius = 1\nyoungs_modulus = 1\n[[fibre]]\nmodel = \"bead-spring\"\nbeads = 2\nbead_radius = 1\nyoungs_modulus = 1\n";
        let (mut c, mut x, _) = configure(scene);
        let mut fluid = x.clone();
        assert!(c.run_phase(0, Phase::FibreVelocities, &mut x).is_err());
        assert!(c.run_phase(0, Phase::FluidPenalty, &mut x).is_err());
        assert!(c.run_phase(0, Phase::FibreForces, &mut x).is_err());
        let r = c.run_phase(0, Phase::FibrePositions, &mut x).unwrap();
        let names: Vec<&str> = r.diagnostics.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, DIAGNOSTICS);
        // no impulses published yet: a clear error
        let e = c.run_phase(0, Phase::FibreVelocities, &mut x).unwrap_err();
        assert!(e.0.contains("bead-impulses"), "{e}");
        // wrong count
        fluid
            .publish_impulses(Port::BeadImpulses, 1, &[BeadImpulse::default(); 4])
            .unwrap();
        assert!(c.run_phase(0, Phase::FibreVelocities, &mut x).is_err());
        // impulses change the velocities by J/m (the fibres are straight and unloaded);
        // out-of-plane parts are dropped in 2D
        let mut j = [BeadImpulse::default(); 5];
        j[1].impulse = [0.3, -0.2, 7.0];
        j[1].angular_impulse = [1.0, 2.0, 0.5];
        j[4].impulse = [0.0, 1.0, 0.0];
        j[4].angular_impulse = [0.0, 0.0, 0.25];
        fluid.publish_impulses(Port::BeadImpulses, 1, &j).unwrap();
        let r = c.run_phase(0, Phase::FibreVelocities, &mut x).unwrap();
        let mut out = Vec::new();
        let h = x.read_states(Port::BeadStates, &mut out).unwrap();
        assert_eq!(h.step, 1);
        let (m, i) = crate::fibre::bead_mass_inertia(1.0, 1.0, true);
        let close = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() < 1e-15);
        assert!(close(out[1].velocity, [0.3 / m, -0.2 / m, 0.0]));
        assert!(close(out[1].angular_velocity, [0.0, 0.0, 0.5 / i]));
        assert!(close(out[4].velocity, [0.0, 1.0 / m, 0.0]));
        // bead-spring beads turn freely under hydrodynamic torque when a fluid is present
        assert!(close(out[4].angular_velocity, [0.0, 0.0, 0.25 / i]));
        assert!(diag(&r, "max_speed") > 0.0);
        assert_eq!(diag(&r, "max_net_force"), 0.0);
    }

    /// Under SPM: beads whose profile's fluid outweighs them are refused (here r_b = 2 with
    /// the default xi = 1, xi_c = 3 in 2D: inertia ratio 3.66, mass ratio 1.37 at density 1);
    /// a fully clamped fibre is not; the profile's inertia plus a density of 2 passes (ratios
    /// 0.5 and 0.68).
    #[test]
    fn light_beads_under_spm_are_refused_unless_clamped_or_given_the_profile_inertia() {
        let scene = |extra: &str| {
            format!(
                "dimensions = 2\n[time]\ndt = 1e-3\n[fluid]\nmethod = \"spm\"\n[[fibre]]\n\
                 model = \"cohesive-beam\"\nbeads = 3\nbead_radius = 2\nyoungs_modulus = 1\n{extra}"
            )
        };
        let refuse = |extra: &str| {
            let mut x = InProcessExchange::new();
            FibreComponent::new()
                .configure(&scene(extra), &mut x)
                .unwrap_err()
                .0
        };
        let e = refuse("");
        assert!(
            e.contains("too light") && e.contains("moment of inertia"),
            "{e}"
        );
        configure(&scene("clamp = [0, 1, 2]\n"));
        let e = refuse("clamp = [0]\n");
        assert!(e.contains("too light"), "{e}");
        let (_, _, cfg) = configure(&scene("density = 2.0\nbead_inertia = \"profile\"\n"));
        let ratio = |k: &str| {
            cfg.derived
                .iter()
                .find(|(n, _)| n == k)
                .map(|(_, v)| *v)
                .unwrap()
        };
        assert!((ratio("fibre.0.profile_to_bead_inertia") - 0.5).abs() < 1e-12);
        assert!(ratio("fibre.0.profile_to_bead_mass") < 2.0);
    }

    #[test]
    fn description() {
        let d = FibreComponent::new().describe();
        assert_eq!(d.name, "fibre-node");
        assert_eq!(d.kind, "fibre");
        assert_eq!(
            d.phases,
            vec![
                Phase::FibrePositions,
                Phase::FibreVelocities,
                Phase::FibreForces,
                Phase::FibreAdvance
            ]
        );
        assert_eq!(d.inputs[0].port, Port::BeadImpulses);
        assert_eq!(d.outputs[0].port, Port::BeadStates);
        for k in [
            "fibre.N.youngs_modulus",
            "fibre.N.clamp",
            "fibre.N.loads",
            "fibre.N.substeps",
            "time.dt",
            "fibre.N.beam_forces",
        ] {
            assert!(d.parameters.iter().any(|p| p.key == k), "{k}");
        }
        assert!(d.render().contains("sub-cycling"));
    }
}
