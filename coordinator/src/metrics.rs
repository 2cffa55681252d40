//! Observables computed from the bead trajectory at the end of a run, each with its
//! reference where one exists (REFERENCE.md section 1).
use crate::reference::elastica;
use crate::reference::stokes_chain_2d as stokes;
use cosim::BeadState;
use serde::Serialize;
use std::collections::BTreeMap;

/// What a metric needs of the scene's tables, and whether it reads fibre 0's orientation
/// at every step.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Needs {
    fluid: bool,
    walls: bool,
    binary: bool,
    fibre: bool,
    trajectory: bool,
}

const NONE: Needs = Needs {
    fluid: false,
    walls: false,
    binary: false,
    fibre: false,
    trajectory: false,
};
/// A fibre alone (cantilever, torsion).
const FIBRE: Needs = Needs {
    fibre: true,
    ..NONE
};
/// A fibre whose orientation is kept every step.
const TRACKED: Needs = Needs {
    trajectory: true,
    ..FIBRE
};
/// A fluid with a body held in it.
const FLUID: Needs = Needs {
    fluid: true,
    ..NONE
};
/// A fluid between walls.
const SHEAR: Needs = Needs {
    walls: true,
    ..FLUID
};
/// A fibre tracked in a wall shear (the orbit metrics, S2023 section IV).
const ORBIT: Needs = Needs {
    walls: true,
    fluid: true,
    ..TRACKED
};
/// A binary fluid (L2020 section 3.3).
const BINARY: Needs = Needs {
    binary: true,
    ..NONE
};
/// A fibre at a binary fluid's interface (L2020 sections 3.4-3.5).
const AT_INTERFACE: Needs = Needs {
    fibre: true,
    ..BINARY
};

/// Every metric a scene may ask for in `analysis.metrics`, with what it needs.
const METRICS: &[(&str, Needs)] = &[
    ("tip_deflection_over_length", FIBRE),
    ("tip_rotation", FIBRE),
    ("twist_angle", FIBRE),
    ("couette_max_error", SHEAR),
    ("drag_ratio", FLUID),
    ("drag_coefficient", FLUID),
    ("tumbling_period_gamma", ORBIT),
    ("min_end_to_end_over_length", TRACKED),
    ("bend_relaxation_time", TRACKED),
    ("orbit", ORBIT),
    ("half_turn_period_gamma", ORBIT),
    ("effective_aspect_ratio", ORBIT),
    ("stuck_angle_deg", ORBIT),
    ("surface_tension", BINARY),
    ("contact_angle_deg", BINARY),
    ("laplace_pressure_jump", BINARY),
    ("final_tilt_deg", AT_INTERFACE),
    ("wrap", AT_INTERFACE),
    ("curvature_radius_over_droplet_radius", AT_INTERFACE),
];

/// Metric names a scene may ask for in `analysis.metrics`.
pub fn known() -> impl Iterator<Item = &'static str> + Clone {
    METRICS.iter().map(|(name, _)| *name)
}

fn needs(name: &str) -> Option<Needs> {
    METRICS.iter().find(|(n, _)| *n == name).map(|(_, w)| *w)
}

/// What metric `name` needs of `scene` that the scene lacks, in words (`None`: nothing
/// missing, or not a metric), so that `check` refuses a metric no run of the scene could
/// compute. Only the tables are checked here; the run says what else is missing (a load, a
/// long enough run).
pub fn unmet_need(name: &str, scene: &crate::scene::Scene) -> Option<&'static str> {
    let w = needs(name)?;
    let beads_of_fibre_0 = scene
        .fibre
        .first()
        .and_then(|f| f.get("beads"))
        .and_then(|b| b.as_integer());
    let has_binary = scene
        .fluid
        .as_ref()
        .is_some_and(|f| f.contains_key("binary"));
    if w.fluid && scene.fluid.is_none() {
        Some("needs a fluid ([fluid]), which the scene has not")
    } else if w.walls && scene.walls.is_none() {
        Some("needs walls ([walls] velocity = [bottom, top]), which the scene has not")
    } else if w.binary && !has_binary {
        Some("needs a binary fluid ([fluid.binary]), which the scene has not")
    } else if w.fibre && scene.fibre.is_empty() {
        Some("needs a fibre ([[fibre]]), which the scene has not")
    } else if w.fibre && beads_of_fibre_0.is_some_and(|n| n < 2) {
        Some("needs fibre 0 to be a chain of 2 beads or more (a single bead has no ends to tell apart)")
    } else {
        None
    }
}

