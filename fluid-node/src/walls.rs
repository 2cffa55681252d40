//! Two moving solid slabs normal to y, smoothed like beads (L2020 eq. 25 across their faces)
//! and penalised like a bead with a fixed velocity (eqs. 37–38).
//!
//! Geometry (grid units, nodes at y = 0..ny, periodic): with T = `walls.thickness`, the
//! bottom slab holds the nodes 0..T, the top slab the nodes ny - T..ny; the two meet inside
//! the solid halfway between nodes ny - 1 and 0 (y = -1/2 ≡ ny - 1/2), where the velocity
//! jumps from the top to the bottom wall speed, T from either face. The inner faces
//! (phi = 1/2) are at y_b = T - 1/2 and y_t = ny - T - 1/2, halfway between nodes, so the two
//! slabs are sampled alike; the fluid gap between them is H = ny - 2 T. The reference for
//! plane Couette flow is the linear profile u_x(y) = u_b + (u_t - u_b) (y - y_b) / H.
use crate::config::WallsConfig;
use crate::smoothed_profile::interface;

/// The slabs' profile and velocity per y, and the Couette reference.
#[derive(Debug, Clone)]
pub struct Walls {
    /// x-velocities of the bottom and top slab.
    pub velocity: [f64; 2],
    pub thickness: f64,
    /// y of the inner faces (phi = 1/2).
    pub faces: [f64; 2],
    /// Distance between the inner faces.
    pub gap: f64,
    /// Wall volume fraction per y.
    phi: Vec<f64>,
    /// Wall x-velocity per y.
    speed: Vec<f64>,
    /// The y where phi > 0.
    rows: Vec<usize>,
    /// The y where the Couette error is measured: between the faces, at least 2 xi away.
    check: Vec<usize>,
}

impl Walls {
    pub fn new(ny: usize, cfg: &WallsConfig, xi: f64, cutoff: f64) -> Self {
        let t = cfg.thickness;
        let [bottom_face, top_face] = cosim::scene_keys::slab_faces(ny as f64, t);
        let middle = 0.5 * (bottom_face + top_face);
        let mut phi = Vec::with_capacity(ny);
        let mut speed = Vec::with_capacity(ny);
        for y in 0..ny {
            let yf = y as f64;
            let (s, u) = if yf < middle {
                (bottom_face - yf, cfg.velocity[0])
            } else {
                (yf - top_face, cfg.velocity[1])
            };
            phi.push(interface(s, xi, cutoff));
            speed.push(u);
        }
        let rows = (0..ny).filter(|&y| phi[y] > 0.0).collect();
        let check = (0..ny)
            .filter(|&y| {
                let yf = y as f64;
                yf >= bottom_face + 2.0 * xi && yf <= top_face - 2.0 * xi
            })
            .collect();
        Self {
            velocity: cfg.velocity,
            thickness: t,
            faces: [bottom_face, top_face],
            gap: top_face - bottom_face,
            phi,
            speed,
            rows,
            check,
        }
    }

    /// Wall volume fraction at row y.
    #[inline]
    pub fn phi(&self, y: usize) -> f64 {
        self.phi[y]
    }

    /// Wall x-velocity at row y (the slab the row belongs to).
    #[inline]
    pub fn speed(&self, y: usize) -> f64 {
        self.speed[y]
    }

    /// The rows where the walls' profile is non-zero.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// Shear rate (u_t - u_b) / H.
    pub fn shear_rate(&self) -> f64 {
        (self.velocity[1] - self.velocity[0]) / self.gap
    }

    /// The linear Couette profile between the faces at height y.
    pub fn linear(&self, y: f64) -> f64 {
        self.velocity[0] + self.shear_rate() * (y - self.faces[0])
    }

    /// Initial x-velocity of `fluid.initial_velocity = "couette"`: the linear profile in the
    /// gap and the slab's own speed inside each slab.
    pub fn couette_start(&self, y: usize) -> f64 {
        let yf = y as f64;
        if yf < self.faces[0] || yf > self.faces[1] {
            self.speed[y]
        } else {
            self.linear(yf)
        }
    }

    /// max over the checked rows of |<u_x>(y) - linear(y)| / |u_t - u_b| (absolute when the
    /// walls move together), `profile[y]` the plane average of u_x.
    pub fn couette_error(&self, profile: &[f64]) -> f64 {
        let du = (self.velocity[1] - self.velocity[0]).abs();
        let scale = if du > 0.0 { du } else { 1.0 };
        self.check
            .iter()
            .map(|&y| (profile[y] - self.linear(y as f64)).abs() / scale)
            .fold(0.0, f64::max)
    }

    /// Largest wall speed.
    pub fn max_speed(&self) -> f64 {
        self.velocity[0].abs().max(self.velocity[1].abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slabs_faces_and_reference() {
        let w = Walls::new(
            64,
            &WallsConfig {
                velocity: [-0.1, 0.1],
                thickness: 4.0,
            },
            1.0,
            3.0,
        );
        assert_eq!(w.faces, [3.5, 59.5]);
        assert_eq!(w.gap, 56.0);
        assert_eq!(w.phi(3), w.phi(60));
        assert!((w.phi(4) - (1.0 - w.phi(3))).abs() < 1e-16);
        assert_eq!(w.phi(0), 1.0);
        assert_eq!(w.phi(63), 1.0);
        assert_eq!(w.phi(32), 0.0);
        assert_eq!(w.speed(63), 0.1);
        assert_eq!(w.speed(0), -0.1);
        assert_eq!(w.rows(), &[0, 1, 2, 3, 4, 5, 6, 57, 58, 59, 60, 61, 62, 63]);
        assert_eq!(w.check, (6..=57).collect::<Vec<_>>());
        assert!((w.linear(31.5)).abs() < 1e-16);
        assert_eq!(w.couette_start(2), -0.1);
        assert_eq!(w.couette_start(62), 0.1);
        assert!((w.shear_rate() - 0.2 / 56.0).abs() < 1e-18);
        let profile: Vec<f64> = (0..64).map(|y| w.couette_start(y)).collect();
        assert!(w.couette_error(&profile) < 1e-15);
    }
}
