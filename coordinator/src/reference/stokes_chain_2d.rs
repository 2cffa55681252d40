//! A 2D reference for the Jeffery period of a rigid chain of touching discs: unbounded Stokes
//! flow, sharp surfaces, solved by a boundary integral method.
//!
//! Jeffery's law needs the aspect ratio of an *equivalent ellipse*; for a chain of discs there
//! is no closed form, and the 3D laws for cylinders (Harris & Pittman, Cox) do not carry over
//! to 2D. So we solve the problem itself. A rigid body in a linear flow `u = G x` (G traceless)
//! turns at a rate linear in G. In 2D, `G = a E1 + b E2 + w W` with the strains
//! `E1 = [[1, 0], [0, -1]]`, `E2 = [[0, 1], [1, 0]]` and the rotation `W = [[0, -1], [1, 0]]`;
//! the body co-rotates with W (rate w), and for a body symmetric about its axes (along x)
//! E1 turns it not at all, E2 at a rate `B` (the 2D Bretherton constant). In simple shear
//! `u = (gamma y, 0)` at orientation theta this gives
//! `omega = -(gamma / 2) (1 - B cos 2 theta)`, Jeffery's form with `B = (e² - 1) / (e² + 1)`, so
//! the full period is `gamma T = 4 pi / sqrt(1 - B²) = 2 pi (e + 1/e)`.
//!
//! B comes from one linear solve. The disturbance is a single-layer potential on the body's
//! closed curves (one per disc), `u(x) = ∫ G(x - y) f(y) ds_y` with the 2D Stokeslet
//! `G = (-ln r I + r r / r²) / (4 pi mu)`, and on the surface `u = U + Omega x r - G x`,
//! with zero net force and torque. Each closed curve leaves the density `f = n` (a uniform
//! pressure inside) without effect; adding `n(x) ∫ n . f ds` over the same curve removes that
//! null space without changing the solution. Nyström discretisation, nodes at equal steps of
//! the curve parameter (offset by half a step, so no node sits on a contact point), the
//! logarithm integrated exactly over each node's own straight element. Checked against
//! Jeffery's exact ellipse (B to 1e-4); for the chains B changes by ~2e-5 from 24 to 96 nodes
//! per disc (the fluid in the cusps at the contact points hardly moves), and
//! the example `stokes_chain_periods` reports the change from half its resolution as the error.
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;

/// Nodes of a set of closed curves: position, unit tangent, outward normal, arc weight, curve.
struct Boundary {
    x: Vec<[f64; 2]>,
    t: Vec<[f64; 2]>,
    n: Vec<[f64; 2]>,
    h: Vec<f64>,
    curve: Vec<usize>,
}

impl Boundary {
    fn new() -> Self {
        Self {
            x: Vec::new(),
            t: Vec::new(),
            n: Vec::new(),
            h: Vec::new(),
            curve: Vec::new(),
        }
    }

    /// An ellipse of semi-axes `a` (along x) and `b` centred at `c`, `m` nodes.
    fn push_ellipse(&mut self, c: [f64; 2], a: f64, b: f64, m: usize) {
        let id = self.curve.last().map_or(0, |k| k + 1);
        let dt = 2.0 * PI / m as f64;
        for k in 0..m {
            let s = (k as f64 + 0.5) * dt;
            let d = [-a * s.sin(), b * s.cos()];
            let len = d[0].hypot(d[1]);
            let t = [d[0] / len, d[1] / len];
            self.x.push([c[0] + a * s.cos(), c[1] + b * s.sin()]);
            self.t.push(t);
            self.n.push([t[1], -t[0]]);
            self.h.push(len * dt);
            self.curve.push(id);
        }
    }
}

/// Angular velocity of the rigid body bounded by `b` in the linear flow `u = g x` (viscosity
/// 1; the body's reference point is the origin).
fn angular_velocity(b: &Boundary, flows: &[[[f64; 2]; 2]]) -> Vec<f64> {
    let rate = 2 * b.x.len() + 2;
    solve(b, flows, false).iter().map(|s| s[rate]).collect()
}