/// The orbit metrics (S2023 section IV), computed together by [`crate::orbit`].
const ORBIT_METRICS: &[&str] = &[
    "orbit",
    "half_turn_period_gamma",
    "effective_aspect_ratio",
    "stuck_angle_deg",
];

/// Whether metric `name` needs fibre 0's orientation at every step.
pub fn needs_trajectory(name: &str) -> bool {
    needs(name).is_some_and(|w| w.trajectory)
}

/// Everything a metric may look at, at the end of a run.
pub struct Context<'a> {
    pub scene: &'a crate::scene::Scene,
    pub beads_per_fibre: &'a [usize],
    /// Quantities the nodes derived when configured (rigidities, shear rate, ...).
    pub derived: &'a [(String, f64)],
    pub initial: &'a [BeadState],
    pub last: &'a [BeadState],
    /// Diagnostics of the last step, all nodes.
    pub diagnostics: &'a [(String, f64)],
    /// Impulses of the last step (fluid scenes).
    pub impulses: &'a [cosim::BeadImpulse],
    pub trajectory: &'a crate::trajectory::Trajectory,
    /// How much what each steady metric reads changed over the run's last fifth
    /// ([`crate::steady_watch`]), by metric.
    pub steady: &'a BTreeMap<String, crate::steady_watch::Change>,
}

/// The value named `key` in a list of named values (diagnostics, derived quantities).
pub fn lookup(list: &[(String, f64)], key: &str) -> Option<f64> {
    list.iter().find(|(k, _)| k == key).map(|(_, v)| *v)
}

/// A TOML number, integer or float.
pub(crate) fn number(v: Option<&toml::Value>) -> Option<f64> {
    v.and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
}

/// Longest chain the 2D Stokes reference is solved for: its dense solve grows as the cube
/// of the beads (about a second at 10 beads), so longer chains fall back to the 3D law.
const MAX_STOKES_BEADS: usize = 16;

/// Above this change of a cantilever's length (1 %), the tip metrics note that the
/// inextensible elastica leaves the stretching out.
const STRETCH_NOTE: f64 = 0.01;

/// Bretherton constant of fibre 0 as a rigid chain in unbounded 2D Stokes flow
/// ([`stokes::chain_bretherton`]), for a 2D scene whose fibre 0 is a straight chain of
/// 2 to [`MAX_STOKES_BEADS`] touching beads; `None` otherwise (3D, beads spaced apart, or a
/// longer chain).
fn stokes_2d_chain(ctx: &Context, beads: usize) -> Option<f64> {
    (ctx.scene.dimensions == 2 && (2..=MAX_STOKES_BEADS).contains(&beads) && touching(ctx, beads)?)
        .then(|| stokes::chain_bretherton(beads))
}

/// Whether fibre 0, of `beads` beads, is a straight chain of touching beads.
fn touching(ctx: &Context, beads: usize) -> Option<bool> {
    let r = fibre0_bead_radius(ctx)?;
    let length = lookup(ctx.derived, "fibre.0.length")?;
    Some((length - 2.0 * r * (beads as f64 - 1.0)).abs() <= 1e-9 * length)
}

/// Longest chain the 3D Stokes reference is solved for: a dense solve of 486 unknowns per
/// bead (about 5 s at 6 beads on one core); longer chains fall back to Harris & Pittman.
const MAX_STOKES_BEADS_3D: usize = 6;

/// Bretherton constant of fibre 0 as a rigid chain of touching spheres in unbounded 3D
/// Stokes flow ([`crate::reference::stokes_chain_3d::chain_bretherton`]), for a 3D scene
/// whose fibre 0 is a straight chain of 2 to [`MAX_STOKES_BEADS_3D`] touching beads.
fn stokes_3d_chain(ctx: &Context, beads: usize) -> Option<f64> {
    (ctx.scene.dimensions == 3
        && (2..=MAX_STOKES_BEADS_3D).contains(&beads)
        && touching(ctx, beads)?)
    .then(|| crate::reference::stokes_chain_3d::chain_bretherton(beads))
}

/// `fibre.0.bead_radius` of the scene.
pub(crate) fn fibre0_bead_radius(ctx: &Context) -> Option<f64> {
    number(ctx.scene.fibre.first().and_then(|f| f.get("bead_radius")))
}

