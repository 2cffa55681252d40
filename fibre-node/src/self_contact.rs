//! Excluded volume within a fibre (`fibre.N.self_contact = true`): two beads that are not
//! neighbours along the chain push each other apart while their spheres overlap.
//!
//! Neither paper has it: L2020's bead chain and S2023's bead-spring fibre let non-neighbouring
//! beads pass through each other. That matters once a fibre closes on itself, as in a full
//! encapsulation, where the two end beads otherwise come to lie inside each other.
//!
//! The force is a linear spring on the overlap, `U = (k_c / 2) (2 r_b - |X_i - X_j|)^2` for
//! `|X_i - X_j| < 2 r_b` and `|i - j| >= 2`, along the line of centres (so it keeps momentum
//! and angular momentum). `k_c` is the fibre's own axial bond stiffness (cohesive beam
//! `E A / l0`, L2020 eq. 11; bead-spring `k_s / l0^2`, S2023 eq. 11): a bead in contact gets
//! at most one more spring as stiff as its bonds, so the time step the bonds allow stays
//! within a factor of about 1.2 of stable. The pairs within a diameter come from a Verlet
//! list ([`crate::near_pairs`], rebuilt once a bead has moved an eighth of a diameter) and
//! are summed in index order (i, then j > i + 1), as over all pairs, so a long fibre costs
//! the beads near each bead rather than O(N^2) per force evaluation, with the same bits.
use crate::near_pairs::NearPairs;
use crate::quaternion::Vec3;

/// Contact between the non-neighbouring beads of one fibre.
#[derive(Debug, Clone)]
pub struct SelfContact {
    /// Spring constant on the overlap (force / length).
    pub stiffness: f64,
    /// Centre distance below which two beads overlap: the bead diameter `2 r_b` (length).
    pub diameter: f64,
    /// The pairs that may overlap (a cache of the positions; no part of the law).
    pairs: NearPairs,
}

/// Two contacts are equal when their laws are: the pair list only caches positions.
impl PartialEq for SelfContact {
    fn eq(&self, other: &Self) -> bool {
        self.stiffness == other.stiffness && self.diameter == other.diameter
    }
}

impl SelfContact {
    /// The contact for a fibre of `beads` beads of diameter `diameter` (length), with the
    /// spring constant `stiffness` (force / length), in the x-y plane when `planar`.
    pub fn new(stiffness: f64, diameter: f64, beads: usize, planar: bool) -> Self {
        let dims = if planar { 2 } else { 3 };
        Self {
            stiffness,
            diameter,
            pairs: NearPairs::new(beads, diameter, 0.25 * diameter, [None; 3], dims),
        }
    }