/// The boundary integral solve of the free rigid body bounded by `b` in each flow `u = g x`:
/// per flow, the single-layer density at every node (x and y interleaved, the force per
/// length the body exerts on the fluid), then U and Omega. With `spinning`, each closed
/// curve (a disc) turns freely about its own centre at a rate of its own, free of torque,
/// while the centres move as one rigid body: a chain of rollers, as beads joined only by
/// central and bending forces are (the bead-spring model); the rates follow Omega.
fn solve(b: &Boundary, flows: &[[[f64; 2]; 2]], spinning: bool) -> Vec<DVector<f64>> {
    let n = b.x.len();
    let curves = b.curve.last().map_or(0, |c| c + 1);
    let spins = if spinning { curves } else { 0 };
    let size = 2 * n + 3 + spins;
    // Centre of each curve: the mean of its nodes (exact for a disc's equal-angle nodes).
    let mut centre = vec![[0.0f64; 2]; curves];
    let mut count = vec![0usize; curves];
    for (x, &c) in b.x.iter().zip(&b.curve) {
        centre[c][0] += x[0];
        centre[c][1] += x[1];
        count[c] += 1;
    }
    for (c, k) in centre.iter_mut().zip(&count) {
        c[0] /= *k as f64;
        c[1] /= *k as f64;
    }
    let mut a = DMatrix::<f64>::zeros(size, size);
    let k = 1.0 / (4.0 * PI);
    for i in 0..n {
        for j in 0..n {
            let hj = b.h[j];
            let mut blk = [[0.0; 2]; 2];
            if i == j {
                // ∫ over the straight element of length h: -ln|s| gives -h (ln(h / 2) - 1),
                // r r / r² gives h t t.
                let l = -hj * ((hj / 2.0).ln() - 1.0);
                for p in 0..2 {
                    for q in 0..2 {
                        blk[p][q] = k * (if p == q { l } else { 0.0 } + hj * b.t[j][p] * b.t[j][q]);
                    }
                }
            } else {
                let r = [b.x[i][0] - b.x[j][0], b.x[i][1] - b.x[j][1]];
                let r2 = r[0] * r[0] + r[1] * r[1];
                let l = -0.5 * r2.ln();
                for p in 0..2 {
                    for q in 0..2 {
                        blk[p][q] = k * hj * (if p == q { l } else { 0.0 } + r[p] * r[q] / r2);
                    }
                }
            }
            if b.curve[i] == b.curve[j] {
                for p in 0..2 {
                    for q in 0..2 {
                        blk[p][q] += b.n[i][p] * b.n[j][q] * hj;
                    }
                }
            }
            for p in 0..2 {
                for q in 0..2 {
                    a[(2 * i + p, 2 * j + q)] = blk[p][q];
                }
            }
        }
        // - U - Omega e_z x r (rollers: - Omega e_z x X_c - omega_c e_z x (r - X_c))
        a[(2 * i, 2 * n)] = -1.0;
        a[(2 * i + 1, 2 * n + 1)] = -1.0;
        let c = b.curve[i];
        let arm = if spinning { centre[c] } else { b.x[i] };
        a[(2 * i, 2 * n + 2)] = arm[1];
        a[(2 * i + 1, 2 * n + 2)] = -arm[0];
        if spinning {
            let r = [b.x[i][0] - centre[c][0], b.x[i][1] - centre[c][1]];
            a[(2 * i, 2 * n + 3 + c)] = r[1];
            a[(2 * i + 1, 2 * n + 3 + c)] = -r[0];
        }
    }
    for j in 0..n {
        let hj = b.h[j];
        a[(2 * n, 2 * j)] = hj;
        a[(2 * n + 1, 2 * j + 1)] = hj;
        a[(2 * n + 2, 2 * j)] = -b.x[j][1] * hj;
        a[(2 * n + 2, 2 * j + 1)] = b.x[j][0] * hj;
        if spinning {
            // No torque on each roller about its own centre.
            let c = b.curve[j];
            let r = [b.x[j][0] - centre[c][0], b.x[j][1] - centre[c][1]];
            a[(2 * n + 3 + c, 2 * j)] = -r[1] * hj;
            a[(2 * n + 3 + c, 2 * j + 1)] = r[0] * hj;
        }
    }
    let lu = a.lu();
    flows
        .iter()
        .map(|g| {
            let mut rhs = DVector::<f64>::zeros(size);
            for i in 0..n {
                let x = b.x[i];
                rhs[2 * i] = -(g[0][0] * x[0] + g[0][1] * x[1]);
                rhs[2 * i + 1] = -(g[1][0] * x[0] + g[1][1] * x[1]);
            }
            lu.solve(&rhs)
                .expect("the boundary integral system is regular")
        })
        .collect()
}

const E1: [[f64; 2]; 2] = [[1.0, 0.0], [0.0, -1.0]];
const E2: [[f64; 2]; 2] = [[0.0, 1.0], [1.0, 0.0]];