/// A metric without a reference.
pub(crate) fn plain(value: f64) -> Metric {
    Metric {
        value,
        reference: None,
        relative_error: None,
        reference_source: String::new(),
        extra: BTreeMap::new(),
        label: None,
        note: String::new(),
    }
}

/// One observable with its reference.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Metric {
    pub value: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reference: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub relative_error: Option<f64>,
    /// Where the reference comes from.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub reference_source: String,
    /// Other numbers worth reporting next to it (e.g. small-deflection theory).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub extra: BTreeMap<String, f64>,
    /// A categorical result (the `orbit` class), next to its numeric code in `value`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub label: Option<String>,
    /// How the value was decided, in words.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub note: String,
}

impl Metric {
    /// A value with its reference and the relative error (absolute if the reference is 0).
    pub fn with_reference(value: f64, reference: f64, source: &str) -> Self {
        let relative_error = if reference != 0.0 {
            ((value - reference) / reference).abs()
        } else {
            (value - reference).abs()
        };
        Self {
            value,
            reference: Some(reference),
            relative_error: Some(relative_error),
            reference_source: source.to_string(),
            extra: BTreeMap::new(),
            label: None,
            note: String::new(),
        }
    }
}

/// What the metrics need to know about fibre 0: its model and tip loads from the scene,
/// its rigidities as the fibre node derived them (so defaults live in one place).
struct FibreZero<'a> {
    model: &'a str,
    bending_rigidity: f64,
    torsional_rigidity: Option<f64>,
    tip_force: [f64; 3],
    tip_torque: [f64; 3],
}

fn vec3(v: Option<&toml::Value>) -> [f64; 3] {
    let mut out = [0.0; 3];
    if let Some(toml::Value::Array(a)) = v {
        for (o, x) in out.iter_mut().zip(a) {
            *o = match x {
                toml::Value::Float(f) => *f,
                toml::Value::Integer(i) => *i as f64,
                _ => 0.0,
            };
        }
    }
    out
}

