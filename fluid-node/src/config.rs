//! The part of the scene the fluid node reads: `dimensions`, `time.dt`, the `[fluid]` and
//! `[walls]` tables (with `[fluid.binary]`, read by [`crate::binary_fluid::scene`]), and from
//! each `[[fibre]]` table only `beads` and `bead_radius` (plus `spacing`, `youngs_modulus` and
//! `affinity` when present). The fibre node owns and checks the other fibre keys.
//!
//! Units are grid units: the grid spacing is 1, lengths are in grid spacings.
//! Every refusal names the dotted key, the value and what was expected; nothing panics.
use cosim::scene_keys::Num;
use cosim::scene_keys::{
    self, describe_value as describe_toml, deserialize_at as deserialize, positive,
};
use serde::Deserialize;

/// Default `fluid.density`.
pub const DEFAULT_DENSITY: f64 = 1.0;
pub use cosim::profile::{DEFAULT_CUTOFF_OVER_XI, DEFAULT_XI};
/// Default `walls.thickness`, grid units (shared with the nodes that read the gap).
pub use cosim::scene_keys::DEFAULT_WALL_THICKNESS;
/// Smallest grid size along any axis.
pub const MIN_GRID: i64 = 8;
/// Largest number of grid cells accepted (512³).
pub const MAX_CELLS: u64 = 1 << 27;
/// Largest number of beads (all fibres together).
pub const MAX_BEADS: i64 = 1_000_000;

/// How the velocity starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitialVelocity {
    /// At rest.
    Rest,
    /// The linear profile between the walls (walls required).
    Couette,
}

/// Two solid slabs normal to y, at the bottom and top of the periodic y range.
#[derive(Debug, Clone, PartialEq)]
pub struct WallsConfig {
    /// x-velocities of the bottom and top slab.
    pub velocity: [f64; 2],
    /// Slab thickness (grid units): the inner faces are at y = thickness and
    /// y = ny - thickness.
    pub thickness: f64,
}

/// What the fluid node needs of one `[[fibre]]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct FibreInfo {
    pub beads: usize,
    pub bead_radius: f64,
    /// Rest distance between bead centres if given (default 2 bead_radius).
    pub spacing: f64,
    /// Young's modulus where it sets the fibre's bending (for the derived k0 / (eta gamma)
    /// and the elastocapillary number): `None` if not given, and for a bead-spring fibre whose
    /// table sets k_b itself (`bending_stiffness` or `bending_number`), which E then does not
    /// describe.
    pub youngs_modulus: Option<f64>,
    /// Bead-spring k_b if given (for the derived bending number K of S2023 eq. 18).
    pub bending_stiffness: Option<f64>,
    /// Wetting affinity psi0 (L2020 eq. 31; `fibre.N.affinity`, default 0, checked in
    /// [-1, 1] here since the fluid node uses it).
    pub affinity: f64,
}

impl FibreInfo {
    /// Extent of a straight fibre, end to end: (N_b - 1) spacing + 2 r_b (= 2 r_b N_b for
    /// touching beads).
    pub fn length(&self) -> f64 {
        (self.beads - 1) as f64 * self.spacing + 2.0 * self.bead_radius
    }
}

/// The validated fluid part of a scene.
#[derive(Debug, Clone, PartialEq)]
pub struct FluidConfig {
    /// 2 or 3.
    pub dimensions: usize,
    /// `time.dt`.
    pub dt: f64,
    /// `[nx, ny, nz]`, `nz = 1` in 2D.
    pub grid: [usize; 3],
    /// Dynamic viscosity eta.
    pub viscosity: f64,
    /// Density rho.
    pub density: f64,
    /// Interface width xi (L2020 eq. 25).
    pub xi: f64,
    /// Cut-off xi_c (L2020 eq. 25).
    pub xi_cutoff: f64,
    /// Body force density, `[fx, fy, fz]` (fz = 0 in 2D).
    pub body_force: [f64; 3],
    pub initial_velocity: InitialVelocity,
    pub walls: Option<WallsConfig>,
    pub fibres: Vec<FibreInfo>,
    /// `[fluid.binary]`: the ternary Cahn–Hilliard fluid (`None`: a single fluid).
    pub binary: Option<crate::binary_fluid::BinaryConfig>,
}

