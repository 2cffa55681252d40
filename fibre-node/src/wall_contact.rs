//! Beads kept out of the walls (`fibre.N.wall_contact = true`): a bead whose sphere reaches
//! past a wall's face is pushed back along the wall's normal.
//!
//! Neither paper has it. Under SPM nothing else keeps a bead out of a wall slab: once its
//! profile overlaps the slab's, the fluid between them is gone, and a fibre tumbling next to
//! a wall dips an end into it (docs/validation/spm.md, "A fibre next to a wall"). Under FPD a
//! bead moves with the flow in its profile, which the bounce-back wall slows but does not
//! stop.
//!
//! The force is a linear spring on the overlap, `U = (k_c / 2) delta^2` with
//! `delta = r_b - (y - y_bottom)` at the bottom face and `delta = y + r_b - y_top` at the top
//! (for `delta > 0`), normal to the walls and through the bead's centre: frictionless, no
//! torque. `k_c` is the fibre's axial bond stiffness, as for [`crate::self_contact`]: a bead
//! in contact gets at most one more spring as stiff as one of its bonds, so the time step the
//! bonds allow stays within a factor of about 1.2 of stable. The walls are planes normal to
//! y (both fluid methods); their faces come from the scene
//! ([`cosim::scene_keys::wall_faces`]).
use crate::quaternion::Vec3;

/// Contact between the beads of one fibre and the two walls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallContact {
    /// Spring constant on the overlap (force / length).
    pub stiffness: f64,
    /// Bead radius `r_b` (length).
    pub radius: f64,
    /// y of the bottom and the top wall's face (length).
    pub faces: [f64; 2],
}

/// How far a sphere of radius `r` at height `y` reaches past the wall faces `[bottom, top]`:
/// the bottom overlap and the top overlap, each 0 when clear (length).
pub fn overlaps(faces: [f64; 2], r: f64, y: f64) -> [f64; 2] {
    [(r - (y - faces[0])).max(0.0), (y + r - faces[1]).max(0.0)]
}

impl WallContact {
    /// Add the contact forces at `pos` to `force`; returns the contact energy.
    pub fn add_forces(&self, pos: &[Vec3], force: &mut [Vec3]) -> f64 {
        let mut energy = 0.0;
        for (p, f) in pos.iter().zip(force.iter_mut()) {
            let [bottom, top] = overlaps(self.faces, self.radius, p.y);
            f.y += self.stiffness * (bottom - top);
            energy += 0.5 * self.stiffness * (bottom * bottom + top * top);
        }
        energy
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient_check::assert_force_is_minus_the_gradient;

    fn contact() -> WallContact {
        WallContact {
            stiffness: 2.5,
            radius: 2.0,
            faces: [3.5, 20.5],
        }
    }

    /// Beads clear of both walls (one only just) and reaching into each.
    fn beads() -> Vec<Vec3> {
        vec![
            Vec3::new(0.0, 10.0, 0.0),
            Vec3::new(1.0, 5.6, 0.3),
            Vec3::new(2.0, 4.7, 0.0),
            Vec3::new(3.0, 19.1, -0.2),
            Vec3::new(4.0, 2.0, 0.0),
        ]
    }

    #[test]
    fn force_is_minus_the_gradient_of_the_energy() {
        let c = contact();
        let pos = beads();
        let mut force = vec![Vec3::zeros(); pos.len()];
        let e0 = c.add_forces(&pos, &mut force);
        // 0.8, 0.6 and 3.5 reach into the walls: (k / 2) (0.64 + 0.36 + 12.25).
        assert!((e0 - 1.25 * 13.25).abs() < 1e-12, "{e0}");
        assert_force_is_minus_the_gradient(&pos, |p, f| c.add_forces(p, f));
    }

    #[test]
    fn pushes_out_along_the_normal_and_spares_beads_that_are_clear() {
        let c = contact();
        let pos = beads();
        let mut force = vec![Vec3::zeros(); pos.len()];
        c.add_forces(&pos, &mut force);
        // Clear of both walls, or only just: nothing.
        assert_eq!(force[0], Vec3::zeros());
        assert_eq!(force[1], Vec3::zeros());
        // Into the bottom wall: up; into the top wall: down; only along y.
        assert!((force[2].y - 2.5 * 0.8).abs() < 1e-12 && force[2].x == 0.0);
        assert!((force[3].y + 2.5 * 0.6).abs() < 1e-12 && force[3].z == 0.0);
        assert!((force[4].y - 2.5 * 3.5).abs() < 1e-12);
        // Touching is not overlapping.
        assert_eq!(overlaps(c.faces, 2.0, 5.5), [0.0, 0.0]);
        assert_eq!(overlaps(c.faces, 2.0, 18.5), [0.0, 0.0]);
    }
}
