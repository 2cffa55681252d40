//! `fluid.method = "fpd-lbm"`: the fluid node's FPD phase on the MRT lattice (S2023 section
//! II C; DESIGN.md, "FPD coupling").
//!
//! One phase per step, `fluid-lattice-step` (step n): read the bead positions R^n
//! ([`Port::BeadStates`]) and forces F^n ([`Port::BeadForces`]), place the profiles and write
//! the viscosity field and the force density (S2023 eqs. 1, 2, 4; [`FpdCoupling::apply`]),
//! take one lattice step to v^{n+1}, and publish the bead velocities V^{n+1} (eq. 5) on
//! [`Port::BeadVelocities`] with step n+1. The fibre node then moves the beads,
//! R^{n+1} = R^n + dt V^{n+1}.
//!
//! Units are lattice units: grid spacing 1 and `time.dt` = 1 (refused otherwise, so a scene
//! cannot silently mean another time step). The lattice is `fluid.grid = [nx, ny]`, periodic
//! in x; with `walls.velocity = [bottom, top]` the bounce-back walls lie at y = -1/2 and
//! y = ny - 1/2 (gap H = ny), otherwise y is periodic.
use crate::fpd::{FpdConfig, FpdCoupling};
use crate::mrt_d2q9::{MrtConfig, MrtD2q9, YBoundary};
use crate::start_geometry::{StartBox, StartCheck, WallFaces};
use cosim::scene_keys::Num;
use cosim::scene_keys::{self, deserialize_at};
use cosim::{BeadForce, BeadState, ComponentError, Configured, Exchange, PhaseReport, Port};
use serde::Deserialize;

mod uniform_stream;
pub use uniform_stream::{UniformStream, DEFAULT_SPONGE_RATE};

/// Largest accepted wall Mach number |u_w| / c_s (c_s = 1/sqrt 3): the lattice's
/// compressibility error grows as Ma^2, and S2023-type runs stay far below this.
pub const MAX_WALL_MACH: f64 = 0.3;
/// A run stops when the flow's Mach number exceeds this: the lattice no longer carries it.
pub const ABORT_MACH: f64 = 0.7;
/// Largest accepted cell Reynolds number `max|u| dx / nu` (max|u| the fastest wall or
/// stream, nu the fluid's kinematic viscosity). Measured on this lattice (its rates
/// `s_e = s_eps = 1.1` and `s_q` tied to `s_nu`): a cylinder held in a uniform stream
/// (`configs/fpd/cylinder_drag.toml`, r_eta 500) runs 16 000-30 000 steps at a cell Reynolds
/// number of 8 for U = 0.025, 0.05 and 0.1 and d = 4 and 5, and blows up at 8.75 (step
/// 15 553), 9 and 10 (within 1 000-5 000 steps) whatever U, d or tau; a Couette flow without
/// beads runs at 10 and blows up at 12. It is a limit on u / (tau - 1/2), not on tau alone.
pub const MAX_CELL_REYNOLDS: f64 = 8.0;
/// Above this Mach number (fastest wall or stream) a scene with beads gets a note: measured,
/// the fold of a flexible fibre deepens as Ma^2 (docs/validation/fpd.md: S2023's K = 0.33
/// fibre folds to 0.950 of its contour at Ma 0.087, 0.930 at 0.173, ~0.958 as Ma -> 0).
pub const NOTE_MACH: f64 = 0.1;

/// Diagnostics after `fluid-lattice-step`, in their fixed order; with walls
/// [`crate::COUETTE_DIAGNOSTIC`] follows.
pub const FPD_DIAGNOSTICS: [&str; 3] = ["max_mach", "total_bead_force_x", "total_bead_force_y"];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFluid {
    method: String,
    grid: Vec<i64>,
    viscosity: f64,
    density: Option<f64>,
    viscosity_ratio: Option<f64>,
    interface_ratio: Option<f64>,
    profile_cutoff: Option<f64>,
    initial_velocity: Option<String>,
    solid_layers: Option<RawLayers>,
    stream: Option<uniform_stream::RawStream>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLayers {
    thickness: f64,
    interface: f64,
}

/// S2023's Couette sandwich (section III A, Fig. 2, eq. 14): a layer of the solid viscosity
/// on each wall, moving with it, with tanh interfaces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolidLayers {
    /// Layer thickness z_L measured from the wall plane (lattice units); the fluid lies in
    /// z_L < z < H - z_L (S2023: z_L = H / 3).
    pub thickness: f64,
    /// Interface length xi of eq. 14 (lattice units).
    pub interface: f64,
}

