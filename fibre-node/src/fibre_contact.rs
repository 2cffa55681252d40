//! Excluded volume between fibres (`fibre.N.fibre_contact = true`): beads of two different
//! fibres that both have the key push each other apart while their spheres overlap.
//!
//! Neither paper has it (both simulate one fibre at a time). The force is the one of
//! [`crate::self_contact`] between fibres: `U = (k / 2) (r_a + r_b - |X_i - X_j|)^2` while
//! positive, along the line of centres (minimum image across the fluid's periodic box), so it
//! keeps momentum and angular momentum. `k` is the smaller of the two fibres' contact
//! stiffnesses (each its axial bond stiffness, as for the self contact): a bead touching one
//! bead of another fibre gets one more spring as stiff as its own bonds, a bead lodged between
//! two of them two. Near the beam-stiffness limit that can make the step unstable (two fibres
//! crossing at 0.88 of it grew for thousands of steps); the coordinator's energy watch ends
//! such a run (coordinator/src/energy_watch.rs).
//!
//! The fibres then depend on each other within a step: the fibre node takes their sub-steps
//! together ([`crate::fibre::together`]), refreshing the contact before every force
//! evaluation, which needs the same `fibre.N.substeps` on every fibre.
use crate::fibre::Fibre;
use crate::near_pairs::NearPairs;
use crate::quaternion::Vec3;

/// The contact between the fibres of a scene.
#[derive(Debug, Clone)]
pub struct FibreContact {
    /// Each bead's fibre, radius and contact stiffness (0: the fibre has no contact).
    fibre_of: Vec<u32>,
    radius: Vec<f64>,
    stiffness: Vec<f64>,
    pairs: NearPairs,
    /// Gathered positions, and the forces and energy per bead (half a pair's each).
    pos: Vec<Vec3>,
    force: Vec<Vec3>,
    energy: Vec<f64>,
}

impl FibreContact {
    /// The contact between fibres of `(beads, bead radius, contact stiffness or None)`, in a
    /// box wrapping with the lengths `period`, in `dims` dimensions. `None` unless at least
    /// two fibres have the contact.
    pub fn new(
        fibres: &[(usize, f64, Option<f64>)],
        period: [Option<f64>; 3],
        dims: usize,
    ) -> Option<Self> {
        if fibres.iter().filter(|f| f.2.is_some()).count() < 2 {
            return None;
        }
        let (mut fibre_of, mut radius, mut stiffness) = (Vec::new(), Vec::new(), Vec::new());
        for (n, &(beads, r, k)) in fibres.iter().enumerate() {
            fibre_of.extend(std::iter::repeat_n(n as u32, beads));
            radius.extend(std::iter::repeat_n(r, beads));
            stiffness.extend(std::iter::repeat_n(k.unwrap_or(0.0), beads));
        }
        let beads = radius.len();
        let largest = radius.iter().cloned().fold(0.0, f64::max);
        Some(Self {
            fibre_of,
            radius,
            stiffness,
            // Rebuilt once a bead has moved a quarter of the largest radius.
            pairs: NearPairs::new(beads, 2.0 * largest, 0.5 * largest, period, dims),
            pos: Vec::with_capacity(beads),
            force: vec![Vec3::zeros(); beads],
            energy: vec![0.0; beads],
        })
    }

    /// The contact forces at the fibres' current positions, into each fibre's
    /// `fibre_contact_force` and `fibre_contact_energy` (which its next force evaluation
    /// adds).
    pub fn apply(&mut self, fibres: &mut [Fibre]) {
        self.pos.clear();
        for f in fibres.iter() {
            self.pos.extend_from_slice(&f.pos);
        }
        self.evaluate();
        let mut offset = 0;
        for f in fibres.iter_mut() {
            let n = f.len();
            if f.fibre_contact_force.len() == n {
                f.fibre_contact_force
                    .copy_from_slice(&self.force[offset..offset + n]);
                f.fibre_contact_energy = self.energy[offset..offset + n].iter().sum();
            }
            offset += n;
        }
    }