/// `(B, omega(E1))` of a body: its Bretherton constant and the turning rate in the strain
/// E1, which vanishes for a body symmetric about its axes (a check of the solve).
fn bretherton(b: &Boundary) -> (f64, f64) {
    let w = angular_velocity(b, &[E2, E1]);
    (w[0], w[1])
}

/// Bretherton constant of a straight chain of `beads` touching discs of unit radius, with
/// `m` nodes per disc, and the turning rate in E1 (zero by symmetry).
pub fn chain_bretherton_at(beads: usize, m: usize) -> (f64, f64) {
    bretherton(&chain(beads, 1.0, m))
}

/// x of disc `k`'s centre in a chain of `beads` discs with centres 2 apart, centred on 0.
fn chain_centre(beads: usize, k: usize) -> f64 {
    2.0 * k as f64 - (beads as f64 - 1.0)
}

/// A straight chain of `beads` discs of `radius` along x, centres 2 apart, `m` nodes each.
fn chain(beads: usize, radius: f64, m: usize) -> Boundary {
    let mut b = Boundary::new();
    for k in 0..beads {
        b.push_ellipse([chain_centre(beads, k), 0.0], radius, radius, m);
    }
    b
}

/// The bending moment a free, straight, rigid chain of `beads` discs of `radius` (centres 2
/// apart, so `radius` < 1 leaves gaps) carries at each of its `beads - 1` joints (the
/// midpoints between neighbouring centres) in the strain `E2` (`u = (y, x)`, viscosity 1),
/// turning at its own rate `B`: the moment about the joint of the fluid's forces on the discs
/// before it, `M_k = sum_{j <= k} ∫ (x - x_k) x (-f) ds`. Returns `(B, M)`. The chain is
/// torque-free as a whole, but the load is spread unevenly along it, so its joints carry an
/// S-shaped moment (odd about the centre), which a flexible chain answers by bending into an
/// S. Used to ask how that moment grows with the chain's thickness at a fixed length.
///
/// With `spinning` the discs turn freely about their centres (a chain of rollers, see
/// `solve`), so no disc carries a torque and the joints carry only the moments of the
/// discs' forces.
pub fn chain_bending_moments(
    beads: usize,
    radius: f64,
    m: usize,
    spinning: bool,
) -> (f64, Vec<f64>) {
    let b = chain(beads, radius, m);
    let s = &solve(&b, &[E2], spinning)[0];
    let moments = (0..beads.saturating_sub(1))
        .map(|k| {
            let xc = chain_centre(beads, k) + 1.0;
            (0..b.x.len())
                .filter(|&j| b.curve[j] <= k)
                .map(|j| {
                    let (rx, ry) = (b.x[j][0] - xc, b.x[j][1]);
                    let (fx, fy) = (-s[2 * j], -s[2 * j + 1]);
                    b.h[j] * (rx * fy - ry * fx)
                })
                .sum()
        })
        .collect();
    (s[2 * b.x.len() + 2], moments)
}

/// The quasi-static S of a flexible chain under the joint moments `m` of
/// [`chain_bending_moments`] (discs of radius 1, centres 2 apart, viscosity and strain rate
/// 1): the largest distance of the beam from the chord through the end discs' centres, over
/// the length L = 2 N, for a bending rigidity EI = L^3. The curvature M / EI is taken linear
/// between the joints and zero at the end centres. For a fibre of length L, bending rigidity
/// EI (per unit depth), in a strain rate E of viscosity mu, the deflection is then this
/// number times L (mu E L^3 / EI).
pub fn s_deflection_per_load(m: &[f64]) -> f64 {
    let beads = m.len() + 1;
    let length = 2.0 * beads as f64;
    let ei = length.powi(3);
    let end = 2.0 * (beads as f64 - 1.0);
    // Knots of the curvature: the end centres and the joints between them.
    let mut knots = vec![(0.0, 0.0)];
    knots.extend(
        m.iter()
            .enumerate()
            .map(|(k, &v)| (2.0 * k as f64 + 1.0, v / ei)),
    );
    knots.push((end, 0.0));
    // w'' = kappa, integrated exactly over each linear piece from w(0) = w'(0) = 0.
    let (mut w, mut slope) = (0.0, 0.0);
    let mut samples = vec![(0.0, 0.0)];
    for pair in knots.windows(2) {
        let ((s0, k0), (s1, k1)) = (pair[0], pair[1]);
        let steps = 64;
        let h = (s1 - s0) / steps as f64;
        let dk = (k1 - k0) / (s1 - s0);
        for i in 0..steps {
            let k = k0 + dk * h * i as f64;
            w += slope * h + k * h * h / 2.0 + dk * h * h * h / 6.0;
            slope += k * h + dk * h * h / 2.0;
            samples.push((s0 + h * (i + 1) as f64, w));
        }
    }
    let w_end = w;
    samples
        .iter()
        .map(|&(s, w)| (w - w_end * s / end).abs())
        .fold(0.0, f64::max)
        / length
}

