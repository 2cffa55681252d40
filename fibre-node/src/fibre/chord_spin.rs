//! `fibre.N.bead_spin = "chord"`: the beads of a bead-spring chain turned with their bonds
//! instead of spinning freely (docs/validation/fpd.md, "Beads turned with their chords").
//! Each bead's angular velocity is the mean rate at which its bonds turn, and the angular
//! impulse a bead takes (the fluid's share, its load torques) is passed to its bonds as
//! couples, so the chain takes it into its orbital motion. Called from the kicks of
//! [`Fibre`]'s integrator (parent module).
//!
//! In 3D a bond can carry only the part of an angular impulse perpendicular to itself, and a
//! chain without torsion has nothing to hold a bead's spin about its own axis. So each bead
//! keeps a free spin about its tangent `t` (along `X_{i+1} - X_{i-1}`, its one bond at an
//! end): its angular velocity is the chord rate less its part along `t`, plus that spin.
//! Of an angular impulse `L`, the part across the tangent goes to the bonds and the rest to
//! the spin, so that nothing is lost (`split`). In 2D `L` is normal to the plane, the
//! spin about the tangent stays zero and all of `L` goes to the bonds.
use super::{Fibre, HydroKick};
use crate::quaternion::Vec3;

/// The chain's direction at bead `i`: along `X_{i+1} - X_{i-1}`, or its one bond at an end.
pub(super) fn tangent(pos: &[Vec3], i: usize) -> Vec3 {
    let n = pos.len();
    (pos[(i + 1).min(n - 1)] - pos[i.saturating_sub(1)]).normalize()
}

/// How the bonds of bead `i` carry its angular impulse `l`. With `t` its tangent and
/// `p = l - (l . t) t` the part across it, bond `k` (`d_k` from bead i to its neighbour,
/// weight `w` = 1/2 for an interior bead, 1 at an end) carries `A_k = w p + a_k t`, with
/// `a_k` such that `A_k . d_k = 0` (a bond passes only what is perpendicular to it); the
/// remainder `l . t - sum a_k` is the spin about `t`. So `sum A_k + (remainder) t = l`
/// exactly, and in 2D (`l` normal to the plane) every `a_k` and the remainder are zero.
/// Calls `bond(j, A_k)` for each neighbour `j`; returns the remainder.
fn split(pos: &[Vec3], i: usize, l: Vec3, mut bond: impl FnMut(usize, Vec3)) -> f64 {
    let n = pos.len();
    let t = tangent(pos, i);
    let along = l.dot(&t);
    let across = l - along * t;
    let bonds = [(i > 0).then(|| i - 1), (i + 1 < n).then_some(i + 1)];
    let w = if bonds.iter().all(Option::is_some) {
        0.5
    } else {
        1.0
    };
    let mut rest = along;
    for j in bonds.into_iter().flatten() {
        let d = pos[j] - pos[i];
        // The chain folds back on itself only where t . d = 0, which touching beads
        // cannot reach.
        let a = -(w * across).dot(&d) / t.dot(&d);
        bond(j, w * across + a * t);
        rest -= a;
    }
    rest
}

/// The linear impulses that pass the angular impulse `l(i)` of each bead of a chain at `pos`
/// to its bonds, into `couple`, and the part left to each bead's spin about its tangent,
/// into `axial` (see [`split`]): bond (i, j), `d = X_j - X_i`, carrying `A` (perpendicular
/// to d) does so as `P = A x d / |d|^2` on bead j and `-P` on bead i, whose moment `d x P`
/// is `A`.
fn couples_into(pos: &[Vec3], couple: &mut [Vec3], axial: &mut [f64], l: impl Fn(usize) -> Vec3) {
    for c in couple.iter_mut() {
        *c = Vec3::zeros();
    }
    for i in 0..pos.len() {
        axial[i] = split(pos, i, l(i), |j, a| {
            let d = pos[j] - pos[i];
            let p = a.cross(&d) / d.norm_squared();
            couple[j] += p;
            couple[i] -= p;
        });
    }
}