    /// Forces and energies at `self.pos`, pairs in index order.
    fn evaluate(&mut self) {
        self.force.fill(Vec3::zeros());
        self.energy.fill(0.0);
        let (fibre_of, radius, stiffness) = (&self.fibre_of, &self.radius, &self.stiffness);
        let (force, energy) = (&mut self.force, &mut self.energy);
        let keep =
            |i: usize, j: usize| fibre_of[i] != fibre_of[j] && stiffness[i].min(stiffness[j]) > 0.0;
        self.pairs.for_each_pair(&self.pos, keep, |i, j, d| {
            let k = stiffness[i].min(stiffness[j]);
            let r = d.norm();
            let overlap = radius[i] + radius[j] - r;
            // Coincident centres have no line of centres: no force (as the self contact).
            if overlap <= 0.0 || r == 0.0 {
                return;
            }
            let f = d * (k * overlap / r);
            force[i] += f;
            force[j] -= f;
            let e = 0.25 * k * overlap * overlap;
            energy[i] += e;
            energy[j] += e;
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient_check::assert_force_is_minus_the_gradient;

    type Specs = Vec<(usize, f64, Option<f64>)>;

    /// Three short fibres crossing one another (and one across the periodic seam in x),
    /// the last without the contact.
    fn crossing() -> (Specs, Vec<Vec3>) {
        let specs = vec![(3, 1.0, Some(2.0)), (3, 0.8, Some(5.0)), (2, 1.0, None)];
        let pos = vec![
            Vec3::new(0.2, 0.0, 0.0),
            Vec3::new(2.0, 0.1, 0.0),
            Vec3::new(4.0, 0.0, 0.1),
            Vec3::new(2.3, -1.2, 0.3),
            Vec3::new(2.1, 0.4, -0.2),
            Vec3::new(19.4, 0.2, 0.1),
            Vec3::new(2.0, 0.5, 0.0),
            Vec3::new(4.2, 0.3, 0.0),
        ];
        (specs, pos)
    }

    fn energy_and_forces(c: &mut FibreContact, pos: &[Vec3], force: &mut [Vec3]) -> f64 {
        c.pos.clear();
        c.pos.extend_from_slice(pos);
        c.evaluate();
        for (f, g) in force.iter_mut().zip(&c.force) {
            *f += g;
        }
        c.energy.iter().sum()
    }

    #[test]
    fn force_is_minus_the_gradient_and_only_fibres_with_the_contact_repel() {
        let (specs, pos) = crossing();
        let mut c = FibreContact::new(&specs, [Some(20.0), None, None], 3).unwrap();
        let mut force = vec![Vec3::zeros(); pos.len()];
        let e = energy_and_forces(&mut c, &pos, &mut force);
        assert!(e > 0.0);
        // The third fibre overlaps the first two but has no contact: no force on it.
        assert_eq!(&force[6..], &[Vec3::zeros(); 2]);
        // Across the seam: bead 5 (x = 19.4) touches bead 0 (x = 0.2 = 20.2).
        assert!(force[5].x < 0.0 && force[0].x > 0.0, "{:?}", force);
        let net: Vec3 = force.iter().sum();
        assert!(net.norm() < 1e-14, "{net}");
        let c = std::cell::RefCell::new(c);
        assert_force_is_minus_the_gradient(&pos, |p, f| {
            energy_and_forces(&mut c.borrow_mut(), p, f)
        });
    }

    #[test]
    fn keeps_angular_momentum_and_needs_two_fibres_with_the_contact() {
        let (specs, pos) = crossing();
        // Without a periodic box the torque of the pair forces about the origin vanishes.
        let mut c = FibreContact::new(&specs, [None; 3], 3).unwrap();
        let mut force = vec![Vec3::zeros(); pos.len()];
        energy_and_forces(&mut c, &pos, &mut force);
        let torque: Vec3 = pos.iter().zip(&force).map(|(x, f)| x.cross(f)).sum();
        assert!(torque.norm() < 1e-13, "{torque}");
        assert!(force.iter().any(|f| f.norm() > 0.1));
        assert!(FibreContact::new(&[(3, 1.0, Some(1.0)), (3, 1.0, None)], [None; 3], 2).is_none());
    }
}
