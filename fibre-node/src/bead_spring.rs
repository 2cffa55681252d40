//! The bead-spring model of S2023 section II.B (eqs. 9-12), in 2D or 3D.
//!
//! # Energy
//! `U = Σ_{segments} k_s / (2 l0²) (R − l0)²  +  k_b Σ_{joints} (1 − t_{i+1} · t_i)`
//!
//! with `R` the segment length and `t` the unit tangent of a segment. S2023 eq. 9 prints the
//! bending term as `−k_b Σ (t_{i+1}·t_i)²`, but its forces, eqs. 12a-e, are the gradient of the
//! *linear* form `−k_b Σ t_{i+1}·t_i` (REFERENCE.md §1). We implement the linear form, shifted
//! by the constant `k_b (N − 2)` so that a straight fibre has zero energy (the forces are
//! unchanged). Its exact gradient, in vector form valid in 2D and 3D: for a joint between
//! segments a (bead a → a+1) and b (bead a+1 → a+2), with `c = t_a · t_b`,
//! `g_a = (I − t_a t_a) t_b / R_a`, `g_b = (I − t_b t_b) t_a / R_b`:
//! `F_a += −k_b g_a`, `F_{a+1} += k_b (g_a − g_b)`, `F_{a+2} += k_b g_b`,
//! which summed over joints is eqs. 12a-e. The stretching force is eqs. 11a-b.
//!
//! # Mapping to Euler–Bernoulli (used when the scene gives only `youngs_modulus`)
//! For small joint angles β, `1 − cos β ≈ β²/2`, so the bending energy is `(k_b / 2) Σ β²`;
//! a discrete elastica with curvature `β / l0` over a length `l0` stores `(E I / (2 l0)) β²`.
//! Hence `k_b = E I / l0` with `I = π r⁴ / 4`. The spring `k_s / l0²` is the axial stiffness
//! `E A / l0` of a segment, `A = π r²`, so `k_s = E A l0`. The scene may override either
//! (`fibre.N.bending_stiffness`, `fibre.N.stretch_stiffness`), as S2023 sets `K` and `K_s`
//! directly.
use crate::energies::Energies;
use crate::quaternion::Vec3;

/// Constants of one bead-spring chain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeadSpring {
    /// Equilibrium spring length `l0` (S2023: `d = 2a`).
    pub rest_length: f64,
    /// Spring constant `k_s` (energy units; the spring stiffness is `k_s / l0²`).
    pub k_s: f64,
    /// Bending constant `k_b` (energy units).
    pub k_b: f64,
}

impl BeadSpring {
    /// Constants from an Euler–Bernoulli rod of radius `r` and Young's modulus `e`.
    pub fn from_modulus(e: f64, r: f64, l0: f64) -> Self {
        let area = std::f64::consts::PI * r * r;
        let i = std::f64::consts::PI * r.powi(4) / 4.0;
        Self {
            rest_length: l0,
            k_s: e * area * l0,
            k_b: e * i / l0,
        }
    }

    /// Bending rigidity `E I = k_b l0` this chain represents.
    pub fn bending_rigidity(&self) -> f64 {
        self.k_b * self.rest_length
    }

    /// Spring stiffness `k_s / l0²` (force per length).
    pub fn spring_stiffness(&self) -> f64 {
        self.k_s / (self.rest_length * self.rest_length)
    }

    /// Add the forces of the chain to `force`; return its energy. Allocation-free.
    pub fn add_chain_forces(&self, pos: &[Vec3], force: &mut [Vec3]) -> Energies {
        let n = pos.len();
        let ks = self.spring_stiffness();
        let mut e = Energies::default();
        if n < 2 {
            return e;
        }
        // Previous segment's tangent and length.
        let mut t_prev = Vec3::zeros();
        let mut r_prev = 0.0;
        for a in 0..n - 1 {
            let d = pos[a + 1] - pos[a];
            let r = d.norm();
            let t = if r > 0.0 { d / r } else { Vec3::zeros() };
            // eq. 11: stretching.
            let s = r - self.rest_length;
            let f = (ks * s) * t;
            force[a] += f;
            force[a + 1] -= f;
            e.stretch += 0.5 * ks * s * s;
            // eq. 12: the joint at bead a between segment a-1 and segment a.
            if a > 0 && r > 0.0 && r_prev > 0.0 {
                let c = t_prev.dot(&t);
                let g_a = (t - c * t_prev) / r_prev;
                let g_b = (t_prev - c * t) / r;
                force[a - 1] -= self.k_b * g_a;
                force[a] += self.k_b * (g_a - g_b);
                force[a + 1] += self.k_b * g_b;
                // 1 − c = ½ |t_a − t_b|², without cancellation.
                e.bend += 0.5 * self.k_b * (t - t_prev).norm_squared();
            }
            t_prev = t;
            r_prev = r;
        }
        e
    }

