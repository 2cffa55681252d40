//! Observables of a fibre at a fluidic interface (L2020 sections 3.4-3.5), from fibre 0's
//! final bead centres and the numbers the nodes derived when configured:
//!
//! - `final_tilt_deg`: the angle between fibre 0's end-to-end vector and the plane of the
//!   flat initial interface (normal `fluid.binary.normal`, default the last axis), in
//!   [0, 90] degrees. L2020 section 3.4: a fibre tilted by 50 degrees across the interface
//!   ends aligned with it (Figs. 9-11).
//! - `wrap`: how far fibre 0 winds around a droplet (L2020 section 3.5, Fig. 12). Value: the
//!   wrap fraction w = |Theta| (N - 1) / ((N - 2) 2 pi), Theta the net signed turning of the
//!   bead-centre polyline (the angle from the first to the last segment, unwrapped): the
//!   share of a circle the N beads would cover if the turning were uniform (the N - 2 turns
//!   between N - 1 segments stand for an arc of N - 1 segments). Label `full` (encapsulation)
//!   when the end beads are less than one bead diameter apart surface to surface
//!   (|X_0 - X_{N-1}| < 4 r_b: no bead fits between them) or w >= 1 (the ends passed each
//!   other); `partial` when w >= 0.05; `none` otherwise.
//! - `curvature_radius_over_droplet_radius`: R_c / R_droplet, R_c the radius of the circle
//!   fitted by least squares (orthogonal distances) to six successive bead centres
//!   (L2020 appendix C), the six around the middle of the fibre (beads (N-6)/2 ..
//!   (N-6)/2 + 5, the part that bends around the droplet; appendix C does not say which
//!   six), and R_droplet the equivalent radius of the initial droplet by L2020 eq. 45
//!   (derived `fluid.binary.initial_droplet_radius`).
use crate::metrics::{
    chord_sag, cross, dot, fibre0_bead_radius, lookup, norm, number, plain, sub, Context, Metric,
};
use crate::scene::Scene;
use std::f64::consts::PI;

/// Metric names this module computes.
pub const INTERFACE_METRICS: &[&str] = &[
    "final_tilt_deg",
    "wrap",
    "curvature_radius_over_droplet_radius",
];

/// Wrap fraction below which a fibre counts as not wrapped at all (`none`).
pub const WRAP_NONE_BELOW: f64 = 0.05;
/// Number of bead centres of the circle fit (L2020 appendix C).
pub const FIT_BEADS: usize = 6;

type P = [f64; 3];

/// Angle in degrees between the segment `a -> b` and the plane of normal `normal`, in
/// [0, 90]: asin(|d . n| / (|d| |n|)).
pub fn tilt_deg(a: P, b: P, normal: P) -> f64 {
    let d = sub(b, a);
    let s = (dot(d, normal).abs() / (norm(d) * norm(normal))).clamp(0.0, 1.0);
    s.asin().to_degrees()
}

/// Net signed turning angle (radians) of the polyline through `points`, about the axis
/// `normal` (the plane of the bend): the sum of the angles between successive segments
/// projected on the plane, so that the turns of an S-shape cancel.
pub fn net_turning(points: &[P], normal: P) -> f64 {
    let n = {
        let l = norm(normal);
        [normal[0] / l, normal[1] / l, normal[2] / l]
    };
    let project = |v: P| {
        let s = dot(v, n);
        [v[0] - s * n[0], v[1] - s * n[1], v[2] - s * n[2]]
    };
    let segs: Vec<P> = points
        .windows(2)
        .map(|w| project(sub(w[1], w[0])))
        .collect();
    segs.windows(2)
        .map(|w| dot(cross(w[0], w[1]), n).atan2(dot(w[0], w[1])))
        .sum()
}

/// Wrap fraction of `points` bent in the plane of normal `normal` (see the module text).
pub fn wrap_fraction(points: &[P], normal: P) -> f64 {
    let n = points.len();
    if n < 3 {
        return 0.0;
    }
    net_turning(points, normal).abs() * (n - 1) as f64 / ((n - 2) as f64 * 2.0 * PI)
}

