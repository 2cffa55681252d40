//! The part of the scene the fibre node reads: `dimensions`, `time.dt`, whether a `[fluid]`
//! table exists, and the `[[fibre]]` array of tables. Other top-level tables are the
//! coordinator's to validate and are ignored here.
//!
//! Every refusal names the dotted path (`fibre.N.key`), the value and what was expected;
//! nothing panics on any input.
use crate::fibre_table::{non_negative, validate_fibre, RawFibre};
use crate::spm_exchange::SmoothedProfile;
use cosim::profile::{DEFAULT_CUTOFF_OVER_XI, DEFAULT_FPD_INTERFACE_RATIO, DEFAULT_XI};
use cosim::scene_keys::{
    self, describe_value as describe_toml, deserialize_at as deserialize, number as toml_number,
    positive,
};

/// Which fibre model a `[[fibre]]` table asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// L2020 cohesive beam (`"cohesive-beam"`).
    CohesiveBeam,
    /// S2023 bead-spring chain (`"bead-spring"`).
    BeadSpring,
}

impl ModelKind {
    /// The name used in the scene.
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::CohesiveBeam => "cohesive-beam",
            ModelKind::BeadSpring => "bead-spring",
        }
    }
}

/// A constant point load on one bead (laboratory frame).
#[derive(Debug, Clone, PartialEq)]
pub struct LoadConfig {
    /// Bead index, resolved (0-based, non-negative).
    pub bead: usize,
    pub force: [f64; 3],
    pub torque: [f64; 3],
}

/// One validated `[[fibre]]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct FibreConfig {
    pub model: ModelKind,
    pub beads: usize,
    pub bead_radius: f64,
    /// Young's modulus E; `None` only for a bead-spring fibre whose table gives both of its
    /// constants (`k_s` and `k_b`), which then need no modulus.
    pub youngs_modulus: Option<f64>,
    /// Shear modulus G: as given, else `E / (2 (1 + nu))`; `None` where E is.
    pub shear_modulus: Option<f64>,
    pub density: f64,
    pub start: [f64; 3],
    /// `centred = true`: `start` is set so that the fibre's midpoint lies at the centre of the
    /// gap between the walls (`centre_in_gap`).
    pub centred: bool,
    /// Unit vector.
    pub direction: [f64; 3],
    pub spacing: f64,
    /// Amplitude (length) of an S-shaped initial offset of the beads across `direction`
    /// (0: straight).
    pub initial_bend: f64,
    /// Non-neighbouring beads repel while they overlap ([`crate::self_contact`]).
    pub self_contact: bool,
    /// Its beads and those of every other fibre with the key repel while they overlap
    /// ([`crate::fibre_contact`]).
    pub fibre_contact: bool,
    /// `fibre.N.wall_contact = true`: the y of the bottom and the top wall's face, which the
    /// beads are kept behind ([`crate::wall_contact`]); `None` without it.
    pub wall_contact: Option<[f64; 2]>,
    /// Resolved, sorted, without duplicates.
    pub clamp: Vec<usize>,
    pub loads: Vec<LoadConfig>,
    pub damping: f64,
    /// Kelvin-Voigt (stiffness-proportional) damping time of the bonds, >= 0.
    pub internal_damping: f64,
    pub substeps: usize,
    pub stretch_stiffness: Option<f64>,
    pub bending_stiffness: Option<f64>,
    pub affinity: f64,
    pub bending_number: Option<f64>,
    /// S2023's stretch number K_s (section II C), given in place of `stretch_stiffness`.
    pub stretch_number: Option<f64>,
    /// Cohesive beam only: `true` for the energy-consistent force law
    /// (`beam_forces = "energy-consistent"`), `false` for the paper's (`"paper"`).
    pub energy_consistent: bool,
    /// `bead_inertia = "profile"`: the bead's moment of inertia is `density` times that of
    /// its smoothed profile (SPM only); `"solid"` (default): that of a sharp disc or sphere.
    pub profile_inertia: bool,
    /// `exchange = "implicit"`: the SPM momentum exchange acts as a drag towards the fluid's
    /// velocity in the bead's profile, taken implicitly (see `crate::fibre`); `"explicit"`
    /// (default): the fluid's impulse is added as it comes (L2020 eqs. 35-36).
    pub implicit_exchange: bool,
    /// Bead-spring under SPM: `bead_spin = "chord"` turns each bead with its chord (the
    /// fluid's torque on a bead passed to its neighbours as a couple, `crate::fibre`), as in
    /// a solid fibre; in 3D each bead keeps a free spin about the chain's tangent, which
    /// bonds without torsion cannot hold. `"free"` (default): each bead spins freely with
    /// the fluid.
    pub spin_with_chord: bool,
}

