//! Large deflection of a cantilever under a fixed-direction tip load (the elastica;
//! Bisshopp & Drucker 1945, Fertis 1993), solved by shooting.
//!
//! With s in [0, 1] the arc length over L, theta the slope, and alpha = P L^2 / (E I):
//! theta'' = -alpha cos(theta), theta(0) = 0 (clamped), theta'(1) = 0 (no moment at the tip).
//! The unknown curvature at the root, theta'(0), is found by bisection on theta'(1) and the
//! shape integrated with classical RK4.
//!
//! Which root: the first integral (theta')^2 / 2 + alpha sin(theta) = const with theta'(1) = 0
//! gives theta'(0) = sqrt(2 alpha sin theta(1)) = sqrt(2 alpha (1 - g)), g = 1 - sin theta(1)
//! in (0, 1]. The equation is a pendulum, and from alpha = (3 pi / 2)^2 = 22.2 on it has
//! more roots below sqrt(2 alpha): beams that swing back and forth along their length
//! (three, five, ... quarter swings), whose ends curl round. The cantilever is the first
//! swing, the root nearest sqrt(2 alpha) (the separatrix, where theta'(1) > 0), so the
//! search scans g upwards from 1e-16 in tenths of a decade (the next root's g is about the
//! cube root of the first's, half a decade or more away) and bisects the first sign change.

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

const STEPS: usize = 4000;

/// Integrate from the root with curvature `k0`; returns (theta(1), theta'(1), x(1), y(1)).
fn shoot(alpha: f64, k0: f64) -> [f64; 4] {
    // State: theta, theta', x, y.
    let f = |s: [f64; 4]| [s[1], -alpha * s[0].cos(), s[0].cos(), s[0].sin()];
    let h = 1.0 / STEPS as f64;
    let mut y = [0.0, k0, 0.0, 0.0];
    for _ in 0..STEPS {
        let a = f(y);
        let b = f(std::array::from_fn(|i| y[i] + 0.5 * h * a[i]));
        let c = f(std::array::from_fn(|i| y[i] + 0.5 * h * b[i]));
        let d = f(std::array::from_fn(|i| y[i] + h * c[i]));
        y = std::array::from_fn(|i| y[i] + h / 6.0 * (a[i] + 2.0 * b[i] + 2.0 * c[i] + d[i]));
    }
    y
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
    let curvature = |g: f64| (2.0 * alpha * (1.0 - g)).sqrt();
    let mut hi = curvature(0.0);
    let mut lo = 0.0;
    for j in 0..=160 {
        let k = curvature(10f64.powf(-16.0 + 0.1 * j as f64).min(1.0));
        if shoot(alpha, k)[1] < 0.0 {
            lo = k;
            break;
        }
        hi = k;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if shoot(alpha, mid)[1] < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let s = shoot(alpha, 0.5 * (lo + hi));
    ElasticaTip {
        deflection: s[3],
        shortening: 1.0 - s[2],
        rotation: s[0],
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

    /// Bisshopp & Drucker's closed form in elliptic integrals of modulus
    /// p = sqrt((1 + sin theta_L) / 2), with sin phi1 = 1 / (p sqrt 2):
    /// sqrt(alpha) = K(p) - F(phi1, p), delta_v / L = 1 - 2 (E(p) - E(phi1, p)) / sqrt(alpha),
    /// x_tip / L = sqrt(2 sin theta_L / alpha). Solved here for theta_L by bisection, the
    /// integrals by composite Simpson on [phi1, pi/2] (smooth there since p < 1).
    fn closed_form(alpha: f64) -> (f64, f64, f64) {
        let simpson = |f: &dyn Fn(f64) -> f64, a: f64, b: f64| {
            let n = 20_000;
            let h = (b - a) / n as f64;
            let mut sum = f(a) + f(b);
            for i in 1..n {
                sum += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
            }
            sum * h / 3.0
        };
        let integrals = |theta: f64| {
            let p = ((1.0 + theta.sin()) / 2.0).sqrt();
            let phi1 = (1.0 / (p * 2f64.sqrt())).asin();
            let w = |phi: f64| (1.0 - p * p * phi.sin().powi(2)).sqrt();
            let first = simpson(&|phi| 1.0 / w(phi), phi1, std::f64::consts::FRAC_PI_2);
            let second = simpson(&w, phi1, std::f64::consts::FRAC_PI_2);
            (first, second)
        };
        // sqrt(alpha) grows with the tip angle on (0, pi/2).
        let (mut lo, mut hi) = (1e-12, std::f64::consts::FRAC_PI_2 - 1e-12);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if integrals(mid).0 < alpha.sqrt() {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let theta = 0.5 * (lo + hi);
        let (_, e) = integrals(theta);
        (
            1.0 - 2.0 * e / alpha.sqrt(),
            1.0 - (2.0 * theta.sin() / alpha).sqrt(),
            theta,
        )
    }

    /// Large loads, where the shooting equation has several roots (from alpha = 22.2): the
    /// cantilever's is taken, as the closed form (above) says, to 1e-6. (Beyond alpha ~ 100
    /// the tip angle is within 1e-5 of pi / 2, where the closed form's first integrand
    /// peaks too sharply for its Simpson rule.)
    #[test]
    fn large_loads_match_the_closed_form() {
        for alpha in [1.0, 10.0, 22.0, 30.0, 35.0, 50.0, 100.0] {
            let t = tip(alpha);
            let (dv, sh, rot) = closed_form(alpha);
            assert!(
                (t.deflection - dv).abs() < 1e-6
                    && (t.shortening - sh).abs() < 1e-6
                    && (t.rotation - rot).abs() < 1e-6,
                "alpha {alpha}: {t:?}, closed form deflection {dv}, shortening {sh}, rotation {rot}"
            );
        }
    }

    /// Small loads: delta / L -> alpha / 3, rotation -> alpha / 2 (Euler-Bernoulli).
    #[test]
    fn small_load_limit() {
        let a = 1e-4;
        let t = tip(a);
        assert!((t.deflection / (a / 3.0) - 1.0).abs() < 1e-6);
        assert!((t.rotation / (a / 2.0) - 1.0).abs() < 1e-6);
    }
}