impl SolidLayers {
    /// Eq. 14 at distance z = y + 1/2 from the bottom wall plane of a gap H.
    pub fn phi(&self, z: f64, h: f64) -> f64 {
        let (zl, zr, xi) = (self.thickness, h - self.thickness, self.interface);
        if z <= 0.5 * h {
            0.5 * (((zl - z) / xi).tanh() + 1.0)
        } else {
            0.5 * (((z - zr) / xi).tanh() + 1.0)
        }
    }

    /// Eq. 13 for walls moving at `b` and `t`: each layer moves with its wall, the fluid
    /// between the interfaces is sheared linearly.
    pub fn exact(&self, z: f64, h: f64, b: f64, t: f64) -> f64 {
        let (zl, zr) = (self.thickness, h - self.thickness);
        b + (t - b) * ((z - zl) / (zr - zl)).clamp(0.0, 1.0)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWalls {
    velocity: [f64; 2],
}

/// The validated FPD part of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct FpdScene {
    pub nx: usize,
    pub ny: usize,
    /// Dynamic viscosity of the fluid eta_f (`fluid.viscosity`).
    pub viscosity: f64,
    /// Reference density rho0 (`fluid.density`, default 1).
    pub density: f64,
    /// `[bottom, top]` wall velocities along x, if the scene has walls.
    pub walls: Option<[f64; 2]>,
    /// Start from the linear profile between the walls (`fluid.initial_velocity = "couette"`).
    pub couette_start: bool,
    pub coupling: FpdConfig,
    /// Beads per fibre, fibres in order.
    pub beads: Vec<usize>,
    /// `fibre.N.bending_stiffness` of each fibre, where given (for the bending number K).
    pub bending_stiffness: Vec<Option<f64>>,
    /// `[fluid.solid_layers]`: S2023's Couette sandwich (scenes without fibres).
    pub solid_layers: Option<SolidLayers>,
    /// `[fluid.stream]`: a uniform stream with a sponge (drag of held bodies).
    pub stream: Option<UniformStream>,
    /// `max|u| dx / nu` with the fastest wall or stream, checked against
    /// [`MAX_CELL_REYNOLDS`].
    pub cell_reynolds: f64,
    /// `max|u| / c_s` with the fastest wall or stream (c_s = 1/sqrt 3): the lattice's
    /// compressibility error grows as its square.
    pub mach: f64,
}

/// Read and check the FPD part of a scene. The keys are checked in the order below, so a
/// scene with several faults is refused for the first of them.
pub fn parse_fpd_scene(scene_toml: &str) -> Result<FpdScene, String> {
    let table = scene_keys::parse_table(scene_toml)?;
    check_lattice_units(&table)?;
    let fluid = table.get("fluid").cloned().ok_or("fluid: missing")?;
    let raw: RawFluid = deserialize_at("fluid", fluid)?;
    debug_assert_eq!(raw.method, "fpd-lbm");
    let [nx, ny] = match raw.grid.as_slice() {
        [nx, ny] if *nx >= 8 && *ny >= 8 => [*nx as usize, *ny as usize],
        _ => {
            return Err(format!(
                "fluid.grid: expected [nx, ny] with each at least 8, got {:?}",
                raw.grid
            ))
        }
    };
    let viscosity = scene_keys::positive("fluid.viscosity", raw.viscosity)?;
    let density = scene_keys::positive("fluid.density", raw.density.unwrap_or(1.0))?;
    let couette_start = match raw.initial_velocity.as_deref() {
        None | Some("rest") => false,
        Some("couette") => true,
        Some(other) => {
            return Err(format!(
                "fluid.initial_velocity: expected \"rest\" or \"couette\", got {other:?}"
            ))
        }
    };
    let walls = walls(&table)?;
    if couette_start && walls.is_none() {
        return Err("fluid.initial_velocity = \"couette\" needs walls.velocity".into());
    }
    let fibres = crate::config::read_fibres(&table)?;
    let radius = shared_bead_radius(&fibres)?;
    let beads: Vec<usize> = fibres.iter().map(|f| f.beads).collect();
    let bending_stiffness = fibres.iter().map(|f| f.bending_stiffness).collect();
    let mut coupling = FpdConfig::new(radius.unwrap_or(1.0), viscosity / density);
    if let Some(r) = raw.viscosity_ratio {
        coupling.viscosity_ratio = r;
    }
    if let Some(r) = raw.interface_ratio {
        coupling.interface_ratio = r;
    }
    if let Some(c) = raw.profile_cutoff {
        coupling.cutoff = c;
    }
    let solid_layers = raw
        .solid_layers
        .map(|l| solid_layers(l, walls.is_some(), ny, &beads))
        .transpose()?;
    let stream = match raw.stream {
        None => None,
        Some(r) => {
            if couette_start || solid_layers.is_some() {
                return Err(
                    "fluid.stream: a uniform stream starts at the stream velocity; \
                            remove fluid.initial_velocity and fluid.solid_layers"
                        .into(),
                );
            }
            Some(UniformStream::new(r, nx, walls, MAX_WALL_MACH)?)
        }
    };
    let fastest = walls
        .iter()
        .flatten()
        .chain(stream.as_ref().map(|s| &s.velocity))
        .fold(0.0f64, |m, u| m.max(u.abs()));
    let cell_re = cell_reynolds(fastest, viscosity, density)?;
    Ok(FpdScene {
        nx,
        ny,
        viscosity,
        density,
        walls,
        couette_start,
        coupling,
        beads,
        bending_stiffness,
        solid_layers,
        stream,
        cell_reynolds: cell_re,
        mach: fastest * 3f64.sqrt(),
    })
}

/// The D2Q9 lattice is 2D and takes one lattice step per step.
fn check_lattice_units(table: &toml::Table) -> Result<(), String> {
    if scene_keys::dimensions(table)? != 2 {
        return Err(
            "dimensions: fluid.method = \"fpd-lbm\" is the 2D D2Q9 lattice of S2023; set dimensions = 2"
                .into(),
        );
    }
    let dt = scene_keys::time_step(table)?;
    if dt != 1.0 {
        return Err(format!(
            "time.dt = {}: fluid.method = \"fpd-lbm\" runs in lattice units, one lattice step \
             per step; set time.dt = 1 and express viscosity and velocities per lattice step",
            Num(dt)
        ));
    }
    Ok(())
}

/// `walls.velocity`, if the scene has walls, each below [`MAX_WALL_MACH`].
fn walls(table: &toml::Table) -> Result<Option<[f64; 2]>, String> {
    let Some(w) = table.get("walls") else {
        return Ok(None);
    };
    let w: RawWalls = deserialize_at("walls", w.clone()).map_err(|e| {
        if e.contains("thickness") {
            format!(
                "{e}; under fluid.method = \"fpd-lbm\" the walls are bounce-back planes \
                 at y = -1/2 and ny - 1/2 and have no thickness"
            )
        } else {
            e
        }
    })?;
    for (k, u) in w.velocity.iter().enumerate() {
        let mach = u.abs() * 3f64.sqrt();
        if mach.is_nan() || mach > MAX_WALL_MACH {
            return Err(format!(
                "walls.velocity.{k} = {}: Mach number |u| sqrt 3 = {:.3} exceeds the \
                 lattice's limit {MAX_WALL_MACH} (compressibility error ~ Ma^2); lower \
                 the wall speed (and raise the viscosity to keep the Reynolds number)",
                Num(*u),
                Num(mach)
            ));
        }
    }
    Ok(Some(w.velocity))
}

/// The one bead radius of all fibres (`None` without fibres).
fn shared_bead_radius(fibres: &[crate::config::FibreInfo]) -> Result<Option<f64>, String> {
    if let Some((n, f)) = fibres
        .iter()
        .enumerate()
        .find(|(_, f)| f.bead_radius != fibres[0].bead_radius)
    {
        return Err(format!(
            "fibre.{n}.bead_radius = {}: under fluid.method = \"fpd-lbm\" all beads share one \
             radius (fibre.0 has {})",
            f.bead_radius, fibres[0].bead_radius
        ));
    }
    Ok(fibres.first().map(|f| f.bead_radius))
}

/// `[fluid.solid_layers]`: between walls, leaving fluid between the layers, without fibres.
fn solid_layers(
    l: RawLayers,
    has_walls: bool,
    ny: usize,
    beads: &[usize],
) -> Result<SolidLayers, String> {
    let thickness = scene_keys::positive("fluid.solid_layers.thickness", l.thickness)?;
    let interface = scene_keys::positive("fluid.solid_layers.interface", l.interface)?;
    if !has_walls {
        return Err(
            "fluid.solid_layers: the layers move with the walls; set walls.velocity".into(),
        );
    }
    if 2.0 * thickness >= ny as f64 {
        return Err(format!(
            "fluid.solid_layers.thickness = {}: two layers must leave fluid \
             between them (gap ny = {ny})",
            Num(thickness)
        ));
    }
    if beads.iter().any(|&n| n > 0) {
        return Err(
            "fluid.solid_layers: the sandwich of S2023 Fig. 2 is a scene without \
                    fibres (the bead profiles would overwrite the layers' viscosity); remove \
                    the [[fibre]] tables"
                .into(),
        );
    }
    Ok(SolidLayers {
        thickness,
        interface,
    })
}

/// `max|u| dx / nu` for the fastest wall or stream, refused above [`MAX_CELL_REYNOLDS`].
fn cell_reynolds(fastest: f64, viscosity: f64, density: f64) -> Result<f64, String> {
    let cell_re = fastest * density / viscosity;
    if cell_re > MAX_CELL_REYNOLDS {
        return Err(format!(
            "fluid (fpd-lbm): the cell Reynolds number max|u| dx / nu = {:.3} (max|u| = \
             {}, the fastest wall or stream; nu = fluid.viscosity / fluid.density = {}) \
             exceeds {MAX_CELL_REYNOLDS}, beyond which this MRT lattice was measured to go \
             unstable; raise fluid.viscosity, or refine the grid (more nodes per bead diameter \
             at the same Reynolds number)",
            Num(cell_re),
            Num(fastest),
            Num(viscosity / density)
        ));
    }
    Ok(cell_re)
}

fn lattice_error(e: impl std::fmt::Display) -> ComponentError {
    ComponentError(format!("fluid (fpd-lbm): {e}"))
}

/// The lattice of `scene` at step 0: the walls, the solid layers' viscosity, and the
/// Couette profile or the uniform stream where the scene starts from one.
fn lattice_at_start(scene: &FpdScene) -> Result<MrtD2q9, String> {
    let y_boundary = match scene.walls {
        Some([bottom, top]) => YBoundary::Walls { bottom, top },
        None => YBoundary::Periodic,
    };
    let nu = scene.viscosity / scene.density;
    let mut mc = MrtConfig::new(scene.nx, scene.ny, y_boundary, nu);
    mc.density = scene.density;
    let mut lattice = MrtD2q9::new(mc).map_err(|e| e.to_string())?;
    if let Some(layers) = scene.solid_layers {
        let (nx, h) = (scene.nx, scene.ny as f64);
        let phi: Vec<f64> = (0..scene.nx * scene.ny)
            .map(|k| layers.phi((k / nx) as f64 + 0.5, h))
            .collect();
        lattice
            .set_viscosity_from_fraction(&phi, nu, nu * scene.coupling.viscosity_ratio)
            .map_err(|e| e.to_string())?;
    }
    if scene.couette_start {
        let [b, t] = scene.walls.unwrap_or([0.0; 2]);
        let ny = scene.ny as f64;
        let layers = scene.solid_layers;
        lattice
            .initialize_with(|_, y| {
                let z = y as f64 + 0.5;
                let u = match layers {
                    Some(l) => l.exact(z, ny, b, t),
                    None => b + (t - b) * z / ny,
                };
                (scene.density, u, 0.0)
            })
            .map_err(|e| e.to_string())?;
    }
    if let Some(s) = &scene.stream {
        lattice
            .initialize_with(|_, _| (scene.density, s.velocity, 0.0))
            .map_err(|e| e.to_string())?;
    }
    Ok(lattice)
}

/// The values an FPD scene derives, for the summary: the viscosities, the profile, the cell
/// Reynolds and Mach numbers; with a stream its Reynolds number and blockage; between walls
/// the gap, the shear rate and S2023's groups C, Re_ps and K (eq. 18) of fibre 0.
fn fpd_derived_values(scene: &FpdScene, total_beads: usize) -> Vec<(String, f64)> {
    let nu = scene.viscosity / scene.density;
    let mut derived = vec![
        // eta_f, shown because S2023's Re_ps may have set it (`fluid.particle_shear_reynolds`).
        ("fluid.viscosity".to_string(), scene.viscosity),
        ("fluid.kinematic_viscosity".into(), nu),
        (
            "fluid.viscosity_ratio".into(),
            scene.coupling.viscosity_ratio,
        ),
        (
            "fluid.interface_ratio".into(),
            scene.coupling.interface_ratio,
        ),
        ("fluid.interface_thickness".into(), scene.coupling.xi()),
        ("fluid.cell_reynolds".into(), scene.cell_reynolds),
        ("fluid.mach".into(), scene.mach),
    ];
    if let Some(s) = &scene.stream {
        let d = 2.0 * scene.coupling.radius;
        derived.push(("fluid.stream.velocity".into(), s.velocity));
        derived.push(("fluid.stream.sponge".into(), s.width as f64));
        if total_beads > 0 {
            // Re = U d / nu of a bead (the cylinder of S2023 Fig. 4), blockage d / H.
            derived.push(("fluid.stream.reynolds".into(), s.velocity.abs() * d / nu));
            derived.push(("fluid.stream.blockage".into(), d / scene.ny as f64));
        }
    }
    let Some([b, t]) = scene.walls else {
        return derived;
    };
    let h = scene.ny as f64;
    let gamma = (t - b) / h;
    derived.push(("fluid.gap".into(), h));
    derived.push(("fluid.shear_rate".into(), gamma));
    if let Some(l) = scene.solid_layers {
        // S2023 section III A: r_xi = xi / H for the sandwich.
        derived.push((
            "fluid.solid_layers.interface_over_gap".into(),
            l.interface / h,
        ));
    }
    if let Some(&n) = scene.beads.first() {
        // S2023 eq. 18: l_c = N d, C = l_c / H, Re_ps = rho gamma l_c^2 / (4 eta_f),
        // K = 2 k_b / (eta_f gamma l_c^2).
        let lc = n as f64 * 2.0 * scene.coupling.radius;
        derived.push(("fluid.confinement".into(), lc / h));
        // Walls at one speed (a towed body, fpd/cylinder_drag.toml) shear nothing: no Re_ps.
        if gamma != 0.0 {
            derived.push((
                "fluid.particle_shear_reynolds".into(),
                scene.density * gamma.abs() * lc * lc / (4.0 * scene.viscosity),
            ));
        }
        if let (Some(Some(kb)), true) = (scene.bending_stiffness.first(), gamma != 0.0) {
            derived.push((
                "fluid.bending_number".into(),
                2.0 * kb / (scene.viscosity * gamma.abs() * lc * lc),
            ));
        }
    }
    derived
}

/// The check of the first bead states: bounce-back walls lie halfway outside the first and
/// last rows.
fn start_check(scene: &FpdScene, total_beads: usize) -> StartCheck {
    StartCheck {
        geometry: StartBox {
            dims: 2,
            size: [scene.nx as f64, scene.ny as f64, 1.0],
            periodic: [true, scene.walls.is_none(), false],
            walls: scene.walls.map(|_| {
                let [bottom, top] = cosim::scene_keys::bounce_back_faces(scene.ny as f64);
                WallFaces { bottom, top }
            }),
        },
        beads_per_fibre: scene.beads.clone(),
        radius: vec![scene.coupling.radius; total_beads],
    }
}

/// Format tag of a saved fpd-lbm state ([`FpdRun::save`]).
const FPD_STATE_FORMAT: &str = "fluid-node fpd-lbm state 1";

/// A configured FPD fluid: lattice, coupling and exchange buffers.
pub struct FpdRun {
    pub scene: FpdScene,
    pub lattice: MrtD2q9,
    coupling: Option<FpdCoupling>,
    total_beads: usize,
    states: Vec<BeadState>,
    forces: Vec<BeadForce>,
    positions: Vec<[f64; 2]>,
    force2: Vec<[f64; 2]>,
    velocities: Vec<[f64; 2]>,
    out: Vec<BeadState>,
    /// Checks the first bead states of a run from step 0, then `None`.
    start: Option<StartCheck>,
}

impl FpdRun {
    /// Plan the lattice and the coupling; what the node derives goes into `Configured`.
    pub fn configure(scene_toml: &str) -> Result<(Self, Configured), ComponentError> {
        let scene = parse_fpd_scene(scene_toml).map_err(ComponentError)?;
        let mut lattice = lattice_at_start(&scene).map_err(lattice_error)?;
        let total_beads: usize = scene.beads.iter().sum();
        let coupling = if total_beads > 0 {
            Some(
                FpdCoupling::new(scene.coupling, &mut lattice, total_beads)
                    .map_err(lattice_error)?,
            )
        } else {
            None
        };
        let derived = fpd_derived_values(&scene, total_beads);
        let mut active = Vec::new();
        if total_beads > 0 {
            active.push(cosim::effects::HYDRODYNAMICS.to_string());
        }
        if scene.walls.is_some() {
            active.push(cosim::effects::WALLS.to_string());
        }
        let mut notes = Vec::new();
        if total_beads > 0 && scene.mach > NOTE_MACH {
            notes.push(format!(
                "fluid (fpd-lbm): the lattice Mach number is {:.3} (fastest wall or stream), \
                 above {NOTE_MACH}: the lattice's compressibility error grows as Ma^2, and a \
                 flexible fibre folds deeper than in the incompressible limit (S2023's K = 0.33 \
                 fibre: 0.930 of its contour at Ma 0.173, about 0.958 as Ma -> 0; a rigid \
                 fibre's period by 1.5 % between Ma 0.043 and 0.173; \
                 docs/validation/fpd.md). To check a result, lower the wall speed and the \
                 viscosity together (same Reynolds number)",
                scene.mach
            ));
        }
        let start = Some(start_check(&scene, total_beads));
        let run = FpdRun {
            start,
            lattice,
            coupling,
            total_beads,
            states: Vec::with_capacity(total_beads),
            forces: Vec::with_capacity(total_beads),
            positions: vec![[0.0; 2]; total_beads],
            force2: vec![[0.0; 2]; total_beads],
            velocities: vec![[0.0; 2]; total_beads],
            out: Vec::with_capacity(total_beads),
            scene,
        };
        let configured = Configured {
            beads_per_fibre: Vec::new(),
            effects: active,
            time_step_limits: Vec::new(),
            derived,
            notes,
        };
        Ok((run, configured))
    }

