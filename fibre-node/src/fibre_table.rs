//! One `[[fibre]]` table of the scene: its keys as written (`RawFibre`) and their validation
//! into a [`FibreConfig`]. Every refusal names the dotted path (`fibre.N.key`), the value and
//! what was expected.
use crate::config::{
    FibreConfig, LoadConfig, ModelKind, DEFAULT_ENERGY_CONSISTENT, DEFAULT_POISSON_RATIO,
    MAX_BEADS, MAX_SUBSTEPS,
};
use cosim::scene_keys::{positive, Num, Nums};
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFibre {
    model: String,
    beads: i64,
    bead_radius: f64,
    youngs_modulus: Option<f64>,
    shear_modulus: Option<f64>,
    density: Option<f64>,
    start: Option<[f64; 3]>,
    #[serde(default)]
    centred: bool,
    direction: Option<[f64; 3]>,
    spacing: Option<f64>,
    initial_bend: Option<f64>,
    #[serde(default)]
    self_contact: bool,
    #[serde(default)]
    fibre_contact: bool,
    #[serde(default)]
    wall_contact: bool,
    #[serde(default)]
    clamp: Vec<i64>,
    #[serde(default)]
    loads: Vec<RawLoad>,
    damping: Option<f64>,
    internal_damping: Option<f64>,
    substeps: Option<i64>,
    stretch_stiffness: Option<f64>,
    bending_stiffness: Option<f64>,
    affinity: Option<f64>,
    bending_number: Option<f64>,
    stretch_number: Option<f64>,
    beam_forces: Option<String>,
    bead_inertia: Option<String>,
    exchange: Option<String>,
    bead_spin: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLoad {
    bead: i64,
    force: Option<[f64; 3]>,
    torque: Option<[f64; 3]>,
}

pub(crate) fn non_negative(path: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{path}: expected a number >= 0, got {}", Num(v)))
    }
}

fn finite(path: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{path}: expected a finite number, got {}", Num(v)))
    }
}

fn finite_vec(path: &str, v: [f64; 3]) -> Result<[f64; 3], String> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(format!(
            "{path}: expected three finite numbers, got {}",
            Nums(&v)
        ))
    }
}

fn planar_vec(path: &str, v: [f64; 3], dims: u8) -> Result<[f64; 3], String> {
    if dims == 2 && v[2] != 0.0 {
        Err(format!(
            "{path}: a 2D scene lies in the x-y plane, expected z = 0, got {}",
            Nums(&v)
        ))
    } else {
        Ok(v)
    }
}

/// Resolve a bead index (negative counts from the end).
fn bead_index(path: &str, index: i64, beads: usize) -> Result<usize, String> {
    let n = beads as i64;
    let resolved = if index < 0 { index + n } else { index };
    if (0..n).contains(&resolved) {
        Ok(resolved as usize)
    } else {
        Err(format!(
            "{path}: bead index {index} is out of range for a fibre of {beads} beads (expected -{beads}..={})",
            n - 1
        ))
    }
}

/// A key with two named values: `false` for `values[0]`, `true` for `values[1]`.
fn switch(p: &str, key: &str, value: &str, values: [&str; 2]) -> Result<bool, String> {
    match values.iter().position(|v| *v == value) {
        Some(i) => Ok(i == 1),
        None => Err(format!(
            "{p}.{key}: expected {:?} or {:?}, got {value:?}",
            values[0], values[1]
        )),
    }
}