impl Fibre {
    /// `bead_spin = "chord"` with the implicit exchange. The fluid's drag on a bead's spin,
    /// `b (Omega_phi - Omega_i)` with `b = share I_phi` and `Omega_phi` the spin of the fluid
    /// in its profile (`chord_spin`), is taken at the new chord rates, as the translational
    /// drag is at the new velocities, and passed to the bonds as couples (as in
    /// [`Fibre::pass_torques_to_neighbours`], with the load torques). The rates depend on the
    /// new velocities, which the couples change through the same drag, so the two are solved
    /// together: `V = V_b + P(L(V)) / (M + a)`, `V_b` the velocities after the translational
    /// drag (`a = share m_phi`), by fixed-point passes from `V_b`. A pass contracts the error
    /// by about `I_phi / ((M + m_phi) l^2 / 2)`, 0.2-0.4 for touching beads of any density
    /// (the fluid's mass moves with the bead). Tried: the explicit couples simply added
    /// inside the translational blend bent the rollers test's chain within 0.5 % of this
    /// solve, at bead density 1 and 0.1; the solve is kept as the drag law the translation
    /// uses, not for a measured gain.
    pub(super) fn lock_spins_implicitly(&mut self, h: f64, share: f64, torques: bool) {
        const MAX_PASSES: usize = 200;
        let Some([m_phi, i_phi]) = self.implicit_exchange else {
            return;
        };
        let n = self.pos.len();
        let (inv, b) = (1.0 / (self.mass + share * m_phi), share * i_phi);
        self.chord_base.copy_from_slice(&self.vel);
        // The spins about the tangents before this kick's angular impulses (the kick left
        // the damped angular velocities in `omega`). Each takes its drag implicitly too,
        // `s = (I s_0 + r' ) / (I + b)`, with `r'` the remainder of the angular impulse
        // less the drag on the spin itself.
        for k in 0..n {
            self.chord_axial_start[k] = self.omega[k].dot(&tangent(&self.pos, k));
        }
        let scale = self.chord_base.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for _ in 0..MAX_PASSES {
            self.turn_beads_with_chords();
            let (omega, spin, torque, pos) =
                (&self.omega, &self.chord_spin, &self.torque, &self.pos);
            couples_into(pos, &mut self.couple, &mut self.chord_axial, |i| {
                // The drag on the turn of the bead with its bonds; that on its spin about
                // the tangent is solved for below.
                let t = tangent(pos, i);
                let l = b * (spin[i] - omega[i]) + (b * omega[i].dot(&t)) * t;
                if torques {
                    l + h * torque[i]
                } else {
                    l
                }
            });
            let mut change: f64 = 0.0;
            for k in 0..n {
                if self.clamped[k] {
                    continue;
                }
                let mut v = self.chord_base[k] + self.couple[k] * inv;
                if self.planar {
                    v.z = 0.0;
                }
                change = change.max((v - self.vel[k]).norm());
                self.vel[k] = v;
                if !self.planar {
                    let t = tangent(&self.pos, k);
                    let axial = (self.inertia * self.chord_axial_start[k] + self.chord_axial[k])
                        / (self.inertia + b);
                    let now = self.omega[k].dot(&t);
                    self.omega[k] += (axial - now) * t;
                }
            }
            if change <= 1e-15 * scale.max(f64::MIN_POSITIVE) {
                break;
            }
        }
    }

    /// `bead_spin = "chord"`: the angular impulse bead i takes in this kick (the fluid's share
    /// and `h` times its load torques), `L_i`, passed to the chain as couples. Each bond
    /// (i, j), `d = X_j - X_i`, carries `w L_i` (w = 1/2 for an interior bead, 1 at an end)
    /// as the impulse `P = w L_i x d / |d|^2` on bead j and `-P` on bead i: no net impulse,
    /// and the angular impulse `d x P = w L_i` (2D: L is normal to d). So the chain takes the
    /// fluid's angular momentum into its motion instead of the beads' spin. Into `couple`.
    pub(super) fn pass_torques_to_neighbours(&mut self, h: f64, hydro: &HydroKick, torques: bool) {
        let substeps = self.substeps as f64;
        let (predicted, torque) = (&self.predicted_angular_impulse, &self.torque);
        couples_into(&self.pos, &mut self.couple, &mut self.chord_axial, |i| {
            let l = match hydro {
                HydroKick::None => Vec3::zeros(),
                HydroKick::Predicted => predicted[i] / substeps,
                HydroKick::Share(imp, share) => Vec3::from(imp[i].angular_impulse) * *share,
            };
            if torques {
                l + h * torque[i]
            } else {
                l
            }
        });
    }