    /// Write the lattice's velocity, density, viscosity and (with beads) solid fraction to
    /// `dir/name` ([`crate::field_output`]).
    pub fn write_fields(
        &self,
        dir: &std::path::Path,
        name: &str,
    ) -> Result<Vec<String>, ComponentError> {
        use cosim::vtk::Array;
        let (nx, ny) = (self.lattice.nx(), self.lattice.ny());
        let n = nx * ny;
        let (mut rho, mut ux, mut uy) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        self.lattice.fields(&mut rho, &mut ux, &mut uy);
        let velocity = crate::field_output::interleave(&[&ux, &uy], n);
        let mut arrays = vec![
            Array::vector("velocity", &velocity),
            Array::scalar("density", &rho),
            Array::scalar("viscosity", self.lattice.viscosity()),
        ];
        if let Some(c) = &self.coupling {
            arrays.push(Array::scalar("solid_fraction", c.solid_fraction()));
        }
        crate::field_output::write(dir, name, [nx, ny, 1], &arrays)
    }

    /// The lattice's state, serialised: a JSON header line, then the populations as
    /// little-endian f64. The viscosity and force fields are rebuilt from the beads at the
    /// next step (the sparse viscosity update equals the full one bit for bit), the solid
    /// layers and the stream's sponge from the scene.
    pub fn save(&self) -> Result<Vec<u8>, ComponentError> {
        let (f, time) = self.lattice.saved_state();
        let header = serde_json::json!({
            "format": FPD_STATE_FORMAT,
            "lattice": [self.scene.nx, self.scene.ny],
            "time": time,
        });
        Ok(crate::saved_state::join(
            header.to_string().as_bytes(),
            f.iter().copied(),
        ))
    }

