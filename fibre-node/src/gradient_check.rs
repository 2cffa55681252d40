//! Test support: a force law checked against its energy by central differences.
use crate::quaternion::Vec3;

/// `add_forces(pos, force)` adds the forces at `pos` to `force` and returns the energy; every
/// component of the force must be minus the energy's derivative (step 1e-6, to 1e-7).
pub fn assert_force_is_minus_the_gradient(
    pos: &[Vec3],
    add_forces: impl Fn(&[Vec3], &mut [Vec3]) -> f64,
) {
    let mut force = vec![Vec3::zeros(); pos.len()];
    add_forces(pos, &mut force);
    let h = 1e-6;
    for b in 0..pos.len() {
        for k in 0..3 {
            let energy_at = |s: f64| {
                let mut p = pos.to_vec();
                p[b][k] += s;
                add_forces(&p, &mut vec![Vec3::zeros(); p.len()])
            };
            let grad = (energy_at(h) - energy_at(-h)) / (2.0 * h);
            assert!(
                (force[b][k] + grad).abs() < 1e-7,
                "bead {b} axis {k}: force {} against -dU/dx {}",
                force[b][k],
                -grad
            );
        }
    }
}