    /// `bead_spin = "chord"`: each bead's angular velocity the mean rate at which its bonds
    /// turn, `d x (V_j - V_i) / |d|^2` (the one bond at an end), less its part along the
    /// bead's tangent, plus the spin about the tangent the bead had (zero in 2D).
    pub(super) fn turn_beads_with_chords(&mut self) {
        let n = self.pos.len();
        for i in 0..n {
            if self.clamped[i] {
                continue;
            }
            let bonds = [(i > 0).then(|| i - 1), (i + 1 < n).then_some(i + 1)];
            let mut w = Vec3::zeros();
            let mut count = 0.0;
            for j in bonds.into_iter().flatten() {
                let d = self.pos[j] - self.pos[i];
                w += d.cross(&(self.vel[j] - self.vel[i])) / d.norm_squared();
                count += 1.0;
            }
            let w = w / count;
            self.omega[i] = if self.planar {
                w
            } else {
                let t = tangent(&self.pos, i);
                w + (self.omega[i].dot(&t) - w.dot(&t)) * t
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::spm_fibre_2d;
    use super::*;
    use cosim::BeadImpulse;

    /// `bead_spin = "chord"`: angular impulses on the beads of a bent chain at rest become the
    /// chain's own motion. No net impulse (to round-off), the orbital angular momentum
    /// `sum X x m V` gains exactly the angular impulse given, and every bead turns at the rate
    /// of its bonds; with free spin the same impulse only spins the beads.
    #[test]
    fn a_chord_locked_chain_takes_the_fluids_torque_into_its_motion() {
        let chain = |spin: &str| {
            spm_fibre_2d(
                1.0,
                &format!(
                    "model = \"bead-spring\"\nbeads = 4\nbead_radius = 1\nyoungs_modulus = 1\n\
                     initial_bend = 0.3\nbead_spin = \"{spin}\"\n"
                ),
            )
        };
        let torques = [0.2, -0.05, 0.7, 0.1];
        let imps: Vec<BeadImpulse> = torques
            .iter()
            .map(|&t| BeadImpulse {
                impulse: [0.0; 3],
                angular_impulse: [0.0, 0.0, t],
            })
            .collect();
        let given: f64 = torques.iter().sum();
        let orbital = |f: &Fibre| -> f64 {
            (0..f.len())
                .map(|k| f.pos[k].cross(&(f.mass * f.vel[k])).z)
                .sum()
        };
        let mut f = chain("chord");
        assert!(f.spin_with_chord);
        let (l0, p0) = (orbital(&f), f.momentum());
        f.advance_velocities(1.0, Some(&imps), false);
        assert!((f.momentum() - p0).norm() < 1e-15, "{}", f.momentum());
        let gained = orbital(&f) - l0;
        assert!(
            (gained - given).abs() < 1e-12 * given,
            "{gained} vs {given}"
        );
        for i in 0..f.len() {
            let mut rate = 0.0;
            let mut bonds = 0.0;
            for j in [i.wrapping_sub(1), i + 1] {
                if j < f.len() {
                    let d = f.pos[j] - f.pos[i];
                    rate += d.cross(&(f.vel[j] - f.vel[i])).z / d.norm_squared();
                    bonds += 1.0;
                }
            }
            assert!((f.omega[i].z - rate / bonds).abs() < 1e-15, "bead {i}");
        }
        let mut free = chain("free");
        free.advance_velocities(1.0, Some(&imps), false);
        assert!(orbital(&free).abs() < 1e-15);
        assert!((free.omega[2].z - 0.7 / free.inertia).abs() < 1e-15);
    }

    /// `bead_spin = "chord"` with the implicit exchange, for beads ten times lighter than
    /// the fluid in their profiles: the spin drag `b (Omega_phi - Omega_i)` taken at the new
    /// chord rates. The velocities solve `V = (dt F + P(L(V))) / (M + a)` (the fluid at
    /// rest, so the translational drag pulls towards 0; F the bent chain's forces) to
    /// round-off; no net impulse; the chain with its
    /// profiles' fluid, `(M + a) sum X x V`, gains the angular impulse the drag gives at the
    /// new rates.
    #[test]
    fn a_chord_locked_chain_takes_the_spin_drag_at_its_new_rates() {
        let mut f = spm_fibre_2d(
            1.0,
            "model = \"bead-spring\"\nbeads = 5\nbead_radius = 1\nyoungs_modulus = 1\n\
             density = 0.1\ninitial_bend = 0.3\nbead_spin = \"chord\"\nexchange = \"implicit\"\n",
        );
        let (m_phi, i_phi) = (10.0 * f.mass, 10.0 * f.inertia);
        f.implicit_exchange = Some([m_phi, i_phi]);
        // Angular impulses I_phi (Omega_phi - 0): the fluid in each profile spinning.
        let spins = [0.02, -0.01, 0.05, 0.0, 0.03];
        let imps: Vec<BeadImpulse> = spins
            .iter()
            .map(|&w| BeadImpulse {
                impulse: [0.0; 3],
                angular_impulse: [0.0, 0.0, i_phi * w],
            })
            .collect();
        f.advance_velocities(1.0, Some(&imps), false);
        let n = f.len();
        let drag: Vec<Vec3> = (0..n)
            .map(|i| i_phi * (Vec3::new(0.0, 0.0, spins[i]) - f.omega[i]))
            .collect();
        let mut couple = vec![Vec3::zeros(); n];
        let mut axial = vec![0.0; n];
        couples_into(&f.pos, &mut couple, &mut axial, |i| drag[i]);
        let scale = f.vel.iter().map(|v| v.norm()).fold(0.0, f64::max);
        assert!(scale > 0.0);
        for k in 0..n {
            // The bent chain's own forces (dt = 1) enter the drag with the couples.
            let want = (f.force[k] + couple[k]) / (f.mass + m_phi);
            assert!((f.vel[k] - want).norm() < 1e-13 * scale, "bead {k}");
        }
        assert!(f.momentum().norm() < 1e-15 * f.mass * scale * n as f64);
        let orbital: f64 = (0..n)
            .map(|k| f.pos[k].cross(&((f.mass + m_phi) * f.vel[k])).z)
            .sum();
        let given: f64 = drag.iter().map(|l| l.z).sum();
        assert!(
            (orbital - given).abs() < 1e-12 * given.abs(),
            "{orbital} vs {given}"
        );
    }

    /// A 3D bead-spring chain of five unit beads under SPM with `bead_spin = "chord"`, bent
    /// out of every plane (bonds turning by 20-40 degrees), its bonds a few per cent
    /// stretched or compressed (with bonds of one length the bonds' share along the tangent
    /// cancels at every bead, [`split`]), at rest.
    fn bent_chain_3d(keys: &str) -> Fibre {
        let mut f = super::super::tests::fibre(&format!(
            "dimensions = 3\n[time]\ndt = 1.0\n[fluid]\nmethod = \"spm\"\n[[fibre]]\n\
             model = \"bead-spring\"\nbeads = 5\nbead_radius = 1\nyoungs_modulus = 1\n\
             bead_spin = \"chord\"\n{keys}"
        ));
        let mut p = Vec3::new(10.0, 20.0, 30.0);
        for k in 0..f.len() {
            f.pos[k] = p;
            let kf = k as f64;
            let length = [2.0, 2.1, 1.9, 2.05, 2.0][k];
            p += length * Vec3::new(1.0, 0.4 * kf, 0.25 * kf * (kf - 1.0)).normalize();
        }
        f
    }

    /// Angular impulses in every direction on the beads of a chain.
    fn angular_impulses(scale: f64) -> (Vec<BeadImpulse>, Vec3) {
        let l = [
            [0.2, -0.1, 0.3],
            [-0.05, 0.4, 0.1],
            [0.7, 0.2, -0.3],
            [0.1, 0.1, 0.1],
            [-0.3, 0.2, 0.5],
        ];
        let imps = l
            .iter()
            .map(|&a| BeadImpulse {
                impulse: [0.0; 3],
                angular_impulse: (Vec3::from(a) * scale).into(),
            })
            .collect();
        (imps, l.iter().map(|&a| Vec3::from(a) * scale).sum())
    }

    /// The split of an angular impulse between a bead's bonds and its spin about the tangent
    /// gives back the impulse, and each bond carries only what is perpendicular to it; in
    /// 2D all of it goes to the bonds, half to each of an interior bead's.
    #[test]
    fn a_split_angular_impulse_adds_up_and_each_bond_carries_only_its_perpendicular() {
        let f = bent_chain_3d("");
        let l = Vec3::new(0.3, -0.7, 0.45);
        for i in 0..f.len() {
            let mut sum = Vec3::zeros();
            let rest = split(&f.pos, i, l, |j, a| {
                let d = f.pos[j] - f.pos[i];
                assert!(
                    a.dot(&d).abs() < 1e-15,
                    "bead {i}, bond to {j}: {}",
                    a.dot(&d)
                );
                sum += a;
            });
            assert!(rest.abs() > 1e-3, "bead {i}: nothing left to the spin");
            let back = sum + rest * tangent(&f.pos, i);
            assert!((back - l).norm() < 1e-15, "bead {i}: {back} vs {l}");
        }
        let planar = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(3.8, 0.9, 0.0),
        ];
        let l = Vec3::new(0.0, 0.0, 0.8);
        for i in 0..3 {
            let w = if i == 1 { 0.5 } else { 1.0 };
            let rest = split(&planar, i, l, |_, a| assert!((a - w * l).norm() < 1e-16));
            assert!(rest.abs() < 1e-16, "{rest}");
        }
    }

    /// 3D, explicit exchange: angular impulses in every direction on a bent chain at rest.
    /// No net impulse; the chain's orbital angular momentum and the beads' spins about their
    /// tangents together gain exactly the angular impulse given; each bead turns across its
    /// tangent at the rate of its bonds.
    #[test]
    fn a_chord_locked_chain_in_3d_keeps_all_of_the_angular_impulse() {
        let mut f = bent_chain_3d("");
        let (imps, given) = angular_impulses(1.0);
        let p0 = f.momentum();
        f.advance_velocities(1.0, Some(&imps), false);
        assert!((f.momentum() - p0).norm() < 1e-14, "{}", f.momentum() - p0);
        let n = f.len();
        let mut total = Vec3::zeros();
        for k in 0..n {
            let t = tangent(&f.pos, k);
            total += f.pos[k].cross(&(f.mass * f.vel[k])) + f.inertia * f.omega[k].dot(&t) * t;
        }
        assert!(
            (total - given).norm() < 1e-12 * given.norm(),
            "{total} vs {given}"
        );
        for i in 0..n {
            let mut rate = Vec3::zeros();
            let mut bonds = 0.0;
            for j in [i.wrapping_sub(1), i + 1] {
                if j < n {
                    let d = f.pos[j] - f.pos[i];
                    rate += d.cross(&(f.vel[j] - f.vel[i])) / d.norm_squared();
                    bonds += 1.0;
                }
            }
            let t = tangent(&f.pos, i);
            let across = |w: Vec3| w - w.dot(&t) * t;
            let (got, want) = (across(f.omega[i]), across(rate / bonds));
            assert!(
                (got - want).norm() < 1e-14 * want.norm(),
                "bead {i}: {got} vs {want}"
            );
        }
    }

    /// 3D, implicit exchange, beads ten times lighter than the fluid in their profiles: the
    /// spin drag `b (Omega_phi - Omega_i)` is taken at the new rates, the part across the
    /// tangents through the bonds (`V = (dt F + P) / (M + a)`) and the spin about each
    /// tangent with its own drag, `I s = r` (r the part of the drag the bonds cannot carry);
    /// the chain with its profiles' fluid and the spins gain the angular impulse of that drag.
    #[test]
    fn a_chord_locked_chain_in_3d_takes_the_spin_drag_at_its_new_rates() {
        let mut f = bent_chain_3d("density = 0.1\nexchange = \"implicit\"\n");
        let (m_phi, i_phi) = (10.0 * f.mass, 10.0 * f.inertia);
        f.implicit_exchange = Some([m_phi, i_phi]);
        // Angular impulses I_phi (Omega_phi - 0): the fluid in each profile spinning.
        let (imps, _) = angular_impulses(0.05 * i_phi);
        f.advance_velocities(1.0, Some(&imps), false);
        let n = f.len();
        let drag: Vec<Vec3> = (0..n)
            .map(|i| Vec3::from(imps[i].angular_impulse) - i_phi * f.omega[i])
            .collect();
        let (mut couple, mut axial) = (vec![Vec3::zeros(); n], vec![0.0; n]);
        couples_into(&f.pos, &mut couple, &mut axial, |i| drag[i]);
        let scale = f.vel.iter().map(|v| v.norm()).fold(0.0, f64::max);
        assert!(scale > 0.0);
        let mut total = Vec3::zeros();
        for k in 0..n {
            let want = (f.force[k] + couple[k]) / (f.mass + m_phi);
            assert!((f.vel[k] - want).norm() < 1e-13 * scale, "bead {k}");
            let t = tangent(&f.pos, k);
            let spin = f.inertia * f.omega[k].dot(&t);
            assert!(
                (spin - axial[k]).abs() < 1e-13 * axial[k].abs(),
                "bead {k}: {spin}"
            );
            total += f.pos[k].cross(&((f.mass + m_phi) * f.vel[k])) + spin * t;
        }
        assert!(f.momentum().norm() < 1e-15 * f.mass * scale * n as f64);
        let given: Vec3 = drag.iter().sum();
        assert!(
            (total - given).norm() < 1e-12 * given.norm(),
            "{total} vs {given}"
        );
    }
}
