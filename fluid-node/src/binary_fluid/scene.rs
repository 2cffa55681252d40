//! The `[fluid.binary]` table of an SPM scene: the ternary Cahn–Hilliard parameters
//! (L2020 sections 2.4, 3) and the initial order parameter. Grid units (spacing 1); time in
//! the scene's unit. Every refusal names the dotted key, the value and what was expected.
use crate::cahn_hilliard::{self, CahnHilliardConfig, Fluid, Scheme};
use cosim::scene_keys::{describe_value as describe_toml, positive, Num};
use std::f64::consts::SQRT_2;

/// Keys of `[fluid.binary]`.
pub const BINARY_KEYS: [&str; 15] = [
    "xi",
    "e0",
    "sigma",
    "mobility",
    "peclet",
    "velocity_scale",
    "stabilisation",
    "wall_affinity",
    "initial",
    "normal",
    "position",
    "width",
    "centre",
    "radius",
    "inside",
];

/// Default `fluid.binary.xi` (grid units; L2020 sections 3.4–3.5 use 2, section 3.3 uses 3).
pub const DEFAULT_XI: f64 = 2.0;
/// Default `fluid.binary.e0`.
pub const DEFAULT_E0: f64 = 1.0;
/// Default `fluid.binary.mobility` (without `peclet`).
pub const DEFAULT_MOBILITY: f64 = 1.0;
/// Default `fluid.binary.stabilisation` (above the 2.815 that removes every diffusive limit,
/// `cahn_hilliard::limits::min_stabilisation(1)`).
pub const DEFAULT_STABILISATION: f64 = 3.0;

/// The order parameter at t = 0: the equilibrium tanh profile across every interface.
#[derive(Debug, Clone, PartialEq)]
pub enum InitialPsi {
    /// A periodic slab of fluid A of `width` along `axis` starting at `position` on the side
    /// the normal points to (`positive`), or ending there (`!positive`): two flat interfaces
    /// (L2020 sections 3.3–3.4: A above, B below).
    Flat {
        axis: usize,
        positive: bool,
        position: f64,
        width: f64,
    },
    /// A disk (2D) or sphere (3D) of `inside` fluid.
    Droplet {
        centre: [f64; 3],
        radius: f64,
        inside: Fluid,
    },
    /// Half a disk (sphere) of `inside` fluid on the side `normal` of its base centre
    /// `centre` (L2020 section 3.5).
    HalfDroplet {
        centre: [f64; 3],
        normal: [f64; 3],
        radius: f64,
        inside: Fluid,
    },
}

/// The validated `[fluid.binary]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct BinaryConfig {
    /// Cahn–Hilliard parameters (ξ, e0, M, S; `dt` = `time.dt`).
    pub ch: CahnHilliardConfig,
    /// Reference velocity U0 of L2020 eqs. 39–41 (length / time), if the scene sets one
    /// (`velocity_scale`, else the largest wall speed).
    pub velocity_scale: Option<f64>,
    /// ψ0 of the walls' solid (L2020 eq. 31 gives their ψ*). Default 0 (neutral).
    pub wall_affinity: f64,
    pub initial: InitialPsi,
}

impl BinaryConfig {
    /// σ_AB = (2 √2 / 3) e0 ξ (units e0 × length).
    pub fn sigma(&self) -> f64 {
        cahn_hilliard::sigma_ab(self.ch.e0, self.ch.xi)
    }
}

fn num(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

struct Table<'a> {
    t: &'a toml::Table,
}

impl Table<'_> {
    fn number(&self, key: &str) -> Result<Option<f64>, String> {
        match self.t.get(key) {
            None => Ok(None),
            Some(v) => match num(v) {
                Some(x) if x.is_finite() => Ok(Some(x)),
                _ => Err(format!(
                    "fluid.binary.{key}: expected a finite number, got {}",
                    describe_toml(v)
                )),
            },
        }
    }

    fn positive(&self, key: &str) -> Result<Option<f64>, String> {
        match self.number(key)? {
            None => Ok(None),
            Some(x) => positive(&format!("fluid.binary.{key}"), x).map(Some),
        }
    }

    /// A vector of `dims` finite numbers.
    fn vector(&self, key: &str, dims: usize) -> Result<Option<[f64; 3]>, String> {
        let Some(v) = self.t.get(key) else {
            return Ok(None);
        };
        let want = if dims == 2 { "[x, y]" } else { "[x, y, z]" };
        let bad = || {
            format!(
                "fluid.binary.{key}: expected {want} (finite numbers), got {}",
                describe_toml(v)
            )
        };
        let a = v.as_array().ok_or_else(bad)?;
        if a.len() != dims {
            return Err(bad());
        }
        let mut out = [0.0; 3];
        for (o, x) in out.iter_mut().zip(a) {
            *o = num(x).filter(|x| x.is_finite()).ok_or_else(bad)?;
        }
        Ok(Some(out))
    }

    fn required<T>(&self, key: &str, v: Option<T>, initial: &str) -> Result<T, String> {
        v.ok_or_else(|| {
            format!("fluid.binary.{key}: required with initial = \"{initial}\" (missing)")
        })
    }
}