/// `wall_faces`: the y of the bottom and the top wall's face when the scene has walls
/// ([`cosim::scene_keys::wall_faces`]), which `wall_contact = true` needs. The keys are checked in
/// the order of the table's documentation, so a table with several faults is refused for the
/// first of them.
pub(crate) fn validate_fibre(
    p: &str,
    raw: RawFibre,
    dims: u8,
    wall_faces: Option<[f64; 2]>,
) -> Result<FibreConfig, String> {
    let model = model_kind(p, &raw.model)?;
    let beads = bead_count(p, raw.beads)?;
    let bead_radius = positive(&format!("{p}.bead_radius"), raw.bead_radius)?;
    let youngs_modulus = elastic_modulus(p, model, &raw)?;
    let shear_modulus = optional(p, "shear_modulus", raw.shear_modulus, positive)?
        .or(youngs_modulus.map(|e| e / (2.0 * (1.0 + DEFAULT_POISSON_RATIO))));
    let wall_contact = wall_contact(p, raw.wall_contact, wall_faces)?;
    let density = optional(p, "density", raw.density, positive)?.unwrap_or(1.0);
    let (start, direction) = placement(p, &raw, dims)?;
    let spacing = optional(p, "spacing", raw.spacing, positive)?.unwrap_or(2.0 * bead_radius);
    resolvable(p, start, spacing * beads as f64, spacing)?;
    let initial_bend = optional(p, "initial_bend", raw.initial_bend, finite)?.unwrap_or(0.0);
    let clamp = clamped_beads(p, &raw.clamp, beads)?;
    let loads = raw
        .loads
        .iter()
        .enumerate()
        .map(|(k, l)| load(&format!("{p}.loads.{k}"), l, beads, dims, model))
        .collect::<Result<Vec<_>, _>>()?;
    if let Some((k, l)) = loads
        .iter()
        .enumerate()
        .find(|(_, l)| clamp.contains(&l.bead))
    {
        return Err(format!(
            "{p}.loads.{k}.bead: bead {} is clamped ({p}.clamp), so a load on it does nothing; \
             load a free bead",
            l.bead
        ));
    }
    let damping = optional(p, "damping", raw.damping, non_negative)?.unwrap_or(0.0);
    let internal_damping =
        optional(p, "internal_damping", raw.internal_damping, non_negative)?.unwrap_or(0.0);
    let substeps = substeps(p, raw.substeps)?;
    let stretch_stiffness = bead_spring_only(
        p,
        model,
        "stretch_stiffness",
        raw.stretch_stiffness,
        positive,
    )?;
    // k_b = 0: a freely jointed chain (S2023's K -> 0).
    let bending_stiffness = bead_spring_only(
        p,
        model,
        "bending_stiffness",
        raw.bending_stiffness,
        non_negative,
    )?;
    let affinity = optional(p, "affinity", raw.affinity, finite)?.unwrap_or(0.0);
    let bending_number = optional(p, "bending_number", raw.bending_number, finite)?;
    let stretch_number = optional(p, "stretch_number", raw.stretch_number, finite)?;
    let switches = Switches::read(p, &raw, model, beads)?;
    Ok(FibreConfig {
        spin_with_chord: switches.spin_with_chord,
        energy_consistent: switches.energy_consistent,
        profile_inertia: switches.profile_inertia,
        implicit_exchange: switches.implicit_exchange,
        model,
        beads,
        bead_radius,
        youngs_modulus,
        shear_modulus,
        density,
        start,
        direction,
        spacing,
        initial_bend,
        self_contact: raw.self_contact,
        fibre_contact: raw.fibre_contact,
        wall_contact,
        centred: raw.centred,
        clamp,
        loads,
        damping,
        internal_damping,
        substeps,
        stretch_stiffness,
        bending_stiffness,
        affinity,
        bending_number,
        stretch_number,
    })
}

/// An optional number checked by `check` under its dotted path `{p}.{key}`.
fn optional(
    p: &str,
    key: &str,
    value: Option<f64>,
    check: fn(&str, f64) -> Result<f64, String>,
) -> Result<Option<f64>, String> {
    value.map(|x| check(&format!("{p}.{key}"), x)).transpose()
}