/// Nodes per disc of [`chain_bretherton`].
pub const CHAIN_NODES: usize = 64;

/// Bretherton constant of a chain of `beads` touching discs with [`CHAIN_NODES`] nodes per
/// disc (within ~2e-5 of 24 and 96 nodes; test `chain_solve_is_symmetric_and_converges`).
/// Solved once per process and chain length: the dense solve takes about a second at ten
/// beads, and several metrics of one run ask for it.
pub fn chain_bretherton(beads: usize) -> f64 {
    static SOLVED: std::sync::Mutex<Vec<(usize, f64)>> = std::sync::Mutex::new(Vec::new());
    let mut solved = SOLVED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(&(_, b)) = solved.iter().find(|(n, _)| *n == beads) {
        return b;
    }
    let b = chain_bretherton_at(beads, CHAIN_NODES).0;
    solved.push((beads, b));
    b
}

/// gamma T of a full turn (2 pi) for a body of Bretherton constant `b`.
pub fn period_gamma(b: f64) -> f64 {
    4.0 * PI / (1.0 - b * b).sqrt()
}

/// Aspect ratio of the ellipse with Bretherton constant `b`.
pub fn equivalent_aspect_ratio(b: f64) -> f64 {
    ((1.0 + b) / (1.0 - b)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bretherton constant of an ellipse of aspect ratio `e` with `m` nodes (Jeffery:
    /// `(e² - 1) / (e² + 1)`).
    fn ellipse_bretherton(e: f64, m: usize) -> f64 {
        let mut b = Boundary::new();
        b.push_ellipse([0.0, 0.0], e, 1.0, m);
        bretherton(&b).0
    }

    /// Jeffery's ellipse: B = (e² - 1) / (e² + 1) to 1e-4 with 256 nodes, and the period
    /// 2 pi (e + 1/e) from it.
    #[test]
    fn ellipse_turns_as_jeffery_says() {
        for e in [1.0, 2.0, 4.0] {
            let b = ellipse_bretherton(e, 256);
            let exact = (e * e - 1.0) / (e * e + 1.0);
            assert!((b - exact).abs() < 1e-4, "e {e}: B {b} vs {exact}");
            let t = period_gamma(exact);
            assert!((t - 2.0 * PI * (e + 1.0 / e)).abs() < 1e-12);
            assert!((equivalent_aspect_ratio(exact) - e).abs() < 1e-12);
        }
    }

    /// A disc does not feel strain; a chain of discs turns only through E2 (symmetry), and
    /// its Bretherton constant is converged to 1e-4 at 24 nodes per disc.
    #[test]
    fn chain_solve_is_symmetric_and_converges() {
        let (b1, _) = chain_bretherton_at(1, 64);
        assert!(b1.abs() < 1e-10, "single disc: B = {b1}");
        let mut last = Vec::new();
        for m in [24, 48, 96] {
            let (b, e1) = chain_bretherton_at(3, m);
            assert!(e1.abs() < 1e-10, "E1 turns the chain: {e1}");
            last.push(b);
        }
        eprintln!("N_b = 3: B = {last:?} at 24, 48, 96 nodes per disc");
        assert!((last[2] - last[0]).abs() < 1e-4, "{last:?}");
        assert!((last[2] - last[1]).abs() < 1e-4, "{last:?}");
    }

    /// The joints' moments: odd about the centre (the chain is point-symmetric and free of
    /// net torque, so the moment before a joint is minus the one after its mirror), the same
    /// B as the plain solve for touching discs, and converged in the nodes per disc.
    #[test]
    fn chain_moments_are_odd_and_converge() {
        let (b, m) = chain_bending_moments(6, 1.0, 48, false);
        assert!((b - chain_bretherton_at(6, 48).0).abs() < 1e-12);
        assert_eq!(m.len(), 5);
        let scale = m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(scale > 0.0);
        for k in 0..5 {
            assert!((m[k] + m[4 - k]).abs() < 1e-9 * scale, "{m:?}");
        }
        // Touching discs converge slowly (the cusps at the contacts): the change halves or
        // better with each doubling of the nodes, and is under 0.5 % at 48 -> 96.
        let (_, coarse) = chain_bending_moments(6, 1.0, 24, false);
        let (_, fine) = chain_bending_moments(6, 1.0, 96, false);
        let (d1, d2) = ((m[0] - coarse[0]).abs(), (fine[0] - m[0]).abs());
        eprintln!(
            "M_0 at 24 / 48 / 96 nodes: {} / {} / {}",
            coarse[0], m[0], fine[0]
        );
        assert!(d2 < 0.5 * d1, "{d1} then {d2}");
        assert!(d2 < 5e-3 * scale, "{d2} against {scale}");
    }

    /// Rollers: each disc free of torque about its own centre (to round-off, against the
    /// torques the locked discs carry), the joints' moments odd about the centre and smaller
    /// than the locked chain's, and converged in the nodes per disc for discs apart.
    #[test]
    fn rollers_carry_no_disc_torque() {
        let torques = |spinning: bool| {
            let b = chain(5, 0.75, 48);
            let s = &solve(&b, &[E2], spinning)[0];
            (0..5)
                .map(|c| {
                    let xc = chain_centre(5, c);
                    (0..b.x.len())
                        .filter(|&j| b.curve[j] == c)
                        .map(|j| b.h[j] * ((b.x[j][0] - xc) * s[2 * j + 1] - b.x[j][1] * s[2 * j]))
                        .sum::<f64>()
                })
                .collect::<Vec<f64>>()
        };
        let locked = torques(false);
        let scale = locked.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(scale > 1e-3, "{locked:?}");
        for t in torques(true) {
            assert!(
                t.abs() < 1e-9 * scale,
                "a roller carries torque {t} (locked: {scale})"
            );
        }
        let max = |m: &[f64]| m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let (_, free) = chain_bending_moments(6, 0.75, 48, true);
        let (_, held) = chain_bending_moments(6, 0.75, 48, false);
        for k in 0..5 {
            assert!(
                (free[k] + free[4 - k]).abs() < 1e-9 * max(&free),
                "{free:?}"
            );
        }
        assert!(max(&free) < max(&held), "{free:?} against {held:?}");
        let (_, fine) = chain_bending_moments(6, 0.75, 96, true);
        assert!(
            (max(&fine) - max(&free)).abs() < 1e-2 * max(&free),
            "{free:?} {fine:?}"
        );
    }

    /// The S of a beam under a moment odd about its centre: the piecewise exact
    /// integration against a fine midpoint quadrature of the same curvature (to 1e-6), and
    /// linear in the moment.
    #[test]
    fn s_deflection_matches_a_fine_quadrature() {
        // Joints of 10 discs at s = 1, 3, ..., 17; the end centres at 0 and 18 (c = 9).
        let c = 9.0;
        let m_odd: Vec<f64> = (0..9)
            .map(|k| {
                let s = 2.0 * k as f64 + 1.0;
                (s - c) * s * (2.0 * c - s) / (c * c)
            })
            .collect();
        let got = s_deflection_per_load(&m_odd);
        // Fine quadrature of the same piecewise-linear curvature.
        let ei = 20f64.powi(3);
        let knots: Vec<(f64, f64)> = std::iter::once((0.0, 0.0))
            .chain(
                m_odd
                    .iter()
                    .enumerate()
                    .map(|(k, &v)| (2.0 * k as f64 + 1.0, v / ei)),
            )
            .chain(std::iter::once((2.0 * c, 0.0)))
            .collect();
        let kappa = |s: f64| {
            let i = knots
                .iter()
                .rposition(|&(x, _)| x <= s)
                .unwrap()
                .min(knots.len() - 2);
            let ((x0, k0), (x1, k1)) = (knots[i], knots[i + 1]);
            k0 + (k1 - k0) * (s - x0) / (x1 - x0)
        };
        let n = 200_000;
        let h = 2.0 * c / n as f64;
        let (mut w, mut slope, mut ws) = (0.0, 0.0, vec![0.0]);
        for i in 0..n {
            let k = kappa((i as f64 + 0.5) * h);
            w += slope * h + k * h * h / 2.0;
            slope += k * h;
            ws.push(w);
        }
        let want = ws
            .iter()
            .enumerate()
            .map(|(i, &v)| (v - w * i as f64 / n as f64).abs())
            .fold(0.0, f64::max)
            / 20.0;
        assert!((got - want).abs() < 1e-6 * want, "{got} against {want}");
        let doubled: Vec<f64> = m_odd.iter().map(|v| 2.0 * v).collect();
        assert!((s_deflection_per_load(&doubled) - 2.0 * got).abs() < 1e-12 * got);
    }
}