fn fibre_zero<'a>(
    scene: &'a crate::scene::Scene,
    derived: &[(String, f64)],
    beads: usize,
) -> Result<FibreZero<'a>, String> {
    let t = scene.fibre.first().ok_or("the scene has no fibre")?;
    let model = t.get("model").and_then(|v| v.as_str()).unwrap_or("");
    let get = |k: &str| derived.iter().find(|(n, _)| n == k).map(|(_, v)| *v);
    let bending_rigidity = get("fibre.0.bending_rigidity")
        .ok_or("the fibre node did not report fibre.0.bending_rigidity")?;
    let torsional_rigidity = get("fibre.0.torsional_rigidity");
    let (mut tip_force, mut tip_torque) = ([0.0; 3], [0.0; 3]);
    if let Some(toml::Value::Array(loads)) = t.get("loads") {
        for l in loads.iter().filter_map(|l| l.as_table()) {
            let b = l.get("bead").and_then(|b| b.as_integer()).unwrap_or(0);
            if b == -1 || b == beads as i64 - 1 {
                let (f, q) = (vec3(l.get("force")), vec3(l.get("torque")));
                for k in 0..3 {
                    tip_force[k] += f[k];
                    tip_torque[k] += q[k];
                }
            }
        }
    }
    Ok(FibreZero {
        model,
        bending_rigidity,
        torsional_rigidity,
        tip_force,
        tip_torque,
    })
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}
pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// Largest distance of `points` from the line through `first` and `last` (a fibre's bend
/// off its end-to-end chord); 0 when the two ends coincide.
pub(crate) fn chord_sag(
    first: [f64; 3],
    last: [f64; 3],
    points: impl Iterator<Item = [f64; 3]>,
) -> f64 {
    let chord = sub(last, first);
    let cl = norm(chord);
    points
        .map(|p| norm(cross(sub(p, first), chord)) / cl)
        .fold(0.0f64, f64::max)
}
fn scale(a: [f64; 3], s: f64) -> [f64; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Rotation q_final * conj(q_initial) as (scalar, vector), sign fixed so scalar >= 0.
fn relative_rotation(initial: [f64; 4], last: [f64; 4]) -> (f64, [f64; 3]) {
    let (a, b) = (last, [initial[0], -initial[1], -initial[2], -initial[3]]);
    let w = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    let v = [
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ];
    if w < 0.0 {
        (-w, scale(v, -1.0))
    } else {
        (w, v)
    }
}

/// Every metric of `names` that can be computed, and for each one that cannot, why (a run
/// too short for a period, a scene without what the metric needs): one metric that fails
/// does not cost a finished run the others. The orbit metrics rest on one analysis, so they
/// are computed (or fail) together.
pub fn compute_each(
    names: &[String],
    ctx: &Context,
    dimensionless: &mut BTreeMap<String, f64>,
) -> (BTreeMap<String, Metric>, BTreeMap<String, String>) {
    let (orbit, others): (Vec<String>, Vec<String>) = names
        .iter()
        .cloned()
        .partition(|n| ORBIT_METRICS.contains(&n.as_str()));
    let groups = std::iter::once(orbit)
        .filter(|g| !g.is_empty())
        .chain(others.into_iter().map(|n| vec![n]));
    let (mut done, mut failed) = (BTreeMap::new(), BTreeMap::new());
    for group in groups {
        match compute(&group, ctx, dimensionless) {
            Ok(m) => done.extend(m),
            Err(e) => failed.extend(group.into_iter().map(|n| (n, e.clone()))),
        }
    }
    (done, failed)
}

/// Compute the requested metrics for fibre 0 from its initial and final bead states, or the
/// first error.
pub fn compute(
    names: &[String],
    ctx: &Context,
    dimensionless: &mut BTreeMap<String, f64>,
) -> Result<BTreeMap<String, Metric>, String> {
    let mut out = BTreeMap::new();
    let mut beam_names = Vec::new();
    let orbit_names: Vec<&String> = names
        .iter()
        .filter(|n| ORBIT_METRICS.contains(&n.as_str()))
        .collect();
    if !orbit_names.is_empty() {
        let mut all = orbit_metrics(ctx)?;
        for n in orbit_names {
            if let Some(m) = all.remove(n.as_str()) {
                out.insert(n.clone(), m);
            }
        }
    }
    for name in names {
        if ORBIT_METRICS.contains(&name.as_str()) {
            continue;
        }
        let mut m = match name.as_str() {
            // Already an error relative to the wall-speed difference: its reference is 0, so
            // that studies plot it against wall time like any other error.
            "couette_max_error" => Metric::with_reference(
                lookup(ctx.diagnostics, "couette_max_error")
                    .ok_or("metric `couette_max_error` needs walls and a fluid that reports it")?,
                0.0,
                "the exact Couette profile (linear; S2023 eq. 13 with solid layers), error \
                     over the wall-speed difference",
            ),
            "drag_ratio" => drag_ratio(ctx)?,
            "drag_coefficient" => drag_coefficient(ctx)?,
            "surface_tension" | "contact_angle_deg" | "laplace_pressure_jump" => {
                crate::capillary_metrics::capillary_metric(
                    name,
                    ctx.diagnostics,
                    ctx.derived,
                    ctx.scene.dimensions.into(),
                )?
            }
            n if crate::interface_metrics::INTERFACE_METRICS.contains(&n) => {
                crate::interface_metrics::interface_metric(n, ctx)?
            }
            "tumbling_period_gamma" => tumbling_period(ctx)?,
            "min_end_to_end_over_length" => plain(
                ctx.trajectory
                    .min_end_to_end_ratio()
                    .ok_or("metric `min_end_to_end_over_length` needs a fibre")?,
            ),
            "bend_relaxation_time" => {
                let t = ctx.trajectory;
                let mut m = plain(
                    t.bend_relaxation_time()
                        .map_err(|e| format!("metric `bend_relaxation_time`: {e}"))?,
                );
                m.extra.insert("initial_sag".into(), t.sag[0]);
                m.extra.insert("final_sag".into(), t.sag[t.sag.len() - 1]);
                m.note = "time for fibre 0's largest bead distance from its end-to-end chord \
                          to fall to 1/e of its start (scene time units)"
                    .into();
                m
            }
            _ => {
                beam_names.push(name.clone());
                continue;
            }
        };
        if let Some(c) = ctx.steady.get(name) {
            steadiness(&mut m, c);
        }
        out.insert(name.clone(), m);
    }
    out.extend(beam_metrics(&beam_names, ctx, dimensionless)?);
    Ok(out)
}

/// `tumbling_period_gamma`: gamma T of fibre 0 against the same rigid chain in unbounded
/// Stokes flow (2D or 3D, where the chain is one the references solve), else Harris &
/// Pittman's law; REFERENCE.md's table and Harris & Pittman ride along in `extra`.
fn tumbling_period(ctx: &Context) -> Result<Metric, String> {
    let gamma = lookup(ctx.derived, "fluid.shear_rate")
        .ok_or("metric `tumbling_period_gamma` needs walls (a shear rate)")?;
    let period = ctx.trajectory.period().ok_or(
        "metric `tumbling_period_gamma`: fibre 0 did not pass the vertical twice; run longer",
    )?;
    let n = *ctx
        .beads_per_fibre
        .first()
        .ok_or("the scene has no fibre")?;
    // The chain's envelope: N_b for touching beads, longer for beads spaced apart.
    let aspect = match (
        fibre0_bead_radius(ctx),
        lookup(ctx.derived, "fibre.0.length"),
    ) {
        (Some(r), Some(l)) if r > 0.0 => (l + 2.0 * r) / (2.0 * r),
        _ => n as f64,
    };
    let harris_pittman = crate::reference::jeffery::cylinder_period_gamma(aspect);
    let stokes_chain = match (stokes_2d_chain(ctx, n), stokes_3d_chain(ctx, n)) {
        (Some(b), _) => Some((
            stokes::period_gamma(b),
            "2D Stokes flow past the same rigid chain of touching discs, \
             unbounded, sharp surfaces (boundary integral solution, \
             coordinator/src/reference/stokes_chain_2d.rs)",
        )),
        (None, Some(b)) => Some((
            crate::reference::stokes_chain_3d::period_gamma(b),
            "3D Stokes flow past the same rigid chain of touching spheres, \
             unbounded, tumbling in the shear plane (rigid multiblob \
             solution, coordinator/src/reference/stokes_chain_3d.rs)",
        )),
        (None, None) => None,
    };
    let mut m = match stokes_chain {
        Some((reference, source)) => {
            let mut m = Metric::with_reference(gamma * period, reference, source);
            m.extra.insert("harris_pittman".into(), harris_pittman);
            m
        }
        None => {
            let mut m = Metric::with_reference(gamma * period, harris_pittman, "");
            m.reference_source = format!(
                "Jeffery, gamma T = 2 pi (e + 1/e) with the equivalent ellipse e = 1.14 \
                 p^0.844 of Harris & Pittman (L2020 appendix B) for the chain's aspect ratio \
                 p = (L + 2 r_b) / (2 r_b) = {}",
                cosim::scene_keys::Sig(aspect)
            );
            // Say so: the Stokes references cover the scenes of docs/validation/spm.md.
            m.note = format!(
                "reference: Harris & Pittman's law for a cylinder of aspect ratio {} (the \
                 Stokes solutions here are for straight chains of touching beads, 2 to \
                 {MAX_STOKES_BEADS} in 2D and to {MAX_STOKES_BEADS_3D} in 3D)",
                cosim::scene_keys::Sig(aspect)
            );
            m
        }
    };
    m.extra.insert(
        "reference_md_table".into(),
        crate::reference::jeffery::chain_period_gamma_table(n),
    );
    m.extra.insert(
        "passes_through_vertical".into(),
        ctx.trajectory.vertical_crossings().len() as f64,
    );
    Ok(m)
}

/// The `orbit` label of a run too short to tell the orbit: less than a half-turn, not
/// stuck, and no fold undone (value null).
pub const UNDETERMINED_ORBIT: &str = "undetermined";

/// S2023's Jeffery fit for a rigid chain of 10 beads at C = 0.2, Re_ps << 1 (Fig. 5a).
const S2023_RIGID_ASPECT_RATIO: f64 = 0.132;

/// The orbit of fibre 0 in the wall shear (S2023 section IV, [`crate::orbit`]): all four
/// orbit metrics at once, so that they rest on one analysis.
fn orbit_metrics(ctx: &Context) -> Result<BTreeMap<&'static str, Metric>, String> {
    let gamma = lookup(ctx.derived, "fluid.shear_rate")
        .ok_or("the orbit metrics need walls (a shear rate)")?
        .abs();
    let n = *ctx
        .beads_per_fibre
        .first()
        .ok_or("the orbit metrics need a fibre")?;
    let a = crate::orbit::analyse_series(&ctx.trajectory.orientation_series(), n, gamma)
        .map_err(|e| format!("orbit analysis of fibre 0: {e}"))?;
    let scalars: BTreeMap<String, f64> = a
        .scalars()
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    let mut out = BTreeMap::new();

    // S2023's regimes (i)-(v): Jeffery, S-turn, S-coiled, Jeffery-stuck, S-stuck.
    let regime = match (a.kind, a.stuck_kind) {
        (crate::orbit::OrbitKind::Jeffery, _) => 1.0,
        (crate::orbit::OrbitKind::STurn, _) => 2.0,
        (crate::orbit::OrbitKind::SCoiled, _) => 3.0,
        (_, Some("s-stuck")) => 5.0,
        _ => 4.0,
    };
    // Less than a half-turn and not stuck: a fold seen and undone is an S-turn, but a fibre
    // still straight may fold later, and one still folded may straighten (S2023 classify
    // over whole turns).
    let premature = a.stuck_kind.is_none()
        && a.net_rotation_deg.abs() < 180.0
        && !matches!(a.kind, crate::orbit::OrbitKind::STurn);
    let mut orbit = plain(if premature { f64::NAN } else { regime });
    orbit.label = Some(if premature {
        UNDETERMINED_ORBIT.to_string()
    } else {
        a.kind.as_str().to_string()
    });
    orbit.note = match (a.stuck_kind, premature) {
        (Some(k), _) => format!("{k}: {}", a.reason),
        (None, true) => format!(
            "too short to classify (it would read {} so far): {}",
            a.kind.as_str(),
            a.reason
        ),
        (None, false) => a.reason.clone(),
    };
    orbit.extra = scalars.clone();
    orbit.extra.insert("folds".into(), a.folds as f64);
    orbit
        .extra
        .insert("straightenings".into(), a.straightenings as f64);
    orbit.extra.insert("tail_rate_deg".into(), a.tail_rate_deg);
    orbit
        .extra
        .insert("stuck_threshold_deg".into(), a.stuck_threshold_deg);
    out.insert("orbit", orbit);

    let mut period = plain(a.period_gamma.unwrap_or(f64::NAN));
    if a.period_gamma.is_none() {
        period.note = "fewer than two passes through 90 deg: no complete half-turn".into();
    }
    if let Some(r) = a.period_aspect_ratio {
        period.extra.insert("period_aspect_ratio".into(), r);
    }
    period
        .extra
        .insert("half_turns".into(), a.half_turns.len() as f64);
    out.insert("half_turn_period_gamma", period);

    let mut fit = match &a.jeffery_fit {
        Some(f) if n == 10 => Metric::with_reference(
            f.effective_aspect_ratio,
            S2023_RIGID_ASPECT_RATIO,
            "S2023 Fig. 5a: rigid 10-bead fibre, C = 0.2, Re_ps << 1",
        ),
        Some(f) => plain(f.effective_aspect_ratio),
        None => {
            let mut m = plain(f64::NAN);
            m.note =
                "no Jeffery fit (stuck fibre, too few samples, or no aspect ratio fits)".into();
            m
        }
    };
    if let Some(b) = stokes_2d_chain(ctx, n) {
        fit.extra.insert(
            "stokes_2d_aspect_ratio".into(),
            1.0 / stokes::equivalent_aspect_ratio(b),
        );
    }
    if let Some(f) = &a.jeffery_fit {
        fit.extra.insert("rms_residual".into(), f.rms_residual);
        fit.extra.insert("coefficient".into(), f.coefficient);
        fit.extra
            .insert("geometric_aspect_ratio".into(), 1.0 / n as f64);
        if let Some(r) = f.free_aspect_ratio {
            fit.extra.insert("free_aspect_ratio".into(), r);
        }
        if let Some(g) = f.free_shear_rate {
            fit.extra
                .insert("free_shear_rate_over_gamma".into(), g / gamma);
        }
    }
    out.insert("effective_aspect_ratio", fit);

    let mut stuck = plain(a.stuck_angle_deg.unwrap_or(f64::NAN));
    stuck.note = match a.stuck_kind {
        Some(k) => format!(
            "{k}; S2023 Fig. 7b at C = 0.87: 6.0 deg (S-stuck, K = 0.33, Re_ps = 1.5), \
             12.0 deg (Jeffery-stuck, K = 3.3, Re_ps = 6)"
        ),
        None => "not stuck".into(),
    };
    out.insert("stuck_angle_deg", stuck);
    Ok(out)
}