    /// Add the contact forces at `pos` to `force`; returns the contact energy.
    pub fn add_forces(&mut self, pos: &[Vec3], force: &mut [Vec3]) -> f64 {
        let (stiffness, diameter) = (self.stiffness, self.diameter);
        let mut energy = 0.0;
        self.pairs.for_each_pair(
            pos,
            |i, j| j >= i + 2,
            |i, j, d| {
                let r = d.norm();
                // Coincident centres have no line of centres: no force (and none needed to
                // keep the energy's gradient, which is undefined there).
                if r >= diameter || r == 0.0 {
                    return;
                }
                let overlap = diameter - r;
                let f = d * (stiffness * overlap / r);
                force[i] += f;
                force[j] -= f;
                energy += 0.5 * stiffness * overlap * overlap;
            },
        );
        energy
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient_check::assert_force_is_minus_the_gradient;
    use crate::xorshift::Xorshift;

    fn contact(beads: usize) -> SelfContact {
        SelfContact::new(2.5, 2.0, beads, false)
    }

    /// A chain folded so that beads 0 and 3, and 1 and 4, overlap; 0 and 2 are close but
    /// (as second neighbours) still count, while 0 and 1 (neighbours) never do.
    fn folded() -> Vec<Vec3> {
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.9, 0.1, 0.0),
            Vec3::new(1.8, 1.7, 0.2),
            Vec3::new(0.3, 1.2, -0.1),
            Vec3::new(1.2, 1.1, 0.4),
        ]
    }

    #[test]
    fn force_is_minus_the_gradient_of_the_energy() {
        let pos = folded();
        let mut c = contact(pos.len());
        assert!(c.add_forces(&pos, &mut vec![Vec3::zeros(); pos.len()]) > 0.0);
        assert_force_is_minus_the_gradient(&pos, |p, f| c.clone().add_forces(p, f));
    }

    #[test]
    fn keeps_momentum_and_angular_momentum_and_spares_neighbours() {
        let pos = folded();
        let mut force = vec![Vec3::zeros(); pos.len()];
        contact(5).add_forces(&pos, &mut force);
        let net: Vec3 = force.iter().sum();
        let torque: Vec3 = pos.iter().zip(&force).map(|(x, f)| x.cross(f)).sum();
        assert!(
            net.norm() < 1e-14 && torque.norm() < 1e-13,
            "{net} {torque}"
        );
        // Neighbours overlapping (0-1 at distance 1.9 < 2) alone give nothing.
        let pair = [Vec3::zeros(), Vec3::new(1.9, 0.0, 0.0)];
        let mut f2 = vec![Vec3::zeros(); 2];
        assert_eq!(contact(2).add_forces(&pair, &mut f2), 0.0);
        assert_eq!(f2, vec![Vec3::zeros(); 2]);
        // Second neighbours just apart: nothing either.
        let apart = [
            Vec3::zeros(),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
        ];
        let mut f3 = vec![Vec3::zeros(); 3];
        assert_eq!(contact(3).add_forces(&apart, &mut f3), 0.0);
    }

    /// The law over all pairs (i, then j > i + 1), as the contact was first written.
    fn over_all_pairs(c: &SelfContact, pos: &[Vec3], force: &mut [Vec3]) -> f64 {
        let mut energy = 0.0;
        for i in 0..pos.len() {
            for j in i + 2..pos.len() {
                let d = pos[i] - pos[j];
                let r = d.norm();
                if r >= c.diameter || r == 0.0 {
                    continue;
                }
                let overlap = c.diameter - r;
                let f = d * (c.stiffness * overlap / r);
                force[i] += f;
                force[j] -= f;
                energy += 0.5 * c.stiffness * overlap * overlap;
            }
        }
        energy
    }

    /// A 400-bead random-walk coil (bonds of one diameter, folded back on itself) whose beads
    /// jiggle for 60 steps: the forces and the energy from the pair list are those over all
    /// pairs, bit for bit, every step, while the list is rebuilt only now and then.
    #[test]
    fn the_pair_list_gives_the_bits_of_all_pairs_on_a_moving_coil() {
        let mut seed = Xorshift(0x9E37_79B9_7F4A_7C15);
        let mut uniform = move || seed.uniform() - 0.5;
        let mut pos = vec![Vec3::zeros()];
        for _ in 1..400 {
            let step = Vec3::new(uniform(), uniform(), uniform()).normalize() * 2.0;
            let last = pos[pos.len() - 1];
            // Turned back at the faces of a box of side 12, so that the beads crowd.
            let next = Vec3::from_fn(|k, _| {
                if (last[k] + step[k]).abs() > 6.0 {
                    last[k] - step[k]
                } else {
                    last[k] + step[k]
                }
            });
            pos.push(next);
        }
        let mut c = contact(pos.len());
        let mut overlapping = 0;
        for step in 0..60 {
            let (mut fast, mut slow) = (vec![Vec3::zeros(); 400], vec![Vec3::zeros(); 400]);
            let e = c.add_forces(&pos, &mut fast);
            let e_all = over_all_pairs(&c, &pos, &mut slow);
            assert_eq!(e.to_bits(), e_all.to_bits(), "step {step}");
            assert_eq!(fast, slow, "step {step}");
            overlapping += (e > 0.0) as usize;
            for p in pos.iter_mut() {
                *p += Vec3::new(uniform(), uniform(), uniform()) * 0.05;
            }
        }
        assert_eq!(overlapping, 60);
        let builds = c.pairs.rebuilds();
        assert!((2..30).contains(&builds), "{builds} builds");
    }
}