/// Eigenvector of the smallest eigenvalue of a symmetric 3x3 matrix (cyclic Jacobi).
fn smallest_eigenvector(mut a: [[f64; 3]; 3]) -> P {
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        if off <= 1e-30 * (a[0][0].powi(2) + a[1][1].powi(2) + a[2][2].powi(2)) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            // A <- J^T A J with the rotation J in the (p, q) plane; V <- V J.
            for k in 0..3 {
                let (akp, akq) = (a[k][p], a[k][q]);
                a[k][p] = c * akp - s * akq;
                a[k][q] = s * akp + c * akq;
            }
            for k in 0..3 {
                let (apk, aqk) = (a[p][k], a[q][k]);
                a[p][k] = c * apk - s * aqk;
                a[q][k] = s * apk + c * aqk;
            }
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let k = (0..3)
        .min_by(|&i, &j| a[i][i].total_cmp(&a[j][j]))
        .unwrap_or(2);
    [v[0][k], v[1][k], v[2][k]]
}

/// A fitted circle: centre, radius, and the root-mean-square orthogonal distance of the
/// points to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    pub centre: P,
    pub radius: f64,
    pub rms_residual: f64,
}

/// Solve the 3x3 system `m x = r` by Cramer's rule; None if singular.
fn solve3(m: [[f64; 3]; 3], r: P) -> Option<P> {
    let det = |m: [[f64; 3]; 3]| dot(m[0], cross(m[1], m[2]));
    let d = det(m);
    let scale = m.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
    if !(d.abs() > 1e-12 * scale.powi(3)) {
        return None;
    }
    let mut out = [0.0; 3];
    for (c, o) in out.iter_mut().enumerate() {
        let mut mc = m;
        for (row, ri) in mc.iter_mut().zip(r) {
            row[c] = ri;
        }
        *o = det(mc) / d;
    }
    Some(out)
}