/// Drag coefficient `C_D = F / (rho U^2 d / 2)` of the beads held in a uniform stream
/// (`[fluid.stream]`, fpd-lbm; S2023 Fig. 4): F is minus the total force the fibre node put
/// on the beads at the last step (the holding force, which balances the drag once steady),
/// d = 2 a of fibre 0, Re = U d / nu as the fluid node derived it.
fn drag_coefficient(ctx: &Context) -> Result<Metric, String> {
    let need = |list: &[(String, f64)], key: &str| {
        lookup(list, key).ok_or_else(|| {
            format!(
                "metric `drag_coefficient` needs a uniform stream past held beads \
                 ([fluid.stream] with fluid.method = \"fpd-lbm\"; missing `{key}`)"
            )
        })
    };
    let u = need(ctx.derived, "fluid.stream.velocity")?;
    let re = need(ctx.derived, "fluid.stream.reynolds")?;
    let held = need(ctx.diagnostics, "total_bead_force_x")?;
    let fluid = ctx
        .scene
        .fluid
        .as_ref()
        .ok_or("metric `drag_coefficient` needs a fluid")?;
    let rho = number(fluid.get("density")).unwrap_or(1.0);
    let a =
        fibre0_bead_radius(ctx).ok_or("metric `drag_coefficient` needs fibre 0's bead_radius")?;
    let cd = -held / (0.5 * rho * u * u.abs() * 2.0 * a);
    let mut m = match crate::reference::cylinder::drag_coefficient(re) {
        Some((reference, source)) => Metric::with_reference(cd, reference, source),
        None => {
            let mut m = plain(cd);
            m.note = format!(
                "no reference at Re = {re}: Dennis & Chang give Re 10, 20, 40, Lamb's law holds \
                 for Re <= 1"
            );
            m
        }
    };
    m.extra.insert("reynolds".into(), re);
    if let Some(b) = lookup(ctx.derived, "fluid.stream.blockage") {
        m.extra.insert("blockage".into(), b);
    }
    Ok(m)
}

