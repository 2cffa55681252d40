//! Large deflection of a cantilever under a fixed-direction tip load (the elastica;
//! Bisshopp & Drucker 1945, Fertis 1993), solved by shooting.
//!
//! With s in [0, 1] the arc length over L, theta the slope, and alpha = P L^2 / (E I):
//! theta'' = -alpha cos(theta), theta(0) = 0 (clamped), theta'(1) = 0 (no moment at the tip).
//! The unknown curvature at the root, theta'(0) = alpha x_tip / L, lies in [0, alpha]; it is
//! found by bisection on theta'(1) and the shape integrated with classical RK4.

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
    let (mut lo, mut hi) = (0.0, alpha);
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

    /// Small loads: delta / L -> alpha / 3, rotation -> alpha / 2 (Euler-Bernoulli).
    #[test]
    fn small_load_limit() {
        let a = 1e-4;
        let t = tip(a);
        assert!((t.deflection / (a / 3.0) - 1.0).abs() < 1e-6);
        assert!((t.rotation / (a / 2.0) - 1.0).abs() < 1e-6);
    }
}