/// Read `[fluid.binary]` (already known to be present) for a scene of `dims` dimensions on
/// `grid`, with the largest wall speed `wall_speed` (0 without walls) and `time.dt`. The keys
/// are checked in the order below, so a table with several faults is refused for the first.
pub fn parse(
    value: &toml::Value,
    dims: usize,
    grid: [usize; 3],
    wall_speed: f64,
    dt: f64,
) -> Result<BinaryConfig, String> {
    let Some(t) = value.as_table() else {
        return Err(format!(
            "fluid.binary: expected a table, got {}",
            describe_toml(value)
        ));
    };
    crate::config::known_keys("fluid.binary", value, &BINARY_KEYS)?;
    let tb = Table { t };
    let xi = tb.positive("xi")?.unwrap_or(DEFAULT_XI);
    let e0 = tb.energy_density(xi)?;
    let velocity_scale = match tb.positive("velocity_scale")? {
        Some(u) => Some(u),
        None if wall_speed > 0.0 => Some(wall_speed),
        None => None,
    };
    let mobility = tb.mobility(velocity_scale, e0)?;
    let stabilisation = match tb.number("stabilisation")? {
        Some(s) if s >= 0.0 => s,
        Some(s) => {
            return Err(format!(
                "fluid.binary.stabilisation: expected a number >= 0, got {}",
                cosim::scene_keys::Num(s)
            ))
        }
        None => DEFAULT_STABILISATION,
    };
    let wall_affinity = match tb.number("wall_affinity")? {
        Some(a) if a.abs() <= 1.0 => a,
        Some(a) => {
            return Err(format!(
                "fluid.binary.wall_affinity: expected psi0 in [-1, 1], got {a}"
            ))
        }
        None => 0.0,
    };
    let initial = tb.initial(dims, grid)?;
    Ok(BinaryConfig {
        ch: CahnHilliardConfig {
            xi,
            e0,
            mobility,
            dt,
            stabilisation,
            scheme: Scheme::SemiImplicit,
        },
        velocity_scale,
        wall_affinity,
        initial,
    })
}