/// Drag on fibre 0's first bead held fixed in a periodic box driven by a body force, over the
/// periodic-array reference at the box's solid fraction (REFERENCE.md section 2).
fn drag_ratio(ctx: &Context) -> Result<Metric, String> {
    let fluid = ctx
        .scene
        .fluid
        .as_ref()
        .ok_or("metric `drag_ratio` needs a fluid")?;
    let grid: Vec<f64> = match fluid.get("grid") {
        Some(toml::Value::Array(a)) => a
            .iter()
            .filter_map(|v| v.as_integer())
            .map(|v| v as f64)
            .collect(),
        _ => return Err("metric `drag_ratio` needs fluid.grid".into()),
    };
    let eta = number(fluid.get("viscosity")).ok_or("metric `drag_ratio` needs fluid.viscosity")?;
    let r = fibre0_bead_radius(ctx).ok_or("metric `drag_ratio` needs fibre 0's bead_radius")?;
    let dt = ctx.scene.time.dt;
    // The fluid drags the held body along the flow (+x): the impulse it receives, over dt.
    let impulse = ctx
        .impulses
        .first()
        .ok_or("metric `drag_ratio`: no impulses were published")?;
    let force = impulse.impulse[0] / dt;
    let u = lookup(ctx.diagnostics, "mean_velocity_x")
        .ok_or("metric `drag_ratio` needs mean_velocity_x")?;
    let volume: f64 = grid.iter().product();
    let pi = std::f64::consts::PI;
    let (reference_force, source, c) = if grid.len() == 2 {
        let c = pi * r * r / volume;
        let (k, src) = crate::reference::periodic_array::cylinder_drag(c)?;
        (k * eta * u, src, c)
    } else {
        let c = 4.0 / 3.0 * pi * r.powi(3) / volume;
        let (k, src) = crate::reference::periodic_array::sphere_drag_factor(c)?;
        (6.0 * pi * eta * r * u * k, src, c)
    };
    let mut m = Metric::with_reference(force / reference_force, 1.0, source);
    m.extra.insert("solid_fraction".into(), c);
    m.extra.insert("drag_force".into(), force);
    m.extra.insert("mean_velocity".into(), u);
    Ok(m)
}