    /// Bring back a state from [`FpdRun::save`] of the same scene.
    pub fn restore(&mut self, state: &[u8]) -> Result<(), ComponentError> {
        let bad =
            |why: String| ComponentError(format!("fluid-node: not a saved fpd-lbm state: {why}"));
        let (header, body) =
            crate::saved_state::split(state).ok_or_else(|| bad("no header".into()))?;
        let h: serde_json::Value =
            serde_json::from_slice(header).map_err(|e| bad(e.to_string()))?;
        if h["format"] != FPD_STATE_FORMAT {
            return Err(bad(format!(
                "format {}, expected {FPD_STATE_FORMAT:?}",
                h["format"]
            )));
        }
        let here = serde_json::json!([self.scene.nx, self.scene.ny]);
        if h["lattice"] != here {
            return Err(ComponentError(format!(
                "fluid-node: saved fpd-lbm state is of a {} lattice, the configured scene has {here}",
                h["lattice"]
            )));
        }
        let time = h["time"]
            .as_u64()
            .ok_or_else(|| bad("no step count".into()))?;
        if !body.len().is_multiple_of(8) {
            return Err(bad(format!("{} bytes of populations", body.len())));
        }
        let f: Vec<f64> = crate::saved_state::values(body).collect();
        self.lattice.set_populations(&f, time).map_err(bad)
    }