    /// Energy of the chain.
    pub fn chain_energy(&self, pos: &[Vec3]) -> Energies {
        let ks = self.spring_stiffness();
        let mut e = Energies::default();
        for a in 0..pos.len().saturating_sub(1) {
            let d = pos[a + 1] - pos[a];
            let s = d.norm() - self.rest_length;
            e.stretch += 0.5 * ks * s * s;
            if a + 2 < pos.len() {
                let d2 = pos[a + 2] - pos[a + 1];
                e.bend += 0.5 * self.k_b * (d.normalize() - d2.normalize()).norm_squared();
            }
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(n: usize, dim3: bool) -> Vec<Vec3> {
        // A deformed chain: random-ish but deterministic bends and stretches.
        let mut x = Vec::with_capacity(n);
        let mut p = Vec3::new(0.3, -0.1, 0.2);
        let mut dir = Vec3::new(1.0, 0.2, if dim3 { -0.1 } else { 0.0 }).normalize();
        for i in 0..n {
            x.push(p);
            let k = i as f64;
            let turn = Vec3::new(
                if dim3 { 0.3 * (1.7 * k).sin() } else { 0.0 },
                if dim3 {
                    0.25 * (0.9 * k + 1.0).cos()
                } else {
                    0.0
                },
                0.35 * (1.3 * k + 0.5).sin(),
            );
            dir = nalgebra::Rotation3::from_scaled_axis(turn) * dir;
            p += dir * (2.0 * (1.0 + 0.05 * (2.1 * k).cos()));
        }
        x
    }

    fn check_gradient(model: &BeadSpring, x: &[Vec3]) -> f64 {
        let n = x.len();
        let mut f = vec![Vec3::zeros(); n];
        let e = model.add_chain_forces(x, &mut f);
        let e2 = model.chain_energy(x);
        assert!((e.total() - e2.total()).abs() <= 1e-12 * e2.total().abs().max(1.0));
        let h = 1e-6;
        let mut worst: f64 = 0.0;
        let scale = f.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for i in 0..n {
            for k in 0..3 {
                let mut xp = x.to_vec();
                xp[i][k] += h;
                let mut xm = x.to_vec();
                xm[i][k] -= h;
                let fd = -(model.chain_energy(&xp).total() - model.chain_energy(&xm).total())
                    / (2.0 * h);
                worst = worst.max((fd - f[i][k]).abs() / scale);
            }
        }
        worst
    }

    #[test]
    fn forces_are_the_exact_gradient_in_3d_and_2d() {
        let model = BeadSpring {
            rest_length: 2.0,
            k_s: 3.0,
            k_b: 1.7,
        };
        for dim3 in [true, false] {
            for n in [2, 3, 4, 5, 12] {
                let x = chain(n, dim3);
                let err = check_gradient(&model, &x);
                assert!(err < 1e-6, "n {n} 3d {dim3}: {err}");
            }
        }
    }

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn forces_match_s2023_eq12_written_out() {
        // Interior bead and the four edge cases of eqs. 12a-e.
        let model = BeadSpring {
            rest_length: 2.0,
            k_s: 0.0,
            k_b: 1.3,
        };
        let x = chain(7, true);
        let n = x.len();
        let mut f = vec![Vec3::zeros(); n];
        model.add_chain_forces(&x, &mut f);
        let t: Vec<Vec3> = (0..n - 1).map(|i| (x[i + 1] - x[i]).normalize()).collect();
        let r: Vec<f64> = (0..n - 1).map(|i| (x[i + 1] - x[i]).norm()).collect();
        // (a · (I - t t)) / R
        let p = |a: Vec3, s: usize| (a - t[s] * t[s].dot(&a)) / r[s];
        let kb = model.k_b;
        // 0-based: S2023 bead i is index i-1, tangent t_i is t[i-1].
        let f1 = -kb * p(t[1], 0);
        let f2 = kb * (p(t[1], 0) - p(t[2] + t[0], 1));
        let fi = |i: usize| kb * (p(t[i] + t[i - 2], i - 1) - p(t[i + 1] + t[i - 1], i));
        let fn1 = kb * (p(t[n - 2] + t[n - 4], n - 3) - p(t[n - 3], n - 2));
        let fnn = kb * p(t[n - 3], n - 2);
        let tol = 1e-12;
        assert!((f[0] - f1).norm() < tol);
        assert!((f[1] - f2).norm() < tol);
        for i in 2..n - 2 {
            assert!((f[i] - fi(i)).norm() < tol, "bead {i}");
        }
        assert!((f[n - 2] - fn1).norm() < tol);
        assert!((f[n - 1] - fnn).norm() < tol);
    }

    /// S2023's K -> 0, a freely jointed chain: bent at every joint with its bonds at rest, it
    /// stores nothing and feels no force with k_b = 0, and is pulled straight with k_b > 0.
    #[test]
    fn a_freely_jointed_chain_keeps_its_bends() {
        let l0 = 2.0;
        let x: Vec<Vec3> = (0..6)
            .scan(Vec3::zeros(), |p, i| {
                let here = *p;
                let a: f64 = if i % 2 == 0 { 0.6 } else { -0.4 };
                *p += Vec3::new(a.cos(), a.sin(), 0.0) * l0;
                Some(here)
            })
            .collect();
        for (kb, bent) in [(0.0, false), (0.5, true)] {
            let model = BeadSpring {
                rest_length: l0,
                k_s: 3.0,
                k_b: kb,
            };
            let mut f = vec![Vec3::zeros(); x.len()];
            let e = model.add_chain_forces(&x, &mut f);
            let largest = f.iter().map(|v| v.norm()).fold(0.0, f64::max);
            assert_eq!(largest > 1e-3, bent, "k_b {kb}: largest force {largest}");
            assert_eq!(e.total() > 1e-3, bent, "k_b {kb}: energy {}", e.total());
            if !bent {
                assert!(largest < 1e-12 && e.total().abs() < 1e-12);
            }
        }
    }

    #[test]
    fn modulus_mapping() {
        let m = BeadSpring::from_modulus(2.0, 0.5, 1.0);
        let i = std::f64::consts::PI * 0.5f64.powi(4) / 4.0;
        assert!((m.bending_rigidity() - 2.0 * i).abs() < 1e-15);
        let a = std::f64::consts::PI * 0.25;
        assert!((m.spring_stiffness() - 2.0 * a / 1.0).abs() < 1e-15);
    }
}
