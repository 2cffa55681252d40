//! Unit quaternions for bead orientations (L2020 eqs. 1, 3-4 and appendix A).
//!
//! Conventions: a quaternion is `q = [q_s, q_x, q_y, q_z]` (scalar first, as in L2020 eq. 1
//! and [`cosim::BeadState::orientation`]); a unit quaternion rotates the body frame onto the
//! laboratory frame, `v_lab = q ⊗ v_body ⊗ q⁻¹`; the product is Hamilton's (nalgebra's `*`).
//!
//! L2020 eq. 3, `dq/dt = ½ A q`, with `A` of eq. 4 built from the laboratory-frame angular
//! velocity Ω, is `dq/dt = ½ [0, Ω] ⊗ q` (left multiplication). For a constant Ω over a step h
//! its exact solution is `q(t + h) = exp(Ω h / 2) ⊗ q(t)`, which [`advance`] implements; the
//! result is renormalised so that `|q| = 1` does not drift with round-off.
use nalgebra::{Quaternion, Vector3};

/// Quaternion type used throughout (nalgebra's, `Quaternion::new(s, x, y, z)`).
pub type Quat = Quaternion<f64>;
/// Laboratory-frame 3-vector.
pub type Vec3 = Vector3<f64>;

/// The identity rotation.
pub fn identity() -> Quat {
    Quat::new(1.0, 0.0, 0.0, 0.0)
}

/// From `[q_s, q_x, q_y, q_z]`.
pub fn from_array(a: [f64; 4]) -> Quat {
    Quat::new(a[0], a[1], a[2], a[3])
}

/// To `[q_s, q_x, q_y, q_z]`.
pub fn to_array(q: &Quat) -> [f64; 4] {
    [q.w, q.i, q.j, q.k]
}

/// Rotate `v` by the unit quaternion `q`: `q ⊗ [0, v] ⊗ q⁻¹`.
#[inline]
pub fn rotate(q: &Quat, v: &Vec3) -> Vec3 {
    let u = Vec3::new(q.i, q.j, q.k);
    let t = 2.0 * u.cross(v);
    v + q.w * t + u.cross(&t)
}

/// Rotate `v` by the inverse of the unit quaternion `q` (components of a laboratory vector in
/// the frame `q`).
#[inline]
pub fn rotate_inverse(q: &Quat, v: &Vec3) -> Vec3 {
    let u = Vec3::new(-q.i, -q.j, -q.k);
    let t = 2.0 * u.cross(v);
    v + q.w * t + u.cross(&t)
}

/// `q / |q|`.
#[inline]
pub fn normalize(q: &Quat) -> Quat {
    let n = (q.w * q.w + q.i * q.i + q.j * q.j + q.k * q.k).sqrt();
    Quat::new(q.w / n, q.i / n, q.j / n, q.k / n)
}

/// The same rotation with a non-negative scalar part (`q` and `-q` are one rotation).
#[inline]
pub fn canonical(q: &Quat) -> Quat {
    if q.w < 0.0 {
        -q
    } else {
        *q
    }
}

/// Small-angle rotation vector of L2020 (text after eq. 12): `θ ≈ 2 vec(q)`, taken on the
/// canonical representative (scalar part ≥ 0) so that it is the short way round.
#[inline]
pub fn small_angles(q: &Quat) -> Vec3 {
    let s = if q.w < 0.0 { -2.0 } else { 2.0 };
    Vec3::new(s * q.i, s * q.j, s * q.k)
}

/// Exact rotation angle of a unit quaternion, in [0, π].
pub fn rotation_angle(q: &Quat) -> f64 {
    let q = canonical(q);
    let v = (q.i * q.i + q.j * q.j + q.k * q.k).sqrt();
    2.0 * v.atan2(q.w)
}

