//! `fibre.N.bead_spin = "chord"`: the beads of a bead-spring chain turned with their bonds
//! instead of spinning freely (docs/validation/fpd.md, "Beads turned with their chords").
//! Each bead's angular velocity is the mean rate at which its bonds turn, and the angular
//! impulse a bead takes (the fluid's share, its load torques) is passed to its bonds as
//! couples, so the chain takes it into its orbital motion. Called from the kicks of
//! [`Fibre`]'s integrator (parent module).
use super::{Fibre, HydroKick};
use crate::quaternion::Vec3;

/// The linear impulses that pass the angular impulse `l(i)` of each bead of a chain at `pos`
/// to its bonds, into `couple`: bond (i, j), `d = X_j - X_i`, carries `w l(i)` (w = 1/2 for an
/// interior bead, 1 at an end) as `P = w l(i) x d / |d|^2` on bead j and `-P` on bead i.
fn couples_into(pos: &[Vec3], couple: &mut [Vec3], l: impl Fn(usize) -> Vec3) {
    let n = pos.len();
    for c in couple.iter_mut() {
        *c = Vec3::zeros();
    }
    for i in 0..n {
        let l = l(i);
        let bonds = [(i > 0).then(|| i - 1), (i + 1 < n).then_some(i + 1)];
        let w = if bonds.iter().all(Option::is_some) {
            0.5
        } else {
            1.0
        };
        for j in bonds.into_iter().flatten() {
            let d = pos[j] - pos[i];
            let p = (w * l).cross(&d) / d.norm_squared();
            couple[j] += p;
            couple[i] -= p;
        }
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
        let scale = self.chord_base.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for _ in 0..MAX_PASSES {
            self.turn_beads_with_chords();
            let (omega, spin, torque) = (&self.omega, &self.chord_spin, &self.torque);
            couples_into(&self.pos, &mut self.couple, |i| {
                let l = b * (spin[i] - omega[i]);
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
        couples_into(&self.pos, &mut self.couple, |i| {
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
    /// turn, `d x (V_j - V_i) / |d|^2` (the one bond at an end).
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
            self.omega[i] = w / count;
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
        couples_into(&f.pos, &mut couple, |i| drag[i]);
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
}