/// What the fibre node reads from a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneConfig {
    /// 2 or 3.
    pub dimensions: u8,
    /// `time.dt`.
    pub dt: f64,
    /// Whether the scene has a `[fluid]` table.
    pub has_fluid: bool,
    /// How the fluid, if any, moves the fibres (from `fluid.method`).
    pub coupling: Coupling,
    /// `fluid.density` (mass / length^dimensions, default 1): sets the gains that hold
    /// clamped beads under FPD and the FPD stiffness limit. The fluid node validates it.
    pub fluid_density: f64,
    /// `fluid.viscosity / fluid.density` where the scene gives the viscosity: under SPM the
    /// explicit exchange's stiffness limit depends on `nu dt / xi^2`. The fluid node
    /// validates it.
    pub fluid_kinematic_viscosity: Option<f64>,
    /// Under FPD: `fluid.interface_ratio` r_xi = xi / d (default 0.125, the fluid node's),
    /// on which the FPD stiffness limit depends. The fluid node validates it.
    pub fpd_interface_ratio: Option<f64>,
    /// Under SPM: the beads' smoothed profile (`fluid.xi`, `fluid.xi_cutoff`, with the fluid
    /// node's defaults), which sizes the fluid a bead exchanges momentum with.
    pub spm_profile: Option<SmoothedProfile>,
    /// Under FPD with sheared walls: the shear S2023's groups are defined on.
    pub shear_flow: Option<ShearFlow>,
    /// y of the bottom and the top wall's face, where the scene has walls
    /// ([`cosim::scene_keys::wall_faces`]): the `wall_overlap` diagnostic measures from them.
    pub wall_faces: Option<[f64; 2]>,
    /// The fluid box's length along each axis on which beads of two fibres meet across the
    /// seam ([`periodic_box`]); all `None` without a fluid.
    pub periodic_box: [Option<f64>; 3],
    pub fibres: Vec<FibreConfig>,
}

/// How the fibre node is coupled to the fluid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coupling {
    /// No `[fluid]` table: the fibres move under their own and external forces.
    None,
    /// SPM (L2020 section 2.6): the fluid returns time-integrated forces and torques per bead
    /// (phases fibre-positions, fibre-velocities).
    Spm,
    /// FPD (S2023 section II C): the fibre publishes bead forces and the fluid returns bead
    /// velocities (phases fibre-forces, fibre-advance); `fluid.method = "fpd-lbm"`.
    Fpd,
}

impl Coupling {
    /// The name the model descriptions use (`"none"`, `"spm"`, `"fpd"`).
    pub fn name(self) -> &'static str {
        match self {
            Coupling::None => "none",
            Coupling::Spm => "spm",
            Coupling::Fpd => "fpd",
        }
    }
}

/// Poisson ratio used for the default shear modulus `E / (2 (1 + ν))`.
pub const DEFAULT_POISSON_RATIO: f64 = 0.3;
/// Default of `fibre.N.beam_forces` (`false`: "paper").
pub const DEFAULT_ENERGY_CONSISTENT: bool = false;
/// Largest accepted `fibre.N.beads`.
pub const MAX_BEADS: i64 = 1_000_000;
/// Largest accepted `fibre.N.substeps`.
pub const MAX_SUBSTEPS: i64 = 1_000_000;

/// Read the fibre node's part of a scene.
pub fn parse_scene(scene_toml: &str) -> Result<SceneConfig, String> {
    let table = scene_keys::parse_table(scene_toml)?;
    let dimensions = scene_keys::dimensions(&table)?;
    let dt = scene_keys::time_step(&table)?;

    let has_fluid = table.contains_key("fluid");
    // The fluid node validates `fluid.method`; here only FPD's is told apart.
    let coupling = match table.get("fluid").and_then(|f| f.get("method")) {
        _ if !has_fluid => Coupling::None,
        Some(toml::Value::String(m)) if m == "fpd-lbm" => Coupling::Fpd,
        _ => Coupling::Spm,
    };
    // The fluid node validates its keys; here they only size the beads' exchange with it.
    let fluid_density = fluid_number(&table, "density").unwrap_or(1.0);
    let fluid_kinematic_viscosity = fluid_number(&table, "viscosity").map(|v| v / fluid_density);
    let fpd_interface_ratio = (coupling == Coupling::Fpd)
        .then(|| fluid_number(&table, "interface_ratio").unwrap_or(DEFAULT_FPD_INTERFACE_RATIO));
    let spm_profile = (coupling == Coupling::Spm).then(|| {
        let xi = fluid_number(&table, "xi").unwrap_or(DEFAULT_XI);
        SmoothedProfile {
            xi,
            cutoff: fluid_number(&table, "xi_cutoff").unwrap_or(DEFAULT_CUTOFF_OVER_XI * xi),
        }
    });

    let wall_faces = scene_keys::wall_faces(&table);
    let mut fibres = Vec::new();
    for (n, v) in fibre_tables(&table)?.into_iter().enumerate() {
        let prefix = format!("fibre.{n}");
        if !v.is_table() {
            return Err(format!(
                "{prefix}: expected a table, got {}",
                describe_toml(&v)
            ));
        }
        let raw: RawFibre = deserialize(&prefix, v)?;
        fibres.push(validate_fibre(&prefix, raw, dimensions, wall_faces)?);
    }
    for (n, f) in fibres.iter_mut().enumerate() {
        resolve_with_flow(&table, &format!("fibre.{n}"), f, coupling)?;
    }
    check_fibre_contact(&fibres)?;

    Ok(SceneConfig {
        dimensions,
        dt,
        has_fluid,
        coupling,
        fluid_density,
        fluid_kinematic_viscosity,
        fpd_interface_ratio,
        spm_profile,
        shear_flow: (coupling != Coupling::None)
            .then(|| shear_flow(&table, "").ok())
            .flatten(),
        wall_faces,
        periodic_box: periodic_box(&table, dimensions),
        fibres,
    })
}