/// `youngs_modulus`: required by the cohesive beam; a bead-spring fibre reads it only for the
/// constants its scene does not give (`k_s` from `stretch_stiffness` or `stretch_number`,
/// `k_b` from `bending_stiffness` or `bending_number`), so there it may be left out when both
/// are given.
fn elastic_modulus(p: &str, model: ModelKind, raw: &RawFibre) -> Result<Option<f64>, String> {
    let key = format!("{p}.youngs_modulus");
    if let Some(e) = raw.youngs_modulus {
        return positive(&key, e).map(Some);
    }
    if model == ModelKind::CohesiveBeam {
        return Err(format!(
            "{key} is required and missing: the cohesive beam's stiffnesses all come from it \
             (Young's modulus E, L2020 eqs. 11-24)"
        ));
    }
    let lacking: Vec<(&str, &str)> = [
        (
            raw.stretch_stiffness.or(raw.stretch_number),
            ("k_s", "stretch_stiffness or stretch_number"),
        ),
        (
            raw.bending_stiffness.or(raw.bending_number),
            ("k_b", "bending_stiffness or bending_number"),
        ),
    ]
    .into_iter()
    .filter_map(|(given, what)| given.is_none().then_some(what))
    .collect();
    if lacking.is_empty() {
        return Ok(None);
    }
    let names: Vec<&str> = lacking.iter().map(|(k, _)| *k).collect();
    let keys: Vec<String> = lacking.iter().map(|(k, w)| format!("{k} ({w})")).collect();
    Err(format!(
        "{key} is required and missing: a bead-spring fibre takes from it the constants \
         of S2023 eq. 9 that its table does not give, here {}; give youngs_modulus, or \
         give {}",
        names.join(" and "),
        keys.join(" and ")
    ))
}

fn model_kind(p: &str, name: &str) -> Result<ModelKind, String> {
    match name {
        "cohesive-beam" => Ok(ModelKind::CohesiveBeam),
        "bead-spring" => Ok(ModelKind::BeadSpring),
        other => Err(format!(
            "{p}.model: expected \"cohesive-beam\" or \"bead-spring\", got {other:?}"
        )),
    }
}

/// One bead is a single rigid particle (e.g. a sphere in a periodic array).
fn bead_count(p: &str, beads: i64) -> Result<usize, String> {
    if beads < 1 {
        return Err(format!("{p}.beads: expected at least 1 bead, got {beads}"));
    }
    if beads > MAX_BEADS {
        return Err(format!(
            "{p}.beads: expected at most {MAX_BEADS} beads, got {beads}"
        ));
    }
    Ok(beads as usize)
}

fn wall_contact(
    p: &str,
    wanted: bool,
    wall_faces: Option<[f64; 2]>,
) -> Result<Option<[f64; 2]>, String> {
    match (wanted, wall_faces) {
        (false, _) => Ok(None),
        (true, Some(faces)) => Ok(Some(faces)),
        (true, None) => Err(format!(
            "{p}.wall_contact = true keeps the beads behind the walls' faces, so it needs \
             walls: a [walls] table and fluid.grid = [nx, ny]; remove the key"
        )),
    }
}

/// Refuse a fibre placed so far from the origin that double precision cannot hold its bead
/// spacing (there the beads would fall onto one another): the spacing must be resolved to
/// one part in a million at `|start| + length`.
fn resolvable(p: &str, start: [f64; 3], length: f64, spacing: f64) -> Result<(), String> {
    let far = start.iter().fold(length, |m, x| m.max(x.abs() + length));
    if far * f64::EPSILON > 1e-6 * spacing {
        return Err(format!(
            "{p}.start: {start:?} lies so far out that the bead spacing {} is not \
             resolved in double precision; place the fibre within the domain",
            Num(spacing)
        ));
    }
    Ok(())
}

/// The first bead's centre and the fibre's unit direction.
fn placement(p: &str, raw: &RawFibre, dims: u8) -> Result<([f64; 3], [f64; 3]), String> {
    if raw.centred && raw.start.is_some() {
        return Err(format!(
            "{p}.centred = true places the fibre's midpoint at the centre of the gap; give \
             either centred or start, not both"
        ));
    }
    let start = finite_vec(&format!("{p}.start"), raw.start.unwrap_or([0.0; 3]))?;
    let start = planar_vec(&format!("{p}.start"), start, dims)?;
    let dpath = format!("{p}.direction");
    let d = finite_vec(&dpath, raw.direction.unwrap_or([1.0, 0.0, 0.0]))?;
    let d = planar_vec(&dpath, d, dims)?;
    let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if !(norm > 0.0 && norm.is_finite()) {
        return Err(format!(
            "{dpath}: expected a non-zero vector, got {}",
            Nums(&d)
        ));
    }
    Ok((start, [d[0] / norm, d[1] / norm, d[2] / norm]))
}