/// The circle fitted by least squares to `points` (at least 3): in their plane (the
/// plane of normal `normal` if given, as in a 2D scene, else the best-fit plane), the
/// algebraic fit of Kasa (exact for points on a circle) refined by Gauss-Newton on the
/// orthogonal distances. None for collinear points (infinite radius).
pub fn fit_circle(points: &[P], normal: Option<P>) -> Option<Circle> {
    let m = points.len();
    if m < 3 {
        return None;
    }
    let mean = centroid(points);
    let n = normal.unwrap_or_else(|| best_fit_normal(points));
    let n = {
        let l = norm(n);
        [n[0] / l, n[1] / l, n[2] / l]
    };
    // An orthonormal basis (e1, e2) of the plane.
    let helper = if n[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let e1 = {
        let c = cross(n, helper);
        let l = norm(c);
        [c[0] / l, c[1] / l, c[2] / l]
    };
    let e2 = cross(n, e1);
    let uv: Vec<(f64, f64)> = points
        .iter()
        .map(|p| {
            let d = sub(*p, mean);
            (dot(d, e1), dot(d, e2))
        })
        .collect();
    let size = uv
        .iter()
        .fold(0.0f64, |s, (u, v)| s.max((u * u + v * v).sqrt()));
    if size == 0.0 {
        return None;
    }
    // Kasa: minimise sum (u^2 + v^2 + D u + E v + F)^2 (coordinates scaled by `size`).
    let mut a = [[0.0; 3]; 3];
    let mut r = [0.0; 3];
    for &(u, v) in &uv {
        let (u, v) = (u / size, v / size);
        let row = [u, v, 1.0];
        let rhs = -(u * u + v * v);
        for i in 0..3 {
            for j in 0..3 {
                a[i][j] += row[i] * row[j];
            }
            r[i] += row[i] * rhs;
        }
    }
    let [d, e, f] = solve3(a, r)?;
    let (mut cu, mut cv) = (-0.5 * d * size, -0.5 * e * size);
    let r2 = (0.25 * (d * d + e * e) - f) * size * size;
    if !(r2 > 0.0) {
        return None;
    }
    let mut radius = r2.sqrt();
    let cost = |cu: f64, cv: f64, rad: f64| -> f64 {
        uv.iter()
            .map(|(u, v)| ((u - cu).hypot(v - cv) - rad).powi(2))
            .sum()
    };
    // Gauss-Newton on the residuals |p - c| - R; a step that does not lower the cost ends it.
    let mut best = cost(cu, cv, radius);
    for _ in 0..50 {
        let mut jtj = [[0.0; 3]; 3];
        let mut jtr = [0.0; 3];
        for &(u, v) in &uv {
            let dist = (u - cu).hypot(v - cv);
            if dist == 0.0 {
                return None;
            }
            let jac = [-(u - cu) / dist, -(v - cv) / dist, -1.0];
            let res = dist - radius;
            for i in 0..3 {
                for j in 0..3 {
                    jtj[i][j] += jac[i] * jac[j];
                }
                jtr[i] -= jac[i] * res;
            }
        }
        let Some(step) = solve3(jtj, jtr) else { break };
        let (nu, nv, nr) = (cu + step[0], cv + step[1], radius + step[2]);
        let c = cost(nu, nv, nr);
        if !(c < best) {
            break;
        }
        (cu, cv, radius, best) = (nu, nv, nr, c);
        if norm(step) <= 1e-14 * radius {
            break;
        }
    }
    let centre = [
        mean[0] + cu * e1[0] + cv * e2[0],
        mean[1] + cu * e1[1] + cv * e2[1],
        mean[2] + cu * e1[2] + cv * e2[2],
    ];
    Some(Circle {
        centre,
        radius,
        rms_residual: (best / m as f64).sqrt(),
    })
}

/// First bead of the `FIT_BEADS` successive beads centred on the middle of a fibre of `n`
/// beads (None with fewer than `FIT_BEADS` beads).
pub fn middle_window(n: usize) -> Option<usize> {
    (n >= FIT_BEADS).then(|| (n - FIT_BEADS) / 2)
}

/// Wrap of `points` (bead centres of radius `r_b`) bent in the plane of normal `normal`:
/// (wrap fraction, label) as defined in the module text.
pub fn classify_wrap(points: &[P], r_b: f64, normal: P) -> (f64, &'static str) {
    let w = wrap_fraction(points, normal);
    let ends = match (points.first(), points.last()) {
        (Some(a), Some(b)) => norm(sub(*b, *a)),
        _ => f64::INFINITY,
    };
    let label = if ends < 4.0 * r_b || w >= 1.0 {
        "full"
    } else if w >= WRAP_NONE_BELOW {
        "partial"
    } else {
        "none"
    };
    (w, label)
}

/// The unit normal of the flat initial interface of the scene's `[fluid.binary]`
/// (`normal`: an axis index or an axis-aligned vector; default the last axis).
fn interface_normal(scene: &Scene) -> Result<P, String> {
    let dims = scene.dimensions as usize;
    let binary = scene
        .fluid
        .as_ref()
        .and_then(|f| f.get("binary"))
        .and_then(|b| b.as_table())
        .ok_or("metric `final_tilt_deg` needs a binary fluid ([fluid.binary])")?;
    if binary.get("initial").and_then(|v| v.as_str()) != Some("flat") {
        return Err("metric `final_tilt_deg` needs a flat initial interface \
                    (fluid.binary.initial = \"flat\")"
            .into());
    }
    let mut n = [0.0; 3];
    match binary.get("normal") {
        None => n[dims.clamp(2, 3) - 1] = 1.0,
        Some(toml::Value::Integer(a)) if (0..3).contains(a) => n[*a as usize] = 1.0,
        Some(toml::Value::Array(a)) => {
            for (o, x) in n.iter_mut().zip(a) {
                *o = number(Some(x)).ok_or("fluid.binary.normal: expected numbers")?;
            }
        }
        Some(_) => return Err("fluid.binary.normal: expected an axis or a vector".into()),
    }
    if norm(n) == 0.0 {
        return Err("fluid.binary.normal: expected a non-zero vector".into());
    }
    Ok(n)
}

/// What the interface metrics read besides fibre 0's bead centres, taken once from the
/// scene and the derived quantities, so that a metric's value can be worked out from the
/// bead centres of any step: the last for the metric, earlier ones for its steadiness
/// ([`crate::steady_watch`]).
#[derive(Debug, Clone, PartialEq)]
pub struct InterfaceGeometry {
    dimensions: u8,
    /// The flat initial interface's normal, or why there is none.
    normal: Result<P, String>,
    bead_radius: Option<f64>,
    /// R_droplet of the initial droplet (L2020 eq. 45).
    droplet_radius: Option<f64>,
}

impl InterfaceGeometry {
    pub fn of(scene: &Scene, derived: &[(String, f64)]) -> Self {
        Self {
            dimensions: scene.dimensions,
            normal: interface_normal(scene),
            bead_radius: number(scene.fibre.first().and_then(|f| f.get("bead_radius"))),
            droplet_radius: lookup(derived, "fluid.binary.initial_droplet_radius"),
        }
    }

    /// The normal of the plane the fibre bends in: z in a 2D scene, else the best-fit plane
    /// of its bead centres.
    fn bend_normal(&self, points: &[P]) -> P {
        if self.dimensions == 2 {
            return [0.0, 0.0, 1.0];
        }
        best_fit_normal(points)
    }

    /// The circle fitted to the `FIT_BEADS` middle bead centres of `points`: (first fitted
    /// bead, circle; None for collinear centres).
    fn middle_circle(&self, points: &[P]) -> Result<(usize, Option<Circle>), String> {
        let first = middle_window(points.len()).ok_or_else(|| {
            format!(
                "metric `curvature_radius_over_droplet_radius` needs a fibre of at least \
                 {FIT_BEADS} beads"
            )
        })?;
        let normal = (self.dimensions == 2).then_some([0.0, 0.0, 1.0]);
        Ok((first, fit_circle(&points[first..first + FIT_BEADS], normal)))
    }

    fn droplet_radius(&self) -> Result<f64, String> {
        self.droplet_radius.ok_or_else(|| {
            "metric `curvature_radius_over_droplet_radius` needs an initial droplet \
             (derived `fluid.binary.initial_droplet_radius`, L2020 eq. 45)"
                .into()
        })
    }

    /// The value of interface metric `name` for fibre 0's bead centres `points` (at least
    /// two).
    pub fn value(&self, name: &str, points: &[P]) -> Result<f64, String> {
        let (first, last) = (points[0], points[points.len() - 1]);
        match name {
            "final_tilt_deg" => Ok(tilt_deg(first, last, self.normal.clone()?)),
            "wrap" => {
                let r_b = self
                    .bead_radius
                    .ok_or("metric `wrap` needs fibre.0.bead_radius")?;
                Ok(classify_wrap(points, r_b, self.bend_normal(points)).0)
            }
            "curvature_radius_over_droplet_radius" => {
                let r_c = self
                    .middle_circle(points)?
                    .1
                    .map_or(f64::INFINITY, |c| c.radius);
                Ok(r_c / self.droplet_radius()?)
            }
            other => Err(format!("`{other}` is not an interface metric")),
        }
    }
}

/// Fibre 0's final bead centres, and its bead radius.
fn fibre_zero(ctx: &Context, name: &str) -> Result<(Vec<P>, f64), String> {
    let n = *ctx
        .beads_per_fibre
        .first()
        .ok_or_else(|| format!("metric `{name}` needs a fibre"))?;
    if n < 2 || ctx.last.len() < n {
        return Err(format!(
            "metric `{name}` needs fibre 0 with at least 2 beads"
        ));
    }
    let r_b = fibre0_bead_radius(ctx)
        .ok_or_else(|| format!("metric `{name}` needs fibre.0.bead_radius"))?;
    Ok((ctx.last[..n].iter().map(|s| s.position).collect(), r_b))
}

/// The mean of `points`.
fn centroid(points: &[P]) -> P {
    let m = points.len() as f64;
    let mut c = [0.0; 3];
    for p in points {
        for k in 0..3 {
            c[k] += p[k] / m;
        }
    }
    c
}

/// The normal of the plane through `points` that fits them best: the eigenvector of the
/// smallest eigenvalue of their scatter matrix.
fn best_fit_normal(points: &[P]) -> P {
    let mean = centroid(points);
    let mut cov = [[0.0; 3]; 3];
    for p in points {
        let d = sub(*p, mean);
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += d[i] * d[j];
            }
        }
    }
    smallest_eigenvector(cov)
}