impl Table<'_> {
    /// e0, given or from `sigma` (one of the two).
    fn energy_density(&self, xi: f64) -> Result<f64, String> {
        match (self.positive("e0")?, self.positive("sigma")?) {
            (Some(_), Some(_)) => Err(
                "fluid.binary.sigma: give either e0 or sigma (sigma = (2 sqrt 2 / 3) e0 xi), \
                 not both"
                    .into(),
            ),
            (Some(e), None) => Ok(e),
            // Invert σ_AB = (2 √2 / 3) e0 ξ.
            (None, Some(s)) => Ok(3.0 * s / (2.0 * SQRT_2 * xi)),
            (None, None) => Ok(DEFAULT_E0),
        }
    }

    /// M, given or from `peclet` (one of the two; the Péclet number needs U0).
    fn mobility(&self, velocity_scale: Option<f64>, e0: f64) -> Result<f64, String> {
        match (self.positive("mobility")?, self.positive("peclet")?) {
            (Some(_), Some(_)) => Err(
                "fluid.binary.peclet: give either mobility or peclet (Pe = U0 L0 / (e0 M), \
                 L2020 eq. 41), not both"
                    .into(),
            ),
            (Some(m), None) => Ok(m),
            (None, Some(pe)) => {
                let u0 = velocity_scale.ok_or(
                    "fluid.binary.peclet: needs the velocity scale U0 of L2020 eq. 41: set \
                     fluid.binary.velocity_scale (or moving walls)",
                )?;
                cahn_hilliard::mobility_from_peclet(pe, u0, 1.0, e0).map_err(|e| e.to_string())
            }
            (None, None) => Ok(DEFAULT_MOBILITY),
        }
    }

    /// `initial` and the keys of its kind; keys that belong to other kinds are refused
    /// rather than ignored.
    fn initial(&self, dims: usize, grid: [usize; 3]) -> Result<InitialPsi, String> {
        let t = self.t;
        let inside = match t.get("inside") {
            None => Fluid::A,
            Some(toml::Value::String(s)) if s == "A" => Fluid::A,
            Some(toml::Value::String(s)) if s == "B" => Fluid::B,
            Some(v) => {
                return Err(format!(
                    "fluid.binary.inside: expected \"A\" (psi = +1) or \"B\" (psi = -1), got {}",
                    describe_toml(v)
                ))
            }
        };
        let kind = match t.get("initial") {
            None => {
                return Err(
                    "fluid.binary.initial is required and missing (expected \"flat\", \
                            \"droplet\" or \"half-droplet\")"
                        .into(),
                )
            }
            Some(toml::Value::String(s)) => s.clone(),
            Some(v) => {
                return Err(format!(
                    "fluid.binary.initial: expected \"flat\", \"droplet\" or \"half-droplet\", \
                     got {}",
                    describe_toml(v)
                ))
            }
        };
        let allowed: &[&str] = match kind.as_str() {
            "flat" => &["normal", "position", "width"],
            "droplet" => &["centre", "radius", "inside"],
            "half-droplet" => &["centre", "radius", "inside", "normal"],
            other => {
                return Err(format!(
                    "fluid.binary.initial: expected \"flat\", \"droplet\" or \"half-droplet\", got \
                     {other:?}"
                ))
            }
        };
        for k in ["normal", "position", "width", "centre", "radius", "inside"] {
            if t.contains_key(k) && !allowed.contains(&k) {
                return Err(format!(
                    "fluid.binary.{k}: does not apply to initial = \"{kind}\" (its keys: {})",
                    allowed.join(", ")
                ));
            }
        }
        if kind == "flat" {
            return self.flat(dims, grid);
        }
        let centre = self.required("centre", self.vector("centre", dims)?, &kind)?;
        let radius = self.required("radius", self.positive("radius")?, &kind)?;
        // A droplet as wide as the periodic box touches its own image: a band, not a drop.
        let box_min = grid[..dims].iter().copied().min().unwrap_or(0) as f64;
        if radius >= 0.5 * box_min {
            return Err(format!(
                "fluid.binary.radius: expected less than half the smallest box length \
                 ({} of fluid.grid = {:?}), got {}: the droplet would touch its own periodic \
                 image",
                0.5 * box_min,
                &grid[..dims],
                Num(radius)
            ));
        }
        if kind == "droplet" {
            return Ok(InitialPsi::Droplet {
                centre,
                radius,
                inside,
            });
        }
        let normal = self.required("normal", self.vector("normal", dims)?, &kind)?;
        if normal.iter().all(|&v| v == 0.0) {
            return Err("fluid.binary.normal: expected a non-zero vector".into());
        }
        Ok(InitialPsi::HalfDroplet {
            centre,
            normal,
            radius,
            inside,
        })
    }

    /// `initial = "flat"`: the normal, the position and the slab's width (default half the
    /// box along the normal).
    fn flat(&self, dims: usize, grid: [usize; 3]) -> Result<InitialPsi, String> {
        let (axis, positive) = flat_normal(self.t.get("normal"), dims)?;
        let len = grid[axis] as f64;
        let position = self.required("position", self.number("position")?, "flat")?;
        let width = match self.positive("width")? {
            Some(w) if w < len => w,
            Some(w) => {
                return Err(format!(
                    "fluid.binary.width: expected less than the box length {len} along \
                     the normal, got {w}"
                ))
            }
            None => 0.5 * len,
        };
        Ok(InitialPsi::Flat {
            axis,
            positive,
            position,
            width,
        })
    }
}

/// `normal` of a flat interface: an axis index (fluid A on the + side) or a vector along
/// one axis (A on the side it points to). Default: the last axis (y in 2D, z in 3D), +.
fn flat_normal(v: Option<&toml::Value>, dims: usize) -> Result<(usize, bool), String> {
    let want = if dims == 2 {
        "an axis 0 or 1, or a vector along x or y such as [0, 1]"
    } else {
        "an axis 0, 1 or 2, or a vector along one axis such as [0, 0, 1]"
    };
    let bad = |v: &toml::Value| {
        format!(
            "fluid.binary.normal: expected {want} (a periodic box holds flat interfaces \
             normal to an axis only), got {}",
            describe_toml(v)
        )
    };
    match v {
        None => Ok((dims - 1, true)),
        Some(toml::Value::Integer(a)) if (0..dims as i64).contains(a) => Ok((*a as usize, true)),
        Some(v @ toml::Value::Array(a)) if a.len() == dims => {
            let x: Vec<f64> = a.iter().filter_map(num).collect();
            if x.len() != dims {
                return Err(bad(v));
            }
            let nonzero: Vec<usize> = (0..dims).filter(|&c| x[c] != 0.0).collect();
            match nonzero.as_slice() {
                [c] if x[*c].is_finite() => Ok((*c, x[*c] > 0.0)),
                _ => Err(bad(v)),
            }
        }
        Some(v) => Err(bad(v)),
    }
}