impl FluidConfig {
    /// Kinematic viscosity nu = eta / rho.
    pub fn kinematic_viscosity(&self) -> f64 {
        self.viscosity / self.density
    }

    /// Total number of beads.
    pub fn total_beads(&self) -> usize {
        self.fibres.iter().map(|f| f.beads).sum()
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFluid {
    method: String,
    grid: Vec<i64>,
    viscosity: f64,
    density: Option<f64>,
    xi: Option<f64>,
    xi_cutoff: Option<f64>,
    body_force: Option<Vec<f64>>,
    initial_velocity: Option<String>,
    binary: Option<toml::Value>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawWalls {
    velocity: Vec<f64>,
    thickness: Option<f64>,
}

/// Keys of `[fluid]`, as serde reads them.
const FLUID_KEYS: [&str; 9] = [
    "method",
    "grid",
    "viscosity",
    "density",
    "xi",
    "xi_cutoff",
    "body_force",
    "initial_velocity",
    "binary",
];
/// Keys of `[walls]`.
const WALLS_KEYS: [&str; 2] = ["velocity", "thickness"];

/// Refuse a key of `table` (at `prefix`) that is not in `known`, naming it and its value.
pub(crate) fn known_keys(prefix: &str, table: &toml::Value, known: &[&str]) -> Result<(), String> {
    if let Some(t) = table.as_table() {
        if let Some((k, v)) = t.iter().find(|(k, _)| !known.contains(&k.as_str())) {
            let list: Vec<String> = known.iter().map(|k| format!("`{k}`")).collect();
            let hint = scene_keys::did_you_mean(k, known.iter().copied());
            let list = list.join(", ");
            let v = describe_toml(v);
            return Err(if hint.is_empty() {
                format!("{prefix}.{k}: unknown key (set to {v}); expected one of {list}")
            } else {
                format!("{prefix}.{k}: unknown key (set to {v}){hint} (expected one of {list})")
            });
        }
    }
    Ok(())
}

fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

fn fmt_list<T: std::fmt::Display>(v: &[T]) -> String {
    let items: Vec<String> = v.iter().map(|x| x.to_string()).collect();
    format!("[{}]", items.join(", "))
}

/// Read the fluid node's part of a scene. The keys are checked in the order below, so a
/// scene with several faults is refused for the first of them.
pub fn parse_scene(scene_toml: &str) -> Result<FluidConfig, String> {
    let table = scene_keys::parse_table(scene_toml)?;
    let dimensions = scene_keys::dimensions(&table)? as usize;
    let dt = scene_keys::time_step(&table)?;

    let raw = raw_fluid(&table)?;
    let grid = grid_sizes(&raw.grid, dimensions)?;
    let viscosity = positive("fluid.viscosity", raw.viscosity)?;
    let density = match raw.density {
        Some(x) => positive("fluid.density", x)?,
        None => DEFAULT_DENSITY,
    };
    let xi = match raw.xi {
        Some(x) => positive("fluid.xi", x)?,
        None => DEFAULT_XI,
    };
    let xi_cutoff = match raw.xi_cutoff {
        Some(x) => positive("fluid.xi_cutoff", x)?,
        None => DEFAULT_CUTOFF_OVER_XI * xi,
    };
    let body_force = body_force(raw.body_force.as_deref(), dimensions)?;
    let walls = walls(&table, grid, xi_cutoff)?;
    let initial_velocity = initial_velocity(raw.initial_velocity.as_deref(), walls.is_some())?;
    let fibres = read_fibres(&table)?;
    check_cutoff_boxes(&fibres, &grid[..dimensions], xi_cutoff)?;
    let binary = match &raw.binary {
        None => None,
        Some(v) => {
            let wall_speed = walls
                .as_ref()
                .map_or(0.0, |w| w.velocity[0].abs().max(w.velocity[1].abs()));
            Some(crate::binary_fluid::scene::parse(
                v, dimensions, grid, wall_speed, dt,
            )?)
        }
    };

    Ok(FluidConfig {
        binary,
        dimensions,
        dt,
        grid,
        viscosity,
        density,
        xi,
        xi_cutoff,
        body_force,
        initial_velocity,
        walls,
        fibres,
    })
}

/// The `[fluid]` table as written, its keys known and its method the SPM.
fn raw_fluid(table: &toml::Table) -> Result<RawFluid, String> {
    let fluid =
        match table.get("fluid") {
            None => return Err(
                "fluid: the scene has no [fluid] table, so the fluid node has nothing to simulate"
                    .into(),
            ),
            Some(v @ toml::Value::Table(_)) => v.clone(),
            Some(v) => return Err(format!("fluid: expected a table, got {}", describe_toml(v))),
        };
    known_keys("fluid", &fluid, &FLUID_KEYS)?;
    let raw: RawFluid = deserialize("fluid", fluid)?;
    if raw.method != "spm" {
        return Err(format!(
            "fluid.method: expected \"spm\" (the Smoothed Profile Method; FPD on \
             lattice Boltzmann is not available yet), got {:?}",
            raw.method
        ));
    }
    Ok(raw)
}

/// `fluid.grid` as `[nx, ny, nz]` (`nz = 1` in 2D), each at least [`MIN_GRID`] and
/// [`MAX_CELLS`] in all.
fn grid_sizes(sizes: &[i64], dimensions: usize) -> Result<[usize; 3], String> {
    if sizes.len() != dimensions {
        let want = if dimensions == 2 {
            "[nx, ny]"
        } else {
            "[nx, ny, nz]"
        };
        return Err(format!(
            "fluid.grid: a {dimensions}D scene expects {want}, got {}",
            fmt_list(sizes)
        ));
    }
    let mut grid = [1usize; 3];
    let mut cells: u64 = 1;
    for (a, &n) in sizes.iter().enumerate() {
        if n < MIN_GRID {
            return Err(format!(
                "fluid.grid: expected sizes of at least {MIN_GRID} along every axis, got {}",
                fmt_list(sizes)
            ));
        }
        cells = cells.saturating_mul(n as u64);
        if cells > MAX_CELLS {
            return Err(format!(
                "fluid.grid: expected at most {MAX_CELLS} cells in all, got {}",
                fmt_list(sizes)
            ));
        }
        grid[a] = n as usize;
    }
    Ok(grid)
}

fn body_force(given: Option<&[f64]>, dimensions: usize) -> Result<[f64; 3], String> {
    let mut body_force = [0.0; 3];
    if let Some(f) = given {
        if f.len() != dimensions || f.iter().any(|x| !x.is_finite()) {
            let want = if dimensions == 2 {
                "[fx, fy]"
            } else {
                "[fx, fy, fz]"
            };
            return Err(format!(
                "fluid.body_force: expected {want} (finite numbers), got {}",
                fmt_list(f)
            ));
        }
        body_force[..dimensions].copy_from_slice(f);
    }
    Ok(body_force)
}

/// The `[walls]` table, if any: two finite speeds and a thickness that leaves a gap wide
/// enough for a bead's cut-off box.
fn walls(
    table: &toml::Table,
    grid: [usize; 3],
    xi_cutoff: f64,
) -> Result<Option<WallsConfig>, String> {
    let v = match table.get("walls") {
        None => return Ok(None),
        Some(v @ toml::Value::Table(_)) => v,
        Some(v) => return Err(format!("walls: expected a table, got {}", describe_toml(v))),
    };
    known_keys("walls", v, &WALLS_KEYS)?;
    let raw: RawWalls = deserialize("walls", v.clone())?;
    if raw.velocity.len() != 2 || raw.velocity.iter().any(|x| !x.is_finite()) {
        return Err(format!(
            "walls.velocity: expected [bottom, top] (two finite numbers), got {}",
            fmt_list(&raw.velocity)
        ));
    }
    let thickness = match raw.thickness {
        Some(t) => positive("walls.thickness", t)?,
        None => DEFAULT_WALL_THICKNESS,
    };
    let gap = grid[1] as f64 - 2.0 * thickness;
    let need = 2.0 * xi_cutoff + 2.0;
    if gap < need {
        return Err(format!(
            "walls.thickness: {} leaves a gap of {} grid units between the \
             walls' inner faces in a grid of ny = {}, expected at least {} \
             (2 fluid.xi_cutoff + 2)",
            Num(thickness),
            Num(gap),
            grid[1],
            Num(need)
        ));
    }
    Ok(Some(WallsConfig {
        velocity: [raw.velocity[0], raw.velocity[1]],
        thickness,
    }))
}

fn initial_velocity(given: Option<&str>, has_walls: bool) -> Result<InitialVelocity, String> {
    match given {
        None | Some("rest") => Ok(InitialVelocity::Rest),
        Some("couette") if has_walls => Ok(InitialVelocity::Couette),
        Some("couette") => Err(
            "fluid.initial_velocity: \"couette\" needs a [walls] table (the \
                                linear profile runs between the walls)"
                .into(),
        ),
        Some(other) => Err(format!(
            "fluid.initial_velocity: expected \"rest\" or \"couette\", got {other:?}"
        )),
    }
}

/// A bead's cut-off box must not wrap onto itself in the periodic grid.
fn check_cutoff_boxes(fibres: &[FibreInfo], sizes: &[usize], xi_cutoff: f64) -> Result<(), String> {
    for (n, f) in fibres.iter().enumerate() {
        let reach = f.bead_radius + xi_cutoff;
        let need = ((2.0 * reach).floor() as usize).saturating_add(2);
        let smallest = sizes.iter().copied().min().unwrap_or(0);
        if smallest < need {
            return Err(format!(
                "fibre.{n}.bead_radius: {} plus fluid.xi_cutoff {} needs a grid \
                 of at least {need} nodes along every axis, fluid.grid has {smallest}",
                Num(f.bead_radius),
                Num(xi_cutoff)
            ));
        }
    }
    Ok(())
}

/// `beads`, `bead_radius` (and `spacing`, `youngs_modulus`, `bending_stiffness` if they are
/// numbers) of each `[[fibre]]` table; the fibre node checks the rest.
pub fn read_fibres(table: &toml::Table) -> Result<Vec<FibreInfo>, String> {
    let list = match table.get("fibre") {
        None => return Ok(Vec::new()),
        Some(toml::Value::Array(a)) => a,
        Some(v) => {
            return Err(format!(
                "fibre: expected an array of tables ([[fibre]]), got {}",
                describe_toml(v)
            ))
        }
    };
    let mut out = Vec::with_capacity(list.len());
    let mut total: i64 = 0;
    for (n, v) in list.iter().enumerate() {
        let p = format!("fibre.{n}");
        let Some(t) = v.as_table() else {
            return Err(format!("{p}: expected a table, got {}", describe_toml(v)));
        };
        let beads = match t.get("beads") {
            None => return Err(format!("{p}.beads is required and missing")),
            Some(toml::Value::Integer(b)) if (1..=MAX_BEADS).contains(b) => *b,
            Some(v) => {
                return Err(format!(
                    "{p}.beads: expected an integer in 1..={MAX_BEADS}, got {}",
                    describe_toml(v)
                ))
            }
        };
        total += beads;
        if total > MAX_BEADS {
            return Err(format!(
                "{p}.beads: expected at most {MAX_BEADS} beads in all fibres together, got {total}"
            ));
        }
        let bead_radius = match t.get("bead_radius") {
            None => return Err(format!("{p}.bead_radius is required and missing")),
            Some(v) => match number(v) {
                Some(x) => positive(&format!("{p}.bead_radius"), x)?,
                None => {
                    return Err(format!(
                        "{p}.bead_radius: expected a positive number, got {}",
                        describe_toml(v)
                    ))
                }
            },
        };
        let spacing = t
            .get("spacing")
            .and_then(number)
            .filter(|s| s.is_finite() && *s > 0.0)
            .unwrap_or(2.0 * bead_radius);
        let bends_by_k_b = ["bending_stiffness", "bending_number"]
            .iter()
            .any(|k| t.contains_key(*k));
        let youngs_modulus = t
            .get("youngs_modulus")
            .and_then(number)
            .filter(|e| e.is_finite() && *e > 0.0 && !bends_by_k_b);
        let bending_stiffness = t.get("bending_stiffness").and_then(number);
        let affinity = match t.get("affinity") {
            None => 0.0,
            Some(v) => match number(v) {
                Some(a) if (-1.0..=1.0).contains(&a) => a,
                _ => {
                    return Err(format!(
                        "{p}.affinity: expected psi0 in [-1, 1] (L2020 eq. 31), got {}",
                        describe_toml(v)
                    ))
                }
            },
        };
        out.push(FibreInfo {
            affinity,
            beads: beads as usize,
            bead_radius,
            spacing,
            youngs_modulus,
            bending_stiffness,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASE: &str = r#"
dimensions = 2
[time]
dt = 0.1
steps = 10
[fluid]
method = "spm"
grid = [32, 24]
viscosity = 0.5
"#;

    fn err(scene: &str) -> String {
        match parse_scene(scene) {
            Ok(_) => panic!("accepted:\n{scene}"),
            Err(e) => e,
        }
    }

    #[test]
    fn defaults() {
        let c = parse_scene(BASE).unwrap();
        assert_eq!(c.dimensions, 2);
        assert_eq!(c.grid, [32, 24, 1]);
        assert_eq!(c.density, 1.0);
        assert_eq!(c.xi, 1.0);
        assert_eq!(c.xi_cutoff, 3.0);
        assert_eq!(c.body_force, [0.0; 3]);
        assert_eq!(c.initial_velocity, InitialVelocity::Rest);
        assert!(c.walls.is_none() && c.fibres.is_empty());
        let c = parse_scene(&BASE.replace("dt = 0.1", "dt = 1").replace("xi", "x")).unwrap();
        assert_eq!(c.dt, 1.0);
    }

    #[test]
    fn full_scene() {
        let s = format!(
            "{BASE}density = 2\nxi = 2\nbody_force = [1e-4, 0]\ninitial_velocity = \"couette\"\n\
             [walls]\nvelocity = [-0.01, 0.01]\nthickness = 3\n\
             [[fibre]]\nmodel = \"cohesive-beam\"\nbeads = 3\nbead_radius = 2.5\nyoungs_modulus = 10\nclamp = [0]\n\
             [[fibre]]\nbeads = 2\nbead_radius = 1\nspacing = 3\n"
        );
        let c = parse_scene(&s).unwrap();
        assert_eq!(c.xi_cutoff, 6.0);
        assert_eq!(c.body_force, [1e-4, 0.0, 0.0]);
        assert_eq!(c.initial_velocity, InitialVelocity::Couette);
        assert_eq!(
            c.walls,
            Some(WallsConfig {
                velocity: [-0.01, 0.01],
                thickness: 3.0
            })
        );
        assert_eq!(c.fibres.len(), 2);
        assert_eq!(c.fibres[0].youngs_modulus, Some(10.0));
        // A bead-spring fibre that sets k_b itself: E does not describe its bending.
        for k in ["bending_stiffness = 0.4", "bending_number = 3.3"] {
            let own = s.replace(
                "spacing = 3\n",
                &format!("spacing = 3\nyoungs_modulus = 1\n{k}\n"),
            );
            assert_eq!(
                parse_scene(&own).unwrap().fibres[1].youngs_modulus,
                None,
                "{k}"
            );
        }
        assert_eq!(c.fibres[0].length(), 15.0);
        assert_eq!(c.fibres[1].length(), 5.0);
        assert_eq!(c.total_beads(), 5);
        assert_eq!(c.kinematic_viscosity(), 0.25);
    }

    #[test]
    fn refusals_name_the_key_the_value_and_what_was_expected() {
        let cases: &[(&str, &str)] = &[
            ("foo = 1", "fluid.foo: unknown key (set to 1); expected one of `method`, `grid`, `viscosity`, `density`, `xi`, `xi_cutoff`, `body_force`, `initial_velocity`, `binary`"),
            ("density = -1", "fluid.density: expected a positive number, got -1"),
            ("xi = 0", "fluid.xi: expected a positive number, got 0"),
            ("xi_cutoff = nan", "fluid.xi_cutoff: expected a positive number, got NaN"),
            ("body_force = [1, 2, 3]", "fluid.body_force: expected [fx, fy] (finite numbers), got [1, 2, 3]"),
            ("body_force = 3", "fluid.body_force: expected an array, got 3"),
            ("initial_velocity = \"couette\"", "fluid.initial_velocity: \"couette\" needs a [walls] table"),
            ("initial_velocity = \"poiseuille\"", "fluid.initial_velocity: expected \"rest\" or \"couette\", got \"poiseuille\""),
            ("[fluid.binary]\nmobility = 1", "fluid.binary.initial is required and missing"),
            ("[fluid.binary]\ninitial = \"flat\"\nposition = 12\ncolour = 1", "fluid.binary.colour: unknown key (set to 1); expected one of `xi`, `e0`, `sigma`, `mobility`, `peclet`, `velocity_scale`, `stabilisation`, `wall_affinity`, `initial`, `normal`, `position`, `width`, `centre`, `radius`, `inside`"),
            ("[fluid.binary]\ninitial = \"flat\"\nposition = 12\nradius = 3", "fluid.binary.radius: does not apply to initial = \"flat\""),
            ("[fluid.binary]\ninitial = \"flat\"\nposition = 12\nnormal = [1, 1]", "fluid.binary.normal: expected an axis 0 or 1, or a vector along x or y"),
            ("[fluid.binary]\ninitial = \"droplet\"\ncentre = [1, 2]", "fluid.binary.radius: required with initial = \"droplet\""),
            ("[fluid.binary]\ninitial = \"droplet\"\ncentre = [1, 2]\nradius = 100", "fluid.binary.radius: expected less than half the smallest box length"),
            ("[fluid.binary]\ninitial = \"flat\"\nposition = 12\npeclet = 1", "fluid.binary.peclet: needs the velocity scale U0"),
            ("[fluid.binary]\ninitial = \"flat\"\nposition = 12\ne0 = 1\nsigma = 2", "fluid.binary.sigma: give either e0 or sigma"),
            ("[fluid.binary]\ninitial = \"bubble\"", "fluid.binary.initial: expected \"flat\", \"droplet\" or \"half-droplet\", got \"bubble\""),
            ("[[fibre]]\nbeads = 2\nbead_radius = 1\naffinity = 2", "fibre.0.affinity: expected psi0 in [-1, 1] (L2020 eq. 31), got 2"),
            ("[walls]\nvelocity = [0, 1]\nspeed = 2", "walls.speed: unknown key (set to 2); expected one of `velocity`, `thickness`"),
            ("[walls]\nvelocity = [0, 1, 2]", "walls.velocity: expected [bottom, top] (two finite numbers), got [0, 1, 2]"),
            ("[walls]\nthickness = 2", "walls.velocity is required and missing"),
            ("[walls]\nvelocity = [0, 1]\nthickness = 9", "walls.thickness: 9 leaves a gap of 6 grid units between the walls' inner faces in a grid of ny = 24, expected at least 8"),
            ("[walls]\nvelocity = [0, inf]", "walls.velocity: expected [bottom, top] (two finite numbers), got [0, inf]"),
            ("[[fibre]]\nbead_radius = 1", "fibre.0.beads is required and missing"),
            ("[[fibre]]\nbeads = 0\nbead_radius = 1", "fibre.0.beads: expected an integer in 1..=1000000, got 0"),
            ("[[fibre]]\nbeads = 2\nbead_radius = \"big\"", "fibre.0.bead_radius: expected a positive number, got the string \"big\""),
            ("[[fibre]]\nbeads = 2\nbead_radius = 9", "fibre.0.bead_radius: 9 plus fluid.xi_cutoff 3 needs a grid of at least 26 nodes along every axis, fluid.grid has 24"),
        ];
        for (extra, want) in cases {
            let e = err(&format!("{BASE}{extra}\n"));
            assert!(e.starts_with(want), "{extra}\n got: {e}\nwant: {want}");
        }
    }

    #[test]
    fn refusals_of_required_and_top_level_keys() {
        let replace = |from: &str, to: &str| err(&BASE.replace(from, to));
        assert_eq!(
            replace("method = \"spm\"", "method = \"lbm\""),
            "fluid.method: expected \"spm\" (the Smoothed Profile Method; FPD on lattice \
             Boltzmann is not available yet), got \"lbm\""
        );
        assert_eq!(
            replace("method = \"spm\"\n", ""),
            "fluid.method is required and missing"
        );
        assert_eq!(
            replace("[32, 24]", "[32, 24, 8]"),
            "fluid.grid: a 2D scene expects [nx, ny], got [32, 24, 8]"
        );
        assert_eq!(
            replace("[32, 24]", "[32, 4]"),
            "fluid.grid: expected sizes of at least 8 along every axis, got [32, 4]"
        );
        assert!(replace("[32, 24]", "[32, 2.5]")
            .starts_with("fluid.grid.1: expected a whole number, got 2.5"));
        assert_eq!(
            replace("[32, 24]", "[65536, 65536]"),
            "fluid.grid: expected at most 134217728 cells in all, got [65536, 65536]"
        );
        assert_eq!(
            replace("viscosity = 0.5", "viscosity = 0"),
            "fluid.viscosity: expected a positive number, got 0"
        );
        assert_eq!(
            replace("dimensions = 2", "dimensions = 1"),
            "dimensions: expected 2 or 3, got 1"
        );
        assert_eq!(
            replace("dimensions = 2", ""),
            "fluid.grid: a 3D scene expects [nx, ny, nz], got [32, 24]"
        );
        assert_eq!(
            replace("dt = 0.1", "dt = -0.1"),
            "time.dt: expected a positive number, got -0.1"
        );
        assert_eq!(
            replace("dt = 0.1", "dt = \"x\""),
            "time.dt: expected a positive number, got the string \"x\""
        );
        assert!(replace("[fluid]", "[fluidx]").starts_with("fluid: the scene has no [fluid] table"));
        assert!(err("x = [").starts_with("the scene is not valid TOML"));
        assert!(err(&format!(
            "{BASE}[[fibre]]\nbeads = 2\nbead_radius = 1\n[[fibre]]\nbeads = -3\nbead_radius = 1\n"
        ))
        .starts_with("fibre.1.beads: expected an integer"));
    }

    #[test]
    fn never_panics_on_odd_input() {
        let odd = [
            "",
            "[fluid]",
            "fluid = 3\n[time]\ndt = 1",
            "[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [-9223372036854775808, 8, 8]\nviscosity = 1",
            "[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [9223372036854775807, 9223372036854775807, 8]\nviscosity = 1",
            "[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [8, 8, 8]\nviscosity = 1\n[walls]\nvelocity = [0, 0]\nthickness = 1e308",
            "[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [8, 8, 8]\nviscosity = 1\nfibre = 3",
            "[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [8, 8, 8]\nviscosity = 1\n[[fibre]]\nbeads = 9223372036854775807\nbead_radius = 1",
            "[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [8, 8, 8]\nviscosity = 1\n[[fibre]]\nbeads = 1\nbead_radius = 1e308",
            "[time]\ndt = 1\n[fluid]\nmethod = \"spm\"\ngrid = [8, 8, 8]\nviscosity = 1\nwalls = 1",
        ];
        for s in odd {
            assert!(parse_scene(s).is_err(), "{s}");
        }
    }
}