/// A steady metric's change `c` over the run's last fifth ([`crate::steady_watch`]), as an
/// extra value, and in its note where the state is not steady.
fn steadiness(m: &mut Metric, c: &crate::steady_watch::Change) {
    m.extra
        .insert(crate::steady_watch::CHANGE_EXTRA.into(), c.amount);
    if let Some(r) = c.remaining {
        m.extra
            .insert(crate::steady_watch::REMAINING_EXTRA.into(), r);
    }
    if let Some(why) = c.not_steady() {
        let not_steady = format!("not steady: {why}");
        m.note = if m.note.is_empty() {
            not_steady
        } else {
            format!("{}; {not_steady}", m.note)
        };
    }
}

/// The fibre-alone metrics of fibre 0 (cantilever and torsion).
fn beam_metrics(
    names: &[String],
    ctx: &Context,
    dimensionless: &mut BTreeMap<String, f64>,
) -> Result<BTreeMap<String, Metric>, String> {
    let (scene, beads_per_fibre, derived, initial, last) = (
        ctx.scene,
        ctx.beads_per_fibre,
        ctx.derived,
        ctx.initial,
        ctx.last,
    );
    let mut out = BTreeMap::new();
    if names.is_empty() {
        return Ok(out);
    }
    let n = *beads_per_fibre
        .first()
        .ok_or("metrics need at least one fibre")?;
    let f = fibre_zero(scene, derived, n)?;
    let (x0, xt0) = (initial[0].position, initial[n - 1].position);
    let axis_vec = sub(xt0, x0);
    let length = norm(axis_vec);
    let axis = scale(axis_vec, 1.0 / length);
    // The elastica is inextensible; the beams stretch (a strain P / (E A) under the load).
    let chord_sum = |b: &[BeadState]| {
        (1..n)
            .map(|i| norm(sub(b[i].position, b[i - 1].position)))
            .sum::<f64>()
    };
    let strain = chord_sum(last) / chord_sum(initial) - 1.0;
    for name in names {
        let m = match name.as_str() {
            "tip_deflection_over_length" | "tip_rotation" => {
                let p = norm(f.tip_force);
                if p == 0.0 || dot(f.tip_force, axis).abs() > 1e-12 * p {
                    return Err(format!(
                        "metric `{name}` needs a load on the last bead of fibre 0 perpendicular to the fibre"
                    ));
                }
                let load_dir = scale(f.tip_force, 1.0 / p);
                let alpha = p * length * length / f.bending_rigidity;
                dimensionless.insert("alpha".into(), alpha);
                let reference = elastica::tip(alpha);
                let stretch_note = if strain.abs() > STRETCH_NOTE {
                    format!(
                        "the fibre's length changed by {:+.1} %; the elastica is inextensible, so \
                         the difference includes the stretching",
                        100.0 * strain
                    )
                } else {
                    String::new()
                };
                if name == "tip_rotation" {
                    let value = if f.model == "bead-spring" {
                        // No bead orientation: the slope of the last segment.
                        let t0 = sub(initial[n - 1].position, initial[n - 2].position);
                        let t1 = sub(last[n - 1].position, last[n - 2].position);
                        (dot(t0, t1) / (norm(t0) * norm(t1)))
                            .clamp(-1.0, 1.0)
                            .acos()
                    } else {
                        let (w, v) =
                            relative_rotation(initial[n - 1].orientation, last[n - 1].orientation);
                        2.0 * norm(v).atan2(w)
                    };
                    let mut m = Metric::with_reference(
                        value,
                        reference.rotation,
                        "elastica (REFERENCE.md section 1)",
                    );
                    m.extra.insert("linear_theory".into(), alpha / 2.0);
                    m.extra.insert("axial_strain".into(), strain);
                    m.note = stretch_note;
                    m
                } else {
                    let value = dot(sub(last[n - 1].position, xt0), load_dir) / length;
                    let mut m = Metric::with_reference(
                        value,
                        reference.deflection,
                        "elastica (REFERENCE.md section 1)",
                    );
                    m.extra.insert("linear_theory".into(), alpha / 3.0);
                    m.extra.insert("alpha".into(), alpha);
                    m.extra.insert("axial_strain".into(), strain);
                    m.note = stretch_note;
                    m
                }
            }
            "twist_angle" => {
                let torque = dot(f.tip_torque, axis);
                if torque == 0.0 {
                    return Err(
                        "metric `twist_angle` needs an axial torque on the last bead of fibre 0"
                            .into(),
                    );
                }
                let (w, v) = relative_rotation(initial[n - 1].orientation, last[n - 1].orientation);
                let value = 2.0 * dot(v, axis).atan2(w);
                let gj = f
                    .torsional_rigidity
                    .ok_or("metric `twist_angle` needs a 3D cohesive-beam fibre")?;
                let reference = torque * length / gj;
                Metric::with_reference(value, reference, "T L / (G J), J = pi r^4 / 2")
            }
            other => return Err(format!("unknown metric `{other}`")),
        };
        out.insert(name.clone(), m);
    }
    Ok(out)
}
