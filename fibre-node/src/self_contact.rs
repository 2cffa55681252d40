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
//! within a factor of about 1.2 of stable. Pairs are visited in a fixed order (i, then
//! j > i + 1), O(N^2) per force evaluation.
use crate::quaternion::Vec3;

/// Contact between the non-neighbouring beads of one fibre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfContact {
    /// Spring constant on the overlap (force / length).
    pub stiffness: f64,
    /// Centre distance below which two beads overlap: the bead diameter `2 r_b` (length).
    pub diameter: f64,
}

impl SelfContact {
    /// Add the contact forces at `pos` to `force`; returns the contact energy.
    pub fn add_forces(&self, pos: &[Vec3], force: &mut [Vec3]) -> f64 {
        let mut energy = 0.0;
        for i in 0..pos.len() {
            for j in i + 2..pos.len() {
                let d = pos[i] - pos[j];
                let r = d.norm();
                // Coincident centres have no line of centres: no force (and none needed to
                // keep the energy's gradient, which is undefined there).
                if r >= self.diameter || r == 0.0 {
                    continue;
                }
                let overlap = self.diameter - r;
                let f = d * (self.stiffness * overlap / r);
                force[i] += f;
                force[j] -= f;
                energy += 0.5 * self.stiffness * overlap * overlap;
            }
        }
        energy
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient_check::assert_force_is_minus_the_gradient;

    fn contact() -> SelfContact {
        SelfContact {
            stiffness: 2.5,
            diameter: 2.0,
        }
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
        let c = contact();
        let pos = folded();
        assert!(c.add_forces(&pos, &mut vec![Vec3::zeros(); pos.len()]) > 0.0);
        assert_force_is_minus_the_gradient(&pos, |p, f| c.add_forces(p, f));
    }

    #[test]
    fn keeps_momentum_and_angular_momentum_and_spares_neighbours() {
        let c = contact();
        let pos = folded();
        let mut force = vec![Vec3::zeros(); pos.len()];
        c.add_forces(&pos, &mut force);
        let net: Vec3 = force.iter().sum();
        let torque: Vec3 = pos.iter().zip(&force).map(|(x, f)| x.cross(f)).sum();
        assert!(
            net.norm() < 1e-14 && torque.norm() < 1e-13,
            "{net} {torque}"
        );
        // Neighbours overlapping (0-1 at distance 1.9 < 2) alone give nothing.
        let pair = [Vec3::zeros(), Vec3::new(1.9, 0.0, 0.0)];
        let mut f2 = vec![Vec3::zeros(); 2];
        assert_eq!(c.add_forces(&pair, &mut f2), 0.0);
        assert_eq!(f2, vec![Vec3::zeros(); 2]);
        // Second neighbours just apart: nothing either.
        let apart = [
            Vec3::zeros(),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
        ];
        let mut f3 = vec![Vec3::zeros(); 3];
        assert_eq!(c.add_forces(&apart, &mut f3), 0.0);
    }
}