/// `exp(φ / 2)` for a rotation vector φ (laboratory frame): the unit quaternion of a rotation
/// by `|φ|` about `φ / |φ|`.
#[inline]
pub fn exp_half(phi: &Vec3) -> Quat {
    let angle = phi.norm();
    let half = 0.5 * angle;
    // sin(half) / angle = ½ sin(half)/half, with its Taylor series near zero.
    let s = if half > 1e-5 {
        0.5 * half.sin() / half
    } else {
        0.5 * (1.0 - half * half / 6.0)
    };
    Quat::new(half.cos(), s * phi.x, s * phi.y, s * phi.z)
}

/// L2020 eq. 3 over one step with constant laboratory-frame Ω:
/// `q ← exp(Ω h / 2) ⊗ q`, renormalised.
#[inline]
pub fn advance(q: &Quat, omega: &Vec3, h: f64) -> Quat {
    normalize(&(exp_half(&(omega * h)) * q))
}

/// Shortest-arc rotation taking the unit vector `from` onto the unit vector `to`.
///
/// Built as `[1 + from·to, from × to]` normalised (L2020 eq. A.1 with `from = e_x`). Near
/// the antiparallel case `1 + c` is computed as `|from × to|² / (1 − c)`, which has no
/// cancellation; exactly antiparallel vectors get a half turn about an axis perpendicular to
/// `from` (about `e_z` when `from = e_x`, the limit reached in a 2D x-y plane).
pub fn shortest_arc(from: &Vec3, to: &Vec3) -> Quat {
    let c = from.dot(to);
    let axis = from.cross(to);
    let s2 = axis.norm_squared();
    let w = if c >= 0.0 { 1.0 + c } else { s2 / (1.0 - c) };
    let n2 = w * w + s2;
    if n2 > 1e-300 {
        let n = n2.sqrt();
        return Quat::new(w / n, axis.x / n, axis.y / n, axis.z / n);
    }
    // Antiparallel: a half turn about a unit axis perpendicular to `from`, chosen as the
    // cross product with the laboratory axis least aligned with `from`, preferring e_z so that
    // `from = e_x` gives a half turn about e_z.
    let a = from.abs();
    let helper = if a.z <= a.x && a.z <= a.y {
        Vec3::new(0.0, 0.0, 1.0)
    } else if a.y <= a.x {
        Vec3::new(0.0, 1.0, 0.0)
    } else {
        Vec3::new(1.0, 0.0, 0.0)
    };
    // The axis is the part of the helper perpendicular to `from`.
    let perp = helper - from * from.dot(&helper);
    let p = perp.normalize();
    Quat::new(0.0, p.x, p.y, p.z)
}

