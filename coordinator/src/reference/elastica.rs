//! Large deflection of a cantilever under a fixed-direction tip load (the elastica;
//! Bisshopp & Drucker 1945, Fertis 1993), from its closed form in elliptic integrals.
//!
//! With s in [0, 1] the arc length over L, theta the slope, and alpha = P L^2 / (E I):
//! theta'' = -alpha cos(theta), theta(0) = 0 (clamped), theta'(1) = 0 (no moment at the tip).
//! Bisshopp & Drucker integrate it once: with the tip angle theta_L, the modulus
//! p = sqrt((1 + sin theta_L) / 2) and sin phi1 = 1 / (p sqrt 2),
//! sqrt(alpha) = K(p) - F(phi1, p), delta_v / L = 1 - 2 (E(p) - E(phi1, p)) / sqrt(alpha),
//! x_tip / L = sqrt(2 sin theta_L / alpha).
//!
//! Large loads: the tip angle tends to pi / 2 exponentially fast (g = 1 - sin theta_L falls
//! like 32 exp(-2 sqrt(alpha))), so it is carried as g, never as 1 - g: K(p) comes from the
//! arithmetic-geometric mean of 1 and the complementary modulus sqrt(g / 2), which stays exact
//! however small g is, and the other two integrals are smooth at p = 1 (composite Simpson).
//! This holds to alpha ~ 1e5, where g reaches the smallest f64; beyond that g is held there,
//! which changes nothing at f64 precision. (Solving by shooting instead, as the tests do,
//! fails from alpha ~ 400 on: the root's curvature differs from the separatrix's by less
//! than f64 resolves.)

use std::f64::consts::{FRAC_PI_2, PI};

/// Tip of the deformed cantilever, in units of L.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ElasticaTip {
    /// Vertical tip displacement delta_v / L.
    pub deflection: f64,
    /// Horizontal shortening (L - x_tip) / L.
    pub shortening: f64,
    /// Tip rotation theta(1), radians.
    pub rotation: f64,
}

/// Composite Simpson intervals for the incomplete integrals (smooth integrands).
const SIMPSON_INTERVALS: usize = 2000;

fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let h = (b - a) / SIMPSON_INTERVALS as f64;
    let mut sum = f(a) + f(b);
    for i in 1..SIMPSON_INTERVALS {
        sum += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

/// K(p) from the complementary modulus p' = sqrt(1 - p^2): pi / (2 AGM(1, p')).
fn complete_first_kind(complementary: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, complementary);
    for _ in 0..64 {
        if a - b <= 4.0 * f64::EPSILON * a {
            break;
        }
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    PI / (a + b)
}

/// The elliptic integrals of the closed form at g = 1 - sin theta_L in (0, 1]:
/// (sqrt(alpha), E(p) - E(phi1, p)).
fn integrals(g: f64) -> (f64, f64) {
    let p2 = 1.0 - 0.5 * g;
    let phi1 = (1.0 / (2.0 * p2).sqrt()).min(1.0).asin();
    let w = |phi: f64| (1.0 - p2 * phi.sin().powi(2)).sqrt();
    let incomplete_first = simpson(|phi| 1.0 / w(phi), 0.0, phi1);
    let sqrt_alpha = complete_first_kind((0.5 * g).sqrt()) - incomplete_first;
    (sqrt_alpha, simpson(w, phi1, FRAC_PI_2))
}

/// Tip deflection, shortening and rotation for load parameter `alpha` >= 0.
pub fn tip(alpha: f64) -> ElasticaTip {
    if alpha <= 0.0 {
        return ElasticaTip {
            deflection: 0.0,
            shortening: 0.0,
            rotation: 0.0,
        };
    }
    let target = alpha.sqrt();
    // sqrt(alpha) falls as g grows: bisect on ln g.
    let (mut lo, mut hi) = (f64::MIN_POSITIVE.ln(), 0.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if integrals(mid.exp()).0 > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let g = (0.5 * (lo + hi)).exp();
    let (_, e) = integrals(g);
    ElasticaTip {
        deflection: 1.0 - 2.0 * e / target,
        shortening: 1.0 - (2.0 * (1.0 - g) / alpha).sqrt(),
        rotation: FRAC_PI_2 - 2.0 * (0.5 * g).sqrt().asin(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// REFERENCE.md section 1, table of the elastica (4 decimals).
    #[test]
    fn matches_reference_table() {
        let table = [
            (0.5, 0.1621, 0.0159, 0.2445),
            (1.0, 0.3017, 0.0564, 0.4614),
            (2.0, 0.4935, 0.1606, 0.7817),
            (3.0, 0.6033, 0.2544, 0.9860),
            (5.0, 0.7138, 0.3876, 1.2154),
            (10.0, 0.8106, 0.5550, 1.4303),
        ];
        for (alpha, dv, sh, rot) in table {
            let t = tip(alpha);
            assert!((t.deflection - dv).abs() < 6e-5, "alpha {alpha}: {t:?}");
            assert!((t.shortening - sh).abs() < 6e-5, "alpha {alpha}: {t:?}");
            assert!((t.rotation - rot).abs() < 6e-5, "alpha {alpha}: {t:?}");
        }
    }

    /// The boundary-value problem solved directly, by shooting on the root curvature
    /// theta'(0) with classical RK4 (4000 steps), as an independent check of the closed form.
    ///
    /// The first integral gives theta'(0) = sqrt(2 alpha (1 - g)), g = 1 - sin theta(1). The
    /// equation is a pendulum, and from alpha = (3 pi / 2)^2 = 22.2 on it has more roots:
    /// beams whose ends curl round. The cantilever's is the root nearest the separatrix
    /// sqrt(2 alpha), so g is scanned upwards from 1e-16 in tenths of a decade and the first
    /// sign change of theta'(1) bisected.
    fn by_shooting(alpha: f64) -> ElasticaTip {
        const STEPS: usize = 4000;
        let shoot = |k0: f64| {
            let f = |s: [f64; 4]| [s[1], -alpha * s[0].cos(), s[0].cos(), s[0].sin()];
            let h = 1.0 / STEPS as f64;
            let mut y = [0.0, k0, 0.0, 0.0];
            for _ in 0..STEPS {
                let a = f(y);
                let b = f(std::array::from_fn(|i| y[i] + 0.5 * h * a[i]));
                let c = f(std::array::from_fn(|i| y[i] + 0.5 * h * b[i]));
                let d = f(std::array::from_fn(|i| y[i] + h * c[i]));
                y = std::array::from_fn(|i| {
                    y[i] + h / 6.0 * (a[i] + 2.0 * b[i] + 2.0 * c[i] + d[i])
                });
            }
            y
        };
        let curvature = |g: f64| (2.0 * alpha * (1.0 - g)).sqrt();
        let (mut lo, mut hi) = (0.0, curvature(0.0));
        for j in 0..=160 {
            let k = curvature(10f64.powf(-16.0 + 0.1 * j as f64).min(1.0));
            if shoot(k)[1] < 0.0 {
                lo = k;
                break;
            }
            hi = k;
        }
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if shoot(mid)[1] < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let s = shoot(0.5 * (lo + hi));
        ElasticaTip {
            deflection: s[3],
            shortening: 1.0 - s[2],
            rotation: s[0],
        }
    }

    /// Closed form and shooting agree to 1e-6 wherever shooting can resolve the root,
    /// including the loads where the shooting problem has several roots (from 22.2).
    #[test]
    fn agrees_with_shooting() {
        for alpha in [0.01, 0.3, 1.0, 10.0, 22.0, 30.0, 35.0, 50.0, 100.0, 200.0] {
            let t = tip(alpha);
            let s = by_shooting(alpha);
            assert!(
                (t.deflection - s.deflection).abs() < 1e-6
                    && (t.shortening - s.shortening).abs() < 1e-6
                    && (t.rotation - s.rotation).abs() < 1e-6,
                "alpha {alpha}: closed form {t:?}, shooting {s:?}"
            );
        }
    }

    /// Small loads: delta / L -> alpha / 3, rotation -> alpha / 2 (Euler-Bernoulli).
    #[test]
    fn small_load_limit() {
        let a = 1e-4;
        let t = tip(a);
        assert!((t.deflection / (a / 3.0) - 1.0).abs() < 1e-6, "{t:?}");
        assert!((t.rotation / (a / 2.0) - 1.0).abs() < 1e-6, "{t:?}");
    }

    /// Very large loads: the beam hangs along the load from a root bend of length
    /// ~ L / sqrt(alpha). At p = 1 the integrals are elementary (E(p) - E(phi1, p) =
    /// 1 - 1 / sqrt 2), so delta_v / L = 1 - (2 - sqrt 2) / sqrt(alpha) and
    /// x_tip / L = sqrt(2 / alpha), up to terms of order exp(-2 sqrt(alpha)). Before the
    /// closed form, shooting gave a tip rotation of 32.9 rad at alpha = 2e4.
    #[test]
    fn huge_loads_hang_along_the_load() {
        let mut previous = tip(100.0);
        for alpha in [1e3, 2e4, 1e6, 1e10, 1e14] {
            let t = tip(alpha);
            let root = alpha.sqrt();
            assert!(
                (t.deflection - (1.0 - (2.0 - 2f64.sqrt()) / root)).abs() < 1e-12,
                "{t:?}"
            );
            assert!(
                (t.shortening - (1.0 - (2.0 / alpha).sqrt())).abs() < 1e-12,
                "{t:?}"
            );
            assert!((t.rotation - FRAC_PI_2).abs() < 1e-12, "{t:?}");
            assert!(t.deflection > previous.deflection && t.rotation >= previous.rotation);
            previous = t;
        }
    }
}