/// `fluid.KEY` where it is a positive finite number.
fn fluid_number(table: &toml::Table, key: &str) -> Option<f64> {
    table
        .get("fluid")
        .and_then(|f| f.get(key))
        .and_then(toml_number)
        .filter(|x| x.is_finite() && *x > 0.0)
}

/// The `[[fibre]]` array: present and not empty.
fn fibre_tables(table: &toml::Table) -> Result<Vec<toml::Value>, String> {
    let list = match table.get("fibre") {
        None => return Err(
            "fibre: the scene has no [[fibre]] table, so the fibre node has nothing to simulate"
                .into(),
        ),
        Some(toml::Value::Array(a)) => a.clone(),
        Some(v) => {
            return Err(format!(
                "fibre: expected an array of tables ([[fibre]]), got {}",
                describe_toml(v)
            ))
        }
    };
    if list.is_empty() {
        return Err("fibre: the scene's fibre list is empty".into());
    }
    Ok(list)
}

/// What a fibre's keys mean with the scene's flow: the SPM-only keys refused under another
/// coupling, `centred` placed in the gap, S2023's groups K and K_s turned into stiffnesses.
fn resolve_with_flow(
    table: &toml::Table,
    p: &str,
    f: &mut FibreConfig,
    coupling: Coupling,
) -> Result<(), String> {
    if f.implicit_exchange && coupling != Coupling::Spm {
        return Err(format!(
            "{p}.exchange = \"implicit\": only the SPM fluid (fluid.method = \"spm\") \
             exchanges momentum with the beads; remove the key"
        ));
    }
    if f.spin_with_chord && coupling != Coupling::Spm {
        return Err(format!(
            "{p}.bead_spin = \"chord\": read for a scene with the SPM fluid \
             (fluid.method = \"spm\"), where a bead's spin is otherwise its own; use \
             \"free\" or remove the key"
        ));
    }
    if f.profile_inertia && coupling != Coupling::Spm {
        return Err(format!(
            "{p}.bead_inertia = \"profile\": only the SPM fluid (fluid.method = \"spm\") \
             gives beads a smoothed profile; use \"solid\" or remove the key"
        ));
    }
    if f.centred {
        f.start = centre_in_gap(table, p, f)?;
    }
    if let Some(k) = f.bending_number {
        let kb = stiffness_from_group(table, p, f, FibreGroup::Bending, k, coupling)?;
        f.bending_stiffness = Some(kb);
    }
    if let Some(k) = f.stretch_number {
        let ks = stiffness_from_group(table, p, f, FibreGroup::Stretch, k, coupling)?;
        f.stretch_stiffness = Some(ks);
    }
    Ok(())
}

/// `fibre.N.fibre_contact` needs a second fibre with the key, and every fibre of the scene
/// on the same sub-steps: the fibres then step together ([`crate::fibre::together`]).
fn check_fibre_contact(fibres: &[FibreConfig]) -> Result<(), String> {
    let with: Vec<usize> = (0..fibres.len())
        .filter(|&n| fibres[n].fibre_contact)
        .collect();
    match with[..] {
        [] => return Ok(()),
        [n] => {
            return Err(format!(
                "fibre.{n}.fibre_contact = true: no other fibre of the scene has it, so there \
                 is nothing for it to push against; set it on every fibre that should keep \
                 clear of the others (both fibres of a pair need it), or remove the key"
            ))
        }
        _ => {}
    }
    let n0 = fibres[0].substeps;
    if let Some(n) = (0..fibres.len()).find(|&n| fibres[n].substeps != n0) {
        return Err(format!(
            "fibre.{}.fibre_contact = true: with contact between fibres all fibres take their \
             sub-steps together, so they need the same fibre.N.substeps (fibre.0.substeps = \
             {n0}, fibre.{n}.substeps = {}); set them equal, to the largest",
            with[0], fibres[n].substeps
        ));
    }
    Ok(())
}

/// `fluid.grid` as numbers (empty without it). Read, not validated: the fluid node checks it.
fn fluid_grid(table: &toml::Table) -> Vec<f64> {
    table
        .get("fluid")
        .and_then(|f| f.get("grid"))
        .and_then(|g| g.as_array())
        .map(|g| g.iter().filter_map(toml_number).collect())
        .unwrap_or_default()
}

/// The axes along which the fluid's box wraps for the beads, with its lengths (grid units,
/// `fluid.grid`): x always; y without walls (SPM's slabs also sit in a box periodic in y,
/// but no bead crosses them, and FPD's walls bound the lattice); z in 3D. All `None` without
/// a fluid (a dry fibre lives in unbounded space). Read, not validated: the fluid node
/// checks `fluid.grid`.
pub fn periodic_box(table: &toml::Table, dimensions: u8) -> [Option<f64>; 3] {
    let grid = fluid_grid(table);
    let wraps = [true, !table.contains_key("walls"), dimensions == 3];
    std::array::from_fn(|a| {
        grid.get(a)
            .copied()
            .filter(|l| wraps[a] && l.is_finite() && *l > 0.0)
    })
}