/// The beam-frame quaternion q* of L2020 appendix A: the shortest-arc rotation taking `e_x`
/// onto the unit beam vector `e_x'` (eq. 7). Its rotation matrix R* (eq. A.2) gives
/// `e_y' = R* e_y`, `e_z' = R* e_z` (eqs. 8-9). Robust near and at `e_x' = -e_x` (see
/// [`shortest_arc`]); at exactly `-e_x` the frame is a half turn about `e_z`.
pub fn beam_frame(e_x_prime: &Vec3) -> Quat {
    shortest_arc(&Vec3::x(), e_x_prime)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Vec3, b: &Vec3, tol: f64) -> bool {
        (a - b).norm() <= tol
    }

    #[test]
    fn beam_frame_maps_ex_onto_beam_vector_including_antiparallel() {
        let dirs = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.3, -0.4, 0.866),
            Vec3::new(-1.0, 1e-9, 0.0),
            Vec3::new(-1.0, 0.0, 1e-12),
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(-0.999999, 0.001, -0.0002),
        ];
        for d in dirs {
            let e = d.normalize();
            let q = beam_frame(&e);
            assert!((q.norm() - 1.0).abs() < 1e-15, "{q:?}");
            assert!(close(&rotate(&q, &Vec3::x()), &e, 1e-12), "{e:?}");
            let ey = rotate(&q, &Vec3::y());
            let ez = rotate(&q, &Vec3::z());
            assert!(close(&e.cross(&ey), &ez, 1e-12));
        }
        // Exactly antiparallel: half turn about e_z, so e_y' = -e_y, e_z' = e_z.
        let q = beam_frame(&Vec3::new(-1.0, 0.0, 0.0));
        assert_eq!(to_array(&q), [0.0, 0.0, 0.0, 1.0]);
        // Approaching -e_x within the x-y plane from either side tends to the same rotation.
        let a = beam_frame(&Vec3::new(-1.0, 1e-10, 0.0).normalize());
        let b = beam_frame(&Vec3::new(-1.0, -1e-10, 0.0).normalize());
        let ra = rotate(&a, &Vec3::y());
        let rb = rotate(&b, &Vec3::y());
        assert!(close(&ra, &rb, 1e-9));
    }

    #[test]
    fn beam_frame_matches_appendix_a_formula() {
        let e = Vec3::new(0.2, 0.7, -0.3).normalize();
        let q = beam_frame(&e);
        let raw = Quat::new(1.0 + e.x, 0.0, -e.z, e.y); // [1 + e_x·e, e_x × e]
        let raw = normalize(&raw);
        assert!((q - raw).norm() < 1e-15);
        // eq. A.2 rotation matrix columns are R e_x, R e_y, R e_z.
        let (s, x, y, z) = (q.w, q.i, q.j, q.k);
        let r = nalgebra::Matrix3::new(
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (y * x - s * z),
            2.0 * (z * x + s * y),
            2.0 * (x * y + s * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (z * y - s * x),
            2.0 * (x * z - s * y),
            2.0 * (y * z + s * x),
            1.0 - 2.0 * (x * x + y * y),
        );
        for v in [Vec3::x(), Vec3::y(), Vec3::z(), Vec3::new(0.3, 0.1, 2.0)] {
            assert!(close(&(r * v), &rotate(&q, &v), 1e-14));
        }
    }

    #[test]
    fn advance_is_exact_for_constant_omega_and_left_multiplies() {
        let q0 = normalize(&Quat::new(0.9, 0.1, -0.3, 0.2));
        let omega = Vec3::new(0.3, -1.2, 0.5);
        // Many small steps equal one big step (exact exponential, same axis).
        let mut q = q0;
        for _ in 0..1000 {
            q = advance(&q, &omega, 1e-3);
        }
        let q1 = advance(&q0, &omega, 1.0);
        assert!((q - q1).norm() < 1e-12);
        assert!((q.norm() - 1.0).abs() < 1e-15);
        // Left multiplication = rotation about a laboratory axis: a body vector mapped to the
        // lab frame is rotated by the lab rotation of angle |Ω| t about Ω.
        let v = Vec3::new(0.2, 0.5, -0.7);
        let before = rotate(&q0, &v);
        let after = rotate(&q1, &v);
        let rot = nalgebra::Rotation3::from_scaled_axis(omega);
        assert!(close(&(rot * before), &after, 1e-13));
        // Matches eq. 3-4: dq/dt = ½ A q for small h.
        let h = 1e-7;
        let dq = (advance(&q0, &omega, h) - q0) / h;
        let (ox, oy, oz) = (omega.x, omega.y, omega.z);
        let a = nalgebra::Matrix4::new(
            0.0, -ox, -oy, -oz, ox, 0.0, -oz, oy, oy, oz, 0.0, -ox, oz, -oy, ox, 0.0,
        );
        let qv = nalgebra::Vector4::new(q0.w, q0.i, q0.j, q0.k);
        let rhs = 0.5 * a * qv;
        let lhs = nalgebra::Vector4::new(dq.w, dq.i, dq.j, dq.k);
        assert!((lhs - rhs).norm() < 1e-6);
    }

    #[test]
    fn small_angles_and_rotation_angle() {
        let phi = Vec3::new(0.01, -0.02, 0.005);
        let q = exp_half(&phi);
        assert!(close(&small_angles(&q), &phi, 1e-6));
        assert!(close(&small_angles(&(-q)), &phi, 1e-6));
        assert!((rotation_angle(&q) - phi.norm()).abs() < 1e-15);
        assert!((rotation_angle(&exp_half(&Vec3::new(0.0, 3.0, 0.0))) - 3.0).abs() < 1e-14);
    }
}