/// The interface metric `name` of fibre 0 at the end of the run, or what is missing.
pub fn interface_metric(name: &str, ctx: &Context) -> Result<Metric, String> {
    let (points, r_b) = fibre_zero(ctx, name)?;
    let (first, last) = (points[0], points[points.len() - 1]);
    let geometry = InterfaceGeometry::of(ctx.scene, ctx.derived);
    let mut m = plain(geometry.value(name, &points)?);
    match name {
        "final_tilt_deg" => {
            let normal = geometry.normal.clone()?;
            let n0 = ctx.initial.len().min(points.len());
            if n0 >= 2 {
                m.extra.insert(
                    "initial_tilt_deg".into(),
                    tilt_deg(
                        ctx.initial[0].position,
                        ctx.initial[n0 - 1].position,
                        normal,
                    ),
                );
            }
            // Heights along the normal, relative to the initial interface
            // (`fluid.binary.position`; mean psi is conserved, so the far interface moves
            // little): which end sits in which fluid, and how far the fibre's centre moved
            // off the interface (an affinity lifts it, L2020 Fig. 10). The fluid node's
            // `interface_position` is sampled half a box from bead 0, which for a long
            // fibre is at its other end's meniscus, so it is only reported.
            let l = norm(normal);
            let h = |p: P| dot(p, normal) / l;
            let base = ctx
                .scene
                .fluid
                .as_ref()
                .and_then(|f| f.get("binary"))
                .and_then(|b| number(b.get("position")))
                .unwrap_or(0.0)
                // The plane x_axis = position, at height +-position along an axis-aligned normal.
                * (normal[0] + normal[1] + normal[2])
                / l;
            let centre_height = points.iter().map(|&p| h(p)).sum::<f64>() / points.len() as f64;
            m.extra.insert("centre_height".into(), centre_height - base);
            m.extra.insert("first_end_height".into(), h(first) - base);
            m.extra.insert("last_end_height".into(), h(last) - base);
            if let Some(level) = lookup(ctx.diagnostics, "interface_position") {
                m.extra
                    .insert("interface_position_diagnostic".into(), level);
            }
            // Bending: the largest distance of a bead centre from the end-to-end chord.
            let sag = chord_sag(first, last, points.iter().copied());
            m.extra.insert("max_sag_over_r_b".into(), sag / r_b);
            m.note = "heights along the interface normal, from fluid.binary.position (the \
                      initial interface)"
                .into();
            Ok(m)
        }
        "wrap" => {
            let normal = geometry.bend_normal(&points);
            let label = classify_wrap(&points, r_b, normal).1;
            m.label = Some(label.to_string());
            let ends = norm(sub(last, first));
            let contour: f64 = points.windows(2).map(|p| norm(sub(p[1], p[0]))).sum();
            m.extra.insert("end_to_end".into(), ends);
            m.extra
                .insert("end_to_end_over_contour".into(), ends / contour);
            m.extra.insert(
                "end_gap_over_bead_diameter".into(),
                (ends - 2.0 * r_b) / (2.0 * r_b),
            );
            m.extra.insert(
                "net_turning_deg".into(),
                net_turning(&points, normal).abs().to_degrees(),
            );
            m.note = format!(
                "w = |net turning| (N-1) / ((N-2) 2 pi); full: end beads closer than 4 r_b \
                 or w >= 1; partial: w >= {WRAP_NONE_BELOW}"
            );
            Ok(m)
        }
        "curvature_radius_over_droplet_radius" => {
            let (first_bead, circle) = geometry.middle_circle(&points)?;
            let r_d = geometry.droplet_radius()?;
            let (r_c, rms) = circle.map_or((f64::INFINITY, 0.0), |c| (c.radius, c.rms_residual));
            m.extra.insert("curvature_radius".into(), r_c);
            m.extra.insert("droplet_radius".into(), r_d);
            m.extra.insert("fit_rms_residual".into(), rms);
            m.extra
                .insert("first_fitted_bead".into(), first_bead as f64);
            if let Some(ec) = lookup(ctx.derived, "fibre.0.elastocapillary") {
                m.extra.insert("elastocapillary".into(), ec);
            }
            m.note = format!(
                "circle through beads {first_bead}..={} by least squares (L2020 appendix C); \
                 R_droplet of the initial droplet by L2020 eq. 45",
                first_bead + FIT_BEADS - 1
            );
            Ok(m)
        }
        other => Err(format!("`{other}` is not an interface metric")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const Z: P = [0.0, 0.0, 1.0];

    /// `n` points on a circle of `radius` around `c`, from angle `a0` in steps of `da`.
    fn arc(c: P, radius: f64, a0: f64, da: f64, n: usize) -> Vec<P> {
        (0..n)
            .map(|i| {
                let a = a0 + da * i as f64;
                [c[0] + radius * a.cos(), c[1] + radius * a.sin(), c[2]]
            })
            .collect()
    }

    #[test]
    fn tilt_of_a_segment() {
        let n = [0.0, 1.0, 0.0];
        let t = |deg: f64| {
            let a = deg.to_radians();
            tilt_deg(
                [3.0, 4.0, 0.0],
                [3.0 + 5.0 * a.cos(), 4.0 + 5.0 * a.sin(), 0.0],
                n,
            )
        };
        assert!((t(50.0) - 50.0).abs() < 1e-12);
        // Folded into [0, 90]: the end order and the side do not matter.
        assert!((t(130.0) - 50.0).abs() < 1e-12);
        assert!((t(-50.0) - 50.0).abs() < 1e-12);
        assert!((t(180.0)).abs() < 1e-12);
        assert!((t(90.0) - 90.0).abs() < 1e-12);
        // A normal given as a non-unit vector.
        let v = tilt_deg([0.0; 3], [1.0, 0.0, 1.0], [0.0, 0.0, 7.0]);
        assert!((v - 45.0).abs() < 1e-12);
    }

    #[test]
    fn beads_on_a_circle_give_its_radius_exactly() {
        let c = [40.0, -7.0, 0.0];
        for (radius, da) in [(32.5, 0.18), (300.0, 0.04), (5.0, 1.0)] {
            let pts = arc(c, radius, 0.3, da, 6);
            let f = fit_circle(&pts, Some(Z)).unwrap();
            assert!((f.radius - radius).abs() < 1e-9 * radius, "{f:?}");
            assert!((f.centre[0] - c[0]).abs() < 1e-8 * radius, "{f:?}");
            assert!((f.centre[1] - c[1]).abs() < 1e-8 * radius, "{f:?}");
            assert!(f.rms_residual < 1e-9 * radius);
            // Without the plane given (3D): the same circle.
            let g = fit_circle(&pts, None).unwrap();
            assert!((g.radius - radius).abs() < 1e-9 * radius, "{g:?}");
        }
    }

    #[test]
    fn a_tilted_circle_in_3d() {
        // The circle of radius 20 in the plane spanned by (1,0,0) and (0,1,1)/sqrt 2.
        let (e1, e2) = ([1.0, 0.0, 0.0], [0.0, 0.5f64.sqrt(), 0.5f64.sqrt()]);
        let c = [5.0, 6.0, 7.0];
        let pts: Vec<P> = (0..6)
            .map(|i| {
                let a = 0.25 * i as f64;
                let (x, y) = (20.0 * a.cos(), 20.0 * a.sin());
                [
                    c[0] + x * e1[0] + y * e2[0],
                    c[1] + x * e1[1] + y * e2[1],
                    c[2] + x * e1[2] + y * e2[2],
                ]
            })
            .collect();
        let f = fit_circle(&pts, None).unwrap();
        assert!((f.radius - 20.0).abs() < 1e-9, "{f:?}");
        for k in 0..3 {
            assert!((f.centre[k] - c[k]).abs() < 1e-8, "{f:?}");
        }
    }

    #[test]
    fn noisy_points_give_the_least_squares_radius() {
        // Alternating radial offsets +-d about a circle of radius R: the orthogonal-distance
        // fit keeps the centre (by symmetry of the full ring) and finds R, rms d.
        let pts: Vec<P> = (0..12)
            .map(|i| {
                let a = i as f64 * PI / 6.0;
                let r = 10.0 + if i % 2 == 0 { 0.1 } else { -0.1 };
                [r * a.cos(), r * a.sin(), 0.0]
            })
            .collect();
        let f = fit_circle(&pts, Some(Z)).unwrap();
        assert!((f.radius - 10.0).abs() < 1e-9, "{f:?}");
        assert!((f.rms_residual - 0.1).abs() < 1e-9, "{f:?}");
    }

    #[test]
    fn collinear_points_have_no_circle() {
        let pts: Vec<P> = (0..6).map(|i| [i as f64 * 12.0, 3.0, 0.0]).collect();
        assert!(fit_circle(&pts, Some(Z)).is_none());
    }

    #[test]
    fn wrap_of_straight_arc_and_ring() {
        let r_b = 6.0;
        // Straight: no turning.
        let straight: Vec<P> = (0..18).map(|i| [12.0 * i as f64, 0.0, 0.0]).collect();
        assert_eq!(classify_wrap(&straight, r_b, Z), (0.0, "none"));
        // A closed ring of 18 beads with the ends one segment apart: w = (N-1)/N, full.
        let ring = arc([0.0; 3], 30.0, 0.0, 2.0 * PI / 18.0, 18);
        let (w, label) = classify_wrap(&ring, r_b, Z);
        assert!((w - 17.0 / 18.0).abs() < 1e-12, "{w}");
        assert_eq!(label, "full");
        // Half a circle (17 segments over pi): w = 1/2, ends 2R apart: partial.
        let half = arc([0.0; 3], 30.0, 0.0, PI / 17.0, 18);
        let (w, label) = classify_wrap(&half, r_b, Z);
        assert!((w - 0.5).abs() < 1e-12, "{w}");
        assert_eq!(label, "partial");
        // Turning the other way round gives the same fraction.
        let back = arc([0.0; 3], 30.0, 0.0, -PI / 17.0, 18);
        assert!((classify_wrap(&back, r_b, Z).0 - 0.5).abs() < 1e-12);
        // An S-shape: the two bends cancel.
        let mut s = arc([0.0, 0.0, 0.0], 30.0, -PI / 2.0, PI / 8.0, 5);
        s.extend(
            arc([60.0, 0.0, 0.0], 30.0, PI, -PI / 8.0, 5)
                .into_iter()
                .skip(1),
        );
        assert!((s[4][0] - 30.0).abs() < 1e-12 && s[4][1].abs() < 1e-12);
        assert!(net_turning(&s, Z).abs() < 1e-12);
    }

    #[test]
    fn middle_six_of_eighteen() {
        assert_eq!(middle_window(18), Some(6));
        assert_eq!(middle_window(10), Some(2));
        assert_eq!(middle_window(6), Some(0));
        assert_eq!(middle_window(5), None);
    }

    #[test]
    fn smallest_eigenvector_of_a_diagonal_and_a_rotated_matrix() {
        let v = smallest_eigenvector([[3.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]]);
        assert!((v[1].abs() - 1.0).abs() < 1e-12, "{v:?}");
        // diag(1, 2, 3) rotated by 45 degrees about z: smallest along (1, 1, 0)/sqrt 2.
        let m = [[1.5, -0.5, 0.0], [-0.5, 1.5, 0.0], [0.0, 0.0, 3.0]];
        let v = smallest_eigenvector(m);
        assert!((v[0].abs() - 0.5f64.sqrt()).abs() < 1e-12, "{v:?}");
        assert!((v[0] - v[1]).abs() < 1e-12, "{v:?}");
    }
}
