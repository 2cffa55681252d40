//! Observables computed from the bead trajectory at the end of a run, each with its
//! reference where one exists (REFERENCE.md section 1).
use crate::reference::elastica;
use cosim::BeadState;
use serde::Serialize;
use std::collections::BTreeMap;

/// Metric names a scene may ask for in `analysis.metrics`.
pub const KNOWN: &[&str] = &["tip_deflection_over_length", "tip_rotation", "twist_angle"];

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
}

impl Metric {
    fn with_reference(value: f64, reference: f64, source: &str) -> Self {
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

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
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

/// Compute the requested metrics for fibre 0 from its initial and final bead states.
pub fn compute(
    names: &[String],
    scene: &crate::scene::Scene,
    beads_per_fibre: &[usize],
    derived: &[(String, f64)],
    initial: &[BeadState],
    last: &[BeadState],
    dimensionless: &mut BTreeMap<String, f64>,
) -> Result<BTreeMap<String, Metric>, String> {
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