    /// The check of the beads' first positions, while it has not run (none without beads).
    pub fn start_check(&self) -> Option<&StartCheck> {
        self.start.as_ref().filter(|_| self.total_beads > 0)
    }

    /// Phase `fluid-lattice-step` of step `step`.
    pub fn lattice_step(
        &mut self,
        step: u64,
        exchange: &mut dyn Exchange,
    ) -> Result<PhaseReport, ComponentError> {
        let fail = |e: crate::fpd::FpdError| ComponentError(format!("fluid (fpd-lbm): {e}"));
        let (mut fx, mut fy) = (0.0, 0.0);
        if let Some(c) = self.coupling.as_mut() {
            let hs = exchange.read_states(Port::BeadStates, &mut self.states)?;
            let hf = exchange.read_forces(Port::BeadForces, &mut self.forces)?;
            if hs.step != step || hf.step != step {
                return Err(ComponentError(format!(
                    "fluid (fpd-lbm): fluid-lattice-step of step {step} read bead states of step \
                     {} and forces of step {}",
                    hs.step, hf.step
                )));
            }
            if self.states.len() != self.total_beads || self.forces.len() != self.total_beads {
                return Err(ComponentError(format!(
                    "fluid (fpd-lbm): {} bead states and {} forces received for {} beads",
                    self.states.len(),
                    self.forces.len(),
                    self.total_beads
                )));
            }
            if step == 0 {
                if let Some(s) = self.start.take() {
                    s.check(&self.states)
                        .map_err(|e| ComponentError(format!("fluid (fpd-lbm): {e}")))?;
                }
            }
            for k in 0..self.total_beads {
                let p = self.states[k].position;
                let f = self.forces[k].force;
                self.positions[k] = [p[0], p[1]];
                self.force2[k] = [f[0], f[1]];
                fx += f[0];
                fy += f[1];
            }
            if let Some(s) = &self.scene.stream {
                let reach = c.config().reach();
                for (k, p) in self.positions.iter().enumerate() {
                    s.check_clear(k, p[0], reach, self.scene.nx).map_err(|e| {
                        ComponentError(format!("fluid (fpd-lbm): step {step}: {e}"))
                    })?;
                }
                s.apply(&mut self.lattice);
            }
            c.apply(&mut self.lattice, &self.positions, &self.force2)
                .map_err(fail)?;
            self.lattice.step();
            c.bead_velocities(&self.lattice, &mut self.velocities)
                .map_err(fail)?;
            self.out.clear();
            for k in 0..self.total_beads {
                let mut s = self.states[k];
                s.velocity = [self.velocities[k][0], self.velocities[k][1], 0.0];
                s.angular_velocity = [0.0; 3];
                self.out.push(s);
            }
            exchange.publish_states(Port::BeadVelocities, step + 1, &self.out)?;
        } else {
            if let Some(s) = &self.scene.stream {
                s.apply(&mut self.lattice);
            }
            self.lattice.step();
        }
        // Kept by the step itself (the flow it collided, the state at step n): no extra pass.
        let mach = self.lattice.last_step_max_mach();
        if mach.is_nan() || mach > ABORT_MACH {
            return Err(ComponentError(format!(
                "fluid (fpd-lbm): the flow's Mach number reached {mach:.3} at step {step} \
                 (limit {ABORT_MACH}): the lattice cannot carry it; lower the forces or wall \
                 speeds"
            )));
        }
        let mut diagnostics = vec![
            (FPD_DIAGNOSTICS[0].to_string(), mach),
            (FPD_DIAGNOSTICS[1].to_string(), fx),
            (FPD_DIAGNOSTICS[2].to_string(), fy),
        ];
        if let Some([b, t]) = self.scene.walls {
            diagnostics.push((
                crate::COUETTE_DIAGNOSTIC.to_string(),
                self.couette_error(b, t),
            ));
        }
        // Nothing here costs a pass of its own: every report is full.
        Ok(PhaseReport {
            diagnostics,
            detail: cosim::Detail::Full,
        })
    }

    /// Largest deviation of the row-averaged x-velocity from the Couette profile between the
    /// wall planes (linear, or S2023 eq. 13 with solid layers), over |top - bottom|, for the
    /// flow the last lattice step collided.
    fn couette_error(&self, b: f64, t: f64) -> f64 {
        let du = (t - b).abs();
        if du == 0.0 {
            // No shear (walls at rest, or sliding with a uniform stream): nothing to compare.
            return 0.0;
        }
        let ny = self.scene.ny;
        let mut worst: f64 = 0.0;
        for y in 0..ny {
            // Row means the step kept: the flow it collided (step n), no pass over the lattice.
            let mean = self.lattice.last_step_row_mean_ux(y);
            let z = y as f64 + 0.5;
            let exact = match self.scene.solid_layers {
                Some(l) => l.exact(z, ny as f64, b, t),
                None => b + (t - b) * z / ny as f64,
            };
            worst = worst.max((mean - exact).abs() / du);
        }
        worst
    }
}