/// The clamped beads, resolved, sorted and each once.
fn clamped_beads(p: &str, clamp: &[i64], beads: usize) -> Result<Vec<usize>, String> {
    let mut resolved = clamp
        .iter()
        .map(|&c| bead_index(&format!("{p}.clamp"), c, beads))
        .collect::<Result<Vec<_>, _>>()?;
    resolved.sort_unstable();
    resolved.dedup();
    Ok(resolved)
}

/// One `loads` entry under its dotted path `lp`.
fn load(
    lp: &str,
    l: &RawLoad,
    beads: usize,
    dims: u8,
    model: ModelKind,
) -> Result<LoadConfig, String> {
    let bead = bead_index(&format!("{lp}.bead"), l.bead, beads)?;
    let force = finite_vec(&format!("{lp}.force"), l.force.unwrap_or([0.0; 3]))?;
    let force = planar_vec(&format!("{lp}.force"), force, dims)?;
    let torque = finite_vec(&format!("{lp}.torque"), l.torque.unwrap_or([0.0; 3]))?;
    if dims == 2 && (torque[0] != 0.0 || torque[1] != 0.0) {
        return Err(format!(
            "{lp}.torque: a 2D scene turns only about z, expected [0, 0, tz], got {}",
            Nums(&torque)
        ));
    }
    if model == ModelKind::BeadSpring && torque != [0.0; 3] {
        return Err(format!(
            "{lp}.torque: the bead-spring model has no elastic bead rotation, expected [0, 0, 0], got {}",
            Nums(&torque)
        ));
    }
    Ok(LoadConfig {
        bead,
        force,
        torque,
    })
}

fn substeps(p: &str, substeps: Option<i64>) -> Result<usize, String> {
    match substeps {
        None => Ok(1),
        Some(s) if (1..=MAX_SUBSTEPS).contains(&s) => Ok(s as usize),
        Some(s) => Err(format!(
            "{p}.substeps: expected an integer in 1..={MAX_SUBSTEPS}, got {s}"
        )),
    }
}

/// A stiffness only the bead-spring model reads.
fn bead_spring_only(
    p: &str,
    model: ModelKind,
    key: &str,
    value: Option<f64>,
    check: fn(&str, f64) -> Result<f64, String>,
) -> Result<Option<f64>, String> {
    if value.is_some() && model != ModelKind::BeadSpring {
        return Err(format!(
            "{p}.{key}: only the bead-spring model reads this key (model is {:?})",
            model.name()
        ));
    }
    optional(p, key, value, check)
}

/// The table's keys with two named values.
struct Switches {
    energy_consistent: bool,
    profile_inertia: bool,
    implicit_exchange: bool,
    spin_with_chord: bool,
}

impl Switches {
    fn read(p: &str, raw: &RawFibre, model: ModelKind, beads: usize) -> Result<Self, String> {
        if raw.beam_forces.is_some() && model != ModelKind::CohesiveBeam {
            return Err(format!(
                "{p}.beam_forces: only the cohesive-beam model reads this key (model is {:?})",
                model.name()
            ));
        }
        let energy_consistent = match raw.beam_forces.as_deref() {
            None => DEFAULT_ENERGY_CONSISTENT,
            Some(v) => switch(p, "beam_forces", v, ["paper", "energy-consistent"])?,
        };
        let named = |key: &str, value: &Option<String>, values: [&str; 2]| {
            switch(p, key, value.as_deref().unwrap_or(values[0]), values)
        };
        let profile_inertia = named("bead_inertia", &raw.bead_inertia, ["solid", "profile"])?;
        let implicit_exchange = named("exchange", &raw.exchange, ["explicit", "implicit"])?;
        let spin_with_chord = named("bead_spin", &raw.bead_spin, ["free", "chord"])?;
        if spin_with_chord && (model != ModelKind::BeadSpring || beads < 2) {
            return Err(format!(
                "{p}.bead_spin: only a bead-spring fibre of two or more beads reads this key \
                 (a cohesive beam's beads turn with the beam already)"
            ));
        }
        Ok(Switches {
            energy_consistent,
            profile_inertia,
            implicit_exchange,
            spin_with_chord,
        })
    }
}