/// The sheared fluid S2023's fibre groups are defined on: `eta_f = fluid.viscosity` and the
/// walls' plane Couette flow ([`cosim::scene_keys::WallShear`]): the shear rate
/// `gamma = |top - bottom| / H` and the wall speed `V0 = |top - bottom| / 2`, where the gap
/// `H` is the lattice's `ny` under FPD and `ny - 2 T` between SPM's slabs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShearFlow {
    pub viscosity: f64,
    pub shear_rate: f64,
    pub wall_speed: f64,
}

/// [`ShearFlow`] of a scene, or a message saying which key `need` (the fibre key asking, e.g.
/// `fibre.0.bending_number`) is missing. The fluid node validates these keys itself; here
/// they are only read.
pub fn shear_flow(table: &toml::Table, need: &str) -> Result<ShearFlow, String> {
    let viscosity = table
        .get("fluid")
        .and_then(|f| f.get("viscosity"))
        .and_then(toml_number)
        .filter(|e| *e > 0.0)
        .ok_or(format!("{need} needs a positive fluid.viscosity (eta_f)"))?;
    let walls = cosim::scene_keys::wall_shear(table, need)?;
    Ok(ShearFlow {
        viscosity,
        shear_rate: walls.shear_rate,
        wall_speed: walls.wall_speed,
    })
}

/// `start` for a fibre whose midpoint lies at the centre of the gap between the walls, as
/// S2023 place theirs (section IV A): y = (ny - 1) / 2, midway between the FPD walls at
/// y = -1/2 and ny - 1/2 and between the SPM slabs' faces at T - 1/2 and ny - T - 1/2; along
/// the periodic axes x = nx / 2 (and z = nz / 2 in 3D).
fn centre_in_gap(table: &toml::Table, p: &str, f: &FibreConfig) -> Result<[f64; 3], String> {
    let grid = fluid_grid(table);
    if grid.len() < 2 || !table.contains_key("walls") {
        return Err(format!(
            "{p}.centred = true needs a fluid between walls: fluid.grid and walls.velocity"
        ));
    }
    let mid = [
        0.5 * grid[0],
        0.5 * (grid[1] - 1.0),
        grid.get(2).map_or(0.0, |nz| 0.5 * nz),
    ];
    let half = 0.5 * (f.beads as f64 - 1.0) * f.spacing;
    Ok(std::array::from_fn(|k| mid[k] - half * f.direction[k]))
}

/// One of S2023's bead-spring groups, given in place of the stiffness it sets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FibreGroup {
    /// `bending_number` K = 2 k_b / (eta_f gamma l_c^2) (S2023 eq. 18) sets `bending_stiffness`.
    Bending,
    /// `stretch_number` K_s = k_s / (eta_f V0 l0) (S2023 section II C) sets
    /// `stretch_stiffness`.
    Stretch,
}

impl FibreGroup {
    fn keys(self) -> (&'static str, &'static str, &'static str) {
        match self {
            Self::Bending => ("bending_number", "bending_stiffness", "K, S2023 eq. 18"),
            Self::Stretch => (
                "stretch_number",
                "stretch_stiffness",
                "K_s, S2023 section II C",
            ),
        }
    }

    /// The stiffness for the group's value `x`, with l_c = N d and l0 the bond's rest length.
    fn stiffness(self, x: f64, shear: ShearFlow, f: &FibreConfig) -> f64 {
        match self {
            Self::Bending => {
                let lc = f.beads as f64 * 2.0 * f.bead_radius;
                0.5 * x * shear.viscosity * shear.shear_rate * lc * lc
            }
            Self::Stretch => x * shear.viscosity * shear.wall_speed * f.spacing,
        }
    }

    /// The group a stiffness gives (the inverse of `Self::stiffness`).
    pub fn of(self, stiffness: f64, shear: ShearFlow, f: &FibreConfig) -> f64 {
        stiffness / self.stiffness(1.0, shear, f)
    }
}

/// `k_b` or `k_s` from S2023's group (K or K_s) on the scene's wall shear ([`shear_flow`]),
/// with `l_c = N d`.
fn stiffness_from_group(
    table: &toml::Table,
    p: &str,
    f: &FibreConfig,
    group: FibreGroup,
    x: f64,
    coupling: Coupling,
) -> Result<f64, String> {
    let (key, stiffness_key, name) = group.keys();
    if f.model != ModelKind::BeadSpring {
        return Err(format!(
            "{p}.{key}: only the bead-spring model reads this key (model is {:?})",
            f.model.name()
        ));
    }
    let given = match group {
        FibreGroup::Bending => f.bending_stiffness,
        FibreGroup::Stretch => f.stretch_stiffness,
    };
    if given.is_some() {
        return Err(format!(
            "{p}.{key}: give either {key} ({name}) or {stiffness_key}, not both"
        ));
    }
    if coupling == Coupling::None {
        return Err(format!(
            "{p}.{key}: {} is converted with the fluid's viscosity and the walls' shear, so it \
             needs a [fluid] between walls; give {p}.{stiffness_key} instead",
            name.split(',').next().unwrap_or(key)
        ));
    }
    // K = 0 is S2023's freely jointed limit (section IV A: 0 <= K < infinity); a bond needs
    // a stiffness.
    let path = format!("{p}.{key}");
    match group {
        FibreGroup::Bending => non_negative(&path, x)?,
        FibreGroup::Stretch => positive(&path, x)?,
    };
    let shear = shear_flow(table, &format!("{p}.{key}"))?;
    Ok(group.stiffness(x, shear, f))
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
dimensions = 2
[time]
dt = 0.1
steps = 10
[walls]
velocity = [0.0, 1.0]
[[fibre]]
model = "cohesive-beam"
beads = 10
bead_radius = 1.0
youngs_modulus = 100.0
"#;

    fn with(extra: &str) -> String {
        format!("{BASE}{extra}\n")
    }

    fn err(scene: &str) -> String {
        match parse_scene(scene) {
            Ok(_) => panic!("accepted:\n{scene}"),
            Err(e) => e,
        }
    }

    #[test]
    fn defaults() {
        let s = parse_scene(BASE).unwrap();
        assert_eq!(s.dimensions, 2);
        assert_eq!(s.dt, 0.1);
        assert!(!s.has_fluid);
        let f = &s.fibres[0];
        assert_eq!(f.model, ModelKind::CohesiveBeam);
        assert_eq!(f.beads, 10);
        assert_eq!(f.spacing, 2.0);
        assert_eq!(f.density, 1.0);
        assert_eq!(f.direction, [1.0, 0.0, 0.0]);
        assert!((f.shear_modulus.unwrap() - 100.0 / 2.6).abs() < 1e-12);
        assert_eq!(f.substeps, 1);
        assert!(f.clamp.is_empty() && f.loads.is_empty());
    }

    #[test]
    fn full_table_and_fluid() {
        let s = parse_scene(&with(
            r#"shear_modulus = 40
density = 2.5
start = [1, 2, 0]
direction = [0, 2, 0]
spacing = 2.5
clamp = [0, -1, 0]
loads = [{ bead = -2, force = [0, -1, 0] }, { bead = 3, torque = [0, 0, 0.5] }]
damping = 0.1
substeps = 4
affinity = 0.2
[fluid]
method = "spm"
"#,
        ))
        .unwrap();
        assert!(s.has_fluid);
        let f = &s.fibres[0];
        assert_eq!(f.direction, [0.0, 1.0, 0.0]);
        assert_eq!(f.clamp, vec![0, 9]);
        assert_eq!(f.loads[0].bead, 8);
        assert_eq!(f.loads[1].torque, [0.0, 0.0, 0.5]);
        assert_eq!(f.substeps, 4);
        assert_eq!(f.affinity, 0.2);
    }

    const FPD_SHEAR: &str = r#"dimensions = 2
[time]
dt = 1.0
[fluid]
method = "fpd-lbm"
grid = [200, 160]
viscosity = 0.5
[walls]
velocity = [-0.04, 0.04]
[[fibre]]
model = "bead-spring"
beads = 10
bead_radius = 4.0
youngs_modulus = 1.0
"#;

    /// S2023 eq. 18 inverted: k_b = K eta_f gamma l_c^2 / 2 with gamma = 0.08 / 160,
    /// l_c = 10 x 8 = 80: K = 3.3 gives k_b = 3.3 x 0.5 x 5e-4 x 6400 / 2 = 2.64.
    #[test]
    fn bending_number_sets_the_bending_stiffness_from_the_fpd_shear() {
        let s = parse_scene(&format!("{FPD_SHEAR}bending_number = 3.3\n")).unwrap();
        let f = &s.fibres[0];
        assert_eq!(f.bending_number, Some(3.3));
        let kb = f.bending_stiffness.unwrap();
        assert!((kb - 2.64).abs() < 1e-12, "{kb}");
    }

    /// `youngs_modulus` is required by the cohesive beam, and by a bead-spring fibre only for
    /// the constants (k_s, k_b) its table leaves out; the refusal names those.
    #[test]
    fn a_bead_spring_fibre_given_both_constants_needs_no_modulus() {
        let no_e = FPD_SHEAR.replace("youngs_modulus = 1.0\n", "");
        let s = parse_scene(&format!(
            "{no_e}stretch_number = 480\nbending_number = 3.3\n"
        ))
        .unwrap();
        let f = &s.fibres[0];
        assert_eq!((f.youngs_modulus, f.shear_modulus), (None, None));
        let chain = crate::fibre::Fibre::straight(f, 2, true);
        match chain.model {
            crate::fibre::Model::BeadSpring(b) => {
                assert_eq!(Some(b.k_s), f.stretch_stiffness);
                assert_eq!(Some(b.k_b), f.bending_stiffness);
            }
            _ => panic!("a bead-spring chain"),
        }
        let e = parse_scene(&format!("{no_e}bending_stiffness = 0.4\n")).unwrap_err();
        assert_eq!(
            e,
            "fibre.0.youngs_modulus is required and missing: a bead-spring fibre takes from it \
             the constants of S2023 eq. 9 that its table does not give, here k_s; give \
             youngs_modulus, or give k_s (stretch_stiffness or stretch_number)"
        );
        let e = parse_scene(&no_e.replace("bead-spring", "cohesive-beam")).unwrap_err();
        assert!(
            e.starts_with("fibre.0.youngs_modulus is required and missing: the cohesive beam"),
            "{e}"
        );
    }

    /// `bead_spin = "chord"` is read for a bead-spring fibre under SPM, 2D or 3D, with
    /// either exchange, and refused elsewhere with the reason.
    #[test]
    fn bead_spin_chord_is_read_where_a_beads_spin_is_its_own() {
        let spm = FPD_SHEAR.replace("\"fpd-lbm\"", "\"spm\"");
        let s = parse_scene(&format!("{spm}bead_spin = \"chord\"\n")).unwrap();
        assert!(s.fibres[0].spin_with_chord);
        assert!(!parse_scene(&spm).unwrap().fibres[0].spin_with_chord);
        let implicit = parse_scene(&format!(
            "{spm}bead_spin = \"chord\"\nexchange = \"implicit\"\n"
        ))
        .unwrap();
        assert!(implicit.fibres[0].spin_with_chord && implicit.fibres[0].implicit_exchange);
        let spm_3d = spm
            .replace("dimensions = 2", "dimensions = 3")
            .replace("[200, 160]", "[200, 160, 16]");
        let s = parse_scene(&format!("{spm_3d}bead_spin = \"chord\"\n")).unwrap();
        assert!(s.fibres[0].spin_with_chord);
        for (scene, why) in [
            (format!("{FPD_SHEAR}bead_spin = \"chord\"\n"), "SPM fluid"),
            (
                format!("{spm}bead_spin = \"rolling\"\n"),
                "expected \"free\" or \"chord\"",
            ),
            (with("bead_spin = \"chord\""), "only a bead-spring fibre"),
        ] {
            let e = err(&scene);
            assert!(e.contains(why), "{e}\n(expected `{why}`)");
        }
    }

    /// `wall_contact = true` takes the walls' faces from the scene (FPD: the bounce-back
    /// walls of the 160-row lattice; SPM: the faces of 4-row slabs), and is refused without
    /// walls. Every scene with walls carries the faces for the `wall_overlap` diagnostic.
    #[test]
    fn wall_contact_reads_the_faces_of_the_scenes_walls() {
        let fpd = parse_scene(&format!("{FPD_SHEAR}wall_contact = true\n")).unwrap();
        assert_eq!(fpd.fibres[0].wall_contact, Some([-0.5, 159.5]));
        let spm = FPD_SHEAR.replace("\"fpd-lbm\"", "\"spm\"");
        let s = parse_scene(&format!("{spm}wall_contact = true\n")).unwrap();
        assert_eq!(s.fibres[0].wall_contact, Some([3.5, 155.5]));
        let off = parse_scene(&spm).unwrap();
        assert_eq!(off.fibres[0].wall_contact, None);
        assert_eq!(off.wall_faces, Some([3.5, 155.5]));
        let e = err(&with("wall_contact = true"));
        assert!(
            e.contains("fibre.0.wall_contact = true") && e.contains("needs walls"),
            "{e}"
        );
        assert_eq!(parse_scene(BASE).unwrap().wall_faces, None);
    }

    /// K = 0, S2023's freely jointed limit, gives k_b = 0, as `bending_stiffness = 0` does; a
    /// bond still needs a stiffness.
    #[test]
    fn a_bending_number_of_zero_is_a_freely_jointed_chain() {
        let s = parse_scene(&format!("{FPD_SHEAR}bending_number = 0\n")).unwrap();
        assert_eq!(s.fibres[0].bending_stiffness, Some(0.0));
        let s = parse_scene(&format!("{FPD_SHEAR}bending_stiffness = 0\n")).unwrap();
        assert_eq!(s.fibres[0].bending_stiffness, Some(0.0));
        for bad in [
            "stretch_number = 0\n",
            "stretch_stiffness = 0\n",
            "bending_stiffness = -1\n",
        ] {
            assert!(parse_scene(&format!("{FPD_SHEAR}{bad}")).is_err(), "{bad}");
        }
    }

    /// Under SPM the gap is the rows between the wall slabs, ny - 2 T: a 200 x 168 grid with
    /// the default slabs of 4 has FPD's gap of 160, so the same K and K_s give the same k_b
    /// and k_s; thicker slabs, a narrower gap and a larger shear rate.
    #[test]
    fn the_groups_read_the_gap_between_the_spm_slabs() {
        let spm = FPD_SHEAR
            .replace("\"fpd-lbm\"", "\"spm\"")
            .replace("[200, 160]", "[200, 168]");
        let fpd = parse_scene(&format!(
            "{FPD_SHEAR}bending_number = 3.3\nstretch_number = 480\n"
        ))
        .unwrap();
        let s = parse_scene(&format!(
            "{spm}bending_number = 3.3\nstretch_number = 480\n"
        ))
        .unwrap();
        assert_eq!(s.coupling, Coupling::Spm);
        assert_eq!(s.shear_flow, fpd.shear_flow);
        assert_eq!(
            s.fibres[0].bending_stiffness,
            fpd.fibres[0].bending_stiffness
        );
        assert_eq!(
            s.fibres[0].stretch_stiffness,
            fpd.fibres[0].stretch_stiffness
        );
        let thick = spm.replace(
            "velocity = [-0.04, 0.04]",
            "velocity = [-0.04, 0.04]\nthickness = 24",
        );
        let s = parse_scene(&format!("{thick}bending_number = 3.3\n")).unwrap();
        let kb = s.fibres[0].bending_stiffness.unwrap();
        // gap 120: k_b = 3.3 x 0.5 x (0.08 / 120) x 6400 / 2
        assert!((kb - 3.52).abs() < 1e-12, "{kb}");
    }

    /// S2023 section II C inverted: k_s = K_s eta_f V0 l0 with V0 = 0.04 (walls at -+0.04) and
    /// l0 = d = 8: K_s = 480 gives k_s = 480 x 0.5 x 0.04 x 8 = 76.8; the scene's shear is
    /// kept for the reported groups.
    #[test]
    fn stretch_number_sets_the_stretch_stiffness_from_the_fpd_shear() {
        let s = parse_scene(&format!("{FPD_SHEAR}stretch_number = 480\n")).unwrap();
        let ks = s.fibres[0].stretch_stiffness.unwrap();
        assert!((ks - 76.8).abs() < 1e-12, "{ks}");
        let shear = s.shear_flow.unwrap();
        assert_eq!(shear.wall_speed, 0.04);
        assert!((shear.shear_rate - 0.08 / 160.0).abs() < 1e-18);
        let back = FibreGroup::Stretch.of(ks, shear, &s.fibres[0]);
        assert!((back - 480.0).abs() < 1e-10, "{back}");
        let e = err(&format!(
            "{FPD_SHEAR}stretch_number = 480\nstretch_stiffness = 1.0\n"
        ));
        assert!(e.contains("give either stretch_number"), "{e}");
        let e = err(&with("stretch_number = 4\n"));
        assert!(e.contains("only the bead-spring model"), "{e}");
    }

    /// The midpoint at x = nx / 2, y = (ny - 1) / 2: ten beads 8 apart along x on a 200 x 160
    /// lattice start at [64, 79.5] (`configs/fpd/flexible_shear.toml`); in 3D, z = nz / 2.
    #[test]
    fn a_centred_fibre_starts_at_the_centre_of_the_gap() {
        let s = parse_scene(&format!("{FPD_SHEAR}centred = true\n")).unwrap();
        assert_eq!(s.fibres[0].start, [64.0, 79.5, 0.0]);
        let spm = "dimensions = 3\n[time]\ndt = 0.1\n[fluid]\nmethod = \"spm\"\ngrid = [32, 40, 16]\n\
                   [walls]\nvelocity = [0.0, 0.1]\n[[fibre]]\nmodel = \"cohesive-beam\"\nbeads = 3\n\
                   bead_radius = 2.0\nyoungs_modulus = 1.0\ndirection = [0, 1, 0]\ncentred = true\n";
        let s = parse_scene(spm).unwrap();
        assert_eq!(s.fibres[0].start, [16.0, 15.5, 8.0]);
        let e = err(&format!("{FPD_SHEAR}centred = true\nstart = [1, 2, 0]\n"));
        assert!(e.contains("either centred or start"), "{e}");
        let e = err(&with("centred = true"));
        assert!(e.contains("fibre.0.centred") && e.contains("walls"), "{e}");
    }

    #[test]
    fn bending_number_refusals_say_why() {
        let cases: &[(String, &str)] = &[
            (
                format!("{FPD_SHEAR}bending_number = 3.3\nbending_stiffness = 1.0\n"),
                "give either bending_number",
            ),
            (
                format!("{FPD_SHEAR}bending_number = -1.0\n"),
                "expected a number >= 0",
            ),
            (
                FPD_SHEAR.replace("velocity = [-0.04, 0.04]", "velocity = [0.0, 0.0]")
                    + "bending_number = 3.3\n",
                "needs a shear",
            ),
            (
                "dimensions = 2\n[time]\ndt = 1.0\n[[fibre]]\nmodel = \"bead-spring\"\nbeads = 10\n\
                 bead_radius = 4.0\nyoungs_modulus = 1.0\nbending_number = 3.3\n"
                    .to_string(),
                "needs a [fluid] between walls",
            ),
            (
                with("bending_number = 3.3\n[fluid]\nmethod = \"fpd-lbm\""),
                "only the bead-spring model",
            ),
        ];
        for (scene, expected) in cases {
            let e = err(scene);
            assert!(e.contains(expected), "{e}\n(expected `{expected}`)");
        }
    }

    #[test]
    fn refusals_name_the_key_the_value_and_what_was_expected() {
        let cases: &[(&str, &str)] = &[
            (
                "clamp = [12]",
                "fibre.0.clamp: bead index 12 is out of range for a fibre of 10 beads (expected -10..=9)",
            ),
            ("clamp = [-11]", "fibre.0.clamp: bead index -11"),
            (
                "clamp = [0]\nloads = [{ bead = 1 }, { bead = -10, force = [0, 1, 0] }]",
                "fibre.0.loads.1.bead: bead 0 is clamped (fibre.0.clamp), so a load on it does nothing",
            ),
            ("foo = 1", "fibre.0: unknown key `foo`"),
            ("damping = -1", "fibre.0.damping: expected a number >= 0, got -1"),
            ("substeps = 0", "fibre.0.substeps: expected an integer in 1..=1000000, got 0"),
            ("spacing = \"two\"", "fibre.0.spacing: expected a number, got the text \"two\""),
            ("direction = [0, 0, 0]", "fibre.0.direction: expected a non-zero vector"),
            ("direction = [1, 0, 1]", "fibre.0.direction: a 2D scene"),
            ("direction = [1, 0]", "fibre.0.direction"),
            ("start = [0, 0, 1]", "fibre.0.start: a 2D scene"),
            ("start = [1e300, 0, 0]", "fibre.0.start: [1e300, 0.0, 0.0] lies so far out"),
            ("density = nan", "fibre.0.density: expected a positive number, got NaN"),
            ("shear_modulus = inf", "fibre.0.shear_modulus: expected a positive number, got inf"),
            ("loads = [{ bead = 10 }]", "fibre.0.loads.0.bead: bead index 10 is out of range"),
            ("loads = [{ bead = 1, forse = [0, 1, 0] }]", "fibre.0.loads.0: unknown key `forse`"),
            ("loads = [{ bead = 1, force = [0, 1, 1] }]", "fibre.0.loads.0.force: a 2D scene"),
            ("loads = [{ bead = 1, torque = [1, 0, 0] }]", "fibre.0.loads.0.torque: a 2D scene"),
            ("loads = [{ force = [0, 1, 0] }]", "fibre.0.loads.0.bead is required and missing"),
            ("stretch_stiffness = 3", "fibre.0.stretch_stiffness: only the bead-spring model"),
            ("clamp = 3", "fibre.0.clamp: expected an array, got 3"),
            ("beam_forces = \"exact\"", "fibre.0.beam_forces: expected \"paper\" or \"energy-consistent\", got \"exact\""),
        ];
        for (extra, want) in cases {
            let e = err(&with(extra));
            assert!(e.starts_with(want), "{extra}\n got: {e}\nwant: {want}");
        }
    }

    #[test]
    fn refusals_of_required_and_top_level_keys() {
        let replace = |from: &str, to: &str| err(&BASE.replace(from, to));
        assert_eq!(
            replace("bead_radius = 1.0", "bead_radius = -1"),
            "fibre.0.bead_radius: expected a positive number, got -1"
        );
        assert_eq!(
            replace("beads = 10", "beads = 0"),
            "fibre.0.beads: expected at least 1 bead, got 0"
        );
        assert!(replace("beads = 10", "beads = 2.5")
            .starts_with("fibre.0.beads: expected a whole number, got 2.5"));
        assert_eq!(
            replace("beads = 10\n", ""),
            "fibre.0.beads is required and missing"
        );
        assert_eq!(
            replace("\"cohesive-beam\"", "\"rope\""),
            "fibre.0.model: expected \"cohesive-beam\" or \"bead-spring\", got \"rope\""
        );
        assert_eq!(
            replace("dimensions = 2", "dimensions = 4"),
            "dimensions: expected 2 or 3, got 4"
        );
        assert_eq!(
            replace("dt = 0.1", "dt = 0"),
            "time.dt: expected a positive number, got 0"
        );
        assert_eq!(replace("dt = 0.1\n", ""), "time.dt is required and missing");
        assert!(replace("[[fibre]]", "[fibre]").starts_with("fibre: expected an array of tables"));
        assert!(err("dt = [").starts_with("the scene is not valid TOML"));
        // Bead-spring refuses a torque and reads its stiffness overrides.
        let bs = BASE.replace("cohesive-beam", "bead-spring");
        let e = err(&format!(
            "{bs}loads = [{{ bead = 2, torque = [0, 0, 1] }}]\n"
        ));
        assert!(
            e.starts_with("fibre.0.loads.0.torque: the bead-spring model"),
            "{e}"
        );
        let e = err(&format!("{bs}beam_forces = \"paper\"\n"));
        assert!(
            e.starts_with("fibre.0.beam_forces: only the cohesive-beam model"),
            "{e}"
        );
        assert!(
            parse_scene(&format!("{BASE}beam_forces = \"energy-consistent\"\n"))
                .unwrap()
                .fibres[0]
                .energy_consistent
        );
        let ok = parse_scene(&format!("{bs}bending_stiffness = 0.5\n")).unwrap();
        assert_eq!(ok.fibres[0].bending_stiffness, Some(0.5));
        // The second fibre is named by its index.
        let two = format!("{BASE}\n[[fibre]]\nmodel = \"bead-spring\"\nbeads = 0\nbead_radius = 1\nyoungs_modulus = 1\n");
        assert_eq!(err(&two), "fibre.1.beads: expected at least 1 bead, got 0");
    }

    #[test]
    fn never_panics_on_odd_input() {
        let odd = [
            "",
            "[[fibre]]",
            "time = 3\n[[fibre]]",
            "[time]\ndt = 1\nfibre = 3",
            "[time]\ndt = 1\nfibre = [1, 2]",
            "[time]\ndt = 1\n[[fibre]]\nmodel = 3",
            "[time]\ndt = 1\n[[fibre]]\nmodel = \"bead-spring\"\nbeads = -9223372036854775808\nbead_radius = 1\nyoungs_modulus = 1",
            "[time]\ndt = 1\n[[fibre]]\nmodel = \"bead-spring\"\nbeads = 9223372036854775807\nbead_radius = 1\nyoungs_modulus = 1",
            "[time]\ndt = 1\n[[fibre]]\nmodel = \"bead-spring\"\nbeads = 3\nbead_radius = 1\nyoungs_modulus = 1\nclamp = [-9223372036854775808]",
            "dimensions = \"2\"\n[time]\ndt = 1",
        ];
        for s in odd {
            assert!(parse_scene(s).is_err(), "{s}");
        }
    }
}
