//! `[fluid.stream]`: a uniform stream past held bodies on the periodic FPD lattice, for the
//! drag of a fixed cylinder (S2023 section III B, Fig. 4).
//!
//! The lattice starts at the stream velocity `(U, 0)`. The box is periodic in x, so the wake
//! would come round and hit the body again; a sponge of `width` columns at the right end of
//! the box (upstream of x = 0 through the periodic wrap) forces the flow back to the stream,
//! `f = sigma(x) rho (U - u)`, with sigma rising as `rate sin^2` over the sponge's first half
//! and the velocity of the last step. Walls, if any, must slide at U: in the body's frame
//! they are the far field (a towing tank), and the blockage d / H is reported.
use crate::mrt_d2q9::MrtD2q9;
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawStream {
    velocity: f64,
    sponge: f64,
    sponge_rate: Option<f64>,
}

/// Default largest sponge rate per step: strong enough to erase a Re <= 40 wake over a few
/// diameters, weak enough that the ramp reflects little.
pub const DEFAULT_SPONGE_RATE: f64 = 0.1;

/// The validated `[fluid.stream]` table.
#[derive(Debug, Clone, PartialEq)]
pub struct UniformStream {
    /// Stream velocity U along x (lattice units per step).
    pub velocity: f64,
    /// Sponge width (lattice columns at the right end of the box).
    pub width: usize,
    /// Largest relaxation rate of the sponge (1 / step).
    pub rate: f64,
    /// `(column, sigma)` of the sponge.
    columns: Vec<(usize, f64)>,
}

impl UniformStream {
    /// Check `[fluid.stream]` against the box `nx` and the walls' velocities.
    pub(super) fn new(
        raw: RawStream,
        nx: usize,
        walls: Option<[f64; 2]>,
        max_mach: f64,
    ) -> Result<Self, String> {
        let u = raw.velocity;
        let mach = u.abs() * 3f64.sqrt();
        // A NaN velocity is refused too.
        if mach.is_nan() || mach > max_mach {
            return Err(format!(
                "fluid.stream.velocity = {}: Mach number |U| sqrt 3 = {:.3} exceeds the \
                 lattice's limit {max_mach}; lower U (and the viscosity, to keep Re)",
                cosim::scene_keys::Num(u),
                cosim::scene_keys::Num(mach)
            ));
        }
        if let Some([b, t]) = walls {
            if b != u || t != u {
                return Err(format!(
                    "walls.velocity = {} with fluid.stream.velocity = {}: in a uniform \
                     stream the walls are the far field and slide at the stream speed; set \
                     walls.velocity = {} or remove [walls] (periodic in y)",
                    cosim::scene_keys::Nums(&[b, t]),
                    cosim::scene_keys::Num(u),
                    cosim::scene_keys::Nums(&[u, u])
                ));
            }
        }
        let width = raw.sponge;
        if !(width >= 2.0 && width <= 0.5 * nx as f64) || width.fract() != 0.0 {
            return Err(format!(
                "fluid.stream.sponge = {width}: expected a whole number of lattice columns \
                 between 2 and half the box (nx / 2 = {})",
                nx / 2
            ));
        }
        let rate = raw.sponge_rate.unwrap_or(DEFAULT_SPONGE_RATE);
        if !(rate > 0.0 && rate <= 1.0) {
            return Err(format!(
                "fluid.stream.sponge_rate = {rate}: expected a rate in (0, 1] per step"
            ));
        }
        let width = width as usize;
        let half = 0.5 * width as f64;
        let columns = (nx - width..nx)
            .map(|x| {
                let s = ((x - (nx - width)) as f64 + 0.5) / half;
                let ramp = (0.5 * std::f64::consts::PI * s.min(1.0)).sin();
                (x, rate * ramp * ramp)
            })
            .collect();
        Ok(Self {
            velocity: u,
            width,
            rate,
            columns,
        })
    }

    /// First sponge column.
    pub fn start(&self) -> usize {
        self.columns[0].0
    }

    /// Write the sponge force into the lattice's force density; the bead profiles write
    /// theirs afterwards, in nodes the sponge never touches ([`UniformStream::check_clear`]).
    pub fn apply(&self, lattice: &mut MrtD2q9) {
        let ny = lattice.ny();
        let u = self.velocity;
        for y in 0..ny {
            for &(x, s) in &self.columns {
                let (rho, ux, uy) = lattice.node(x, y);
                let k = lattice.index(x, y);
                let (fx, fy) = lattice.force_mut();
                fx[k] = s * rho * (u - ux);
                fy[k] = -s * rho * uy;
            }
        }
    }

    /// Refuse a bead whose profile (centre x, reach) overlaps the sponge, where the two
    /// force densities would overwrite each other.
    pub fn check_clear(&self, bead: usize, x: f64, reach: f64, nx: usize) -> Result<(), String> {
        let x = x.rem_euclid(nx as f64);
        let (lo, hi) = (self.start() as f64 - 0.5, nx as f64 - 0.5);
        if x + reach >= lo || x - reach < -0.5 {
            return Err(format!(
                "bead {bead} at x = {x:.2} (profile reach {reach:.2}) touches the sponge of \
                 fluid.stream (columns {lo:.1}..{hi:.1} and their periodic image at the left \
                 edge): move the body or narrow the sponge"
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn raw(velocity: f64, sponge: f64) -> RawStream {
        RawStream {
            velocity,
            sponge,
            sponge_rate: None,
        }
    }

    #[test]
    fn sponge_ramps_up_over_its_first_half() {
        let s = UniformStream::new(raw(0.05, 8.0), 64, None, 0.3).unwrap();
        assert_eq!(s.start(), 56);
        let sig: Vec<f64> = s.columns.iter().map(|c| c.1).collect();
        assert!(sig.windows(2).all(|w| w[1] >= w[0]));
        assert!(sig[0] > 0.0 && sig[0] < 0.1 * DEFAULT_SPONGE_RATE);
        assert!(sig[4..].iter().all(|&v| v == DEFAULT_SPONGE_RATE));
    }

    #[test]
    fn refusals_name_the_key() {
        let e = UniformStream::new(raw(0.3, 8.0), 64, None, 0.3).unwrap_err();
        assert!(
            e.contains("fluid.stream.velocity") && e.contains("Mach"),
            "{e}"
        );
        let e = UniformStream::new(raw(0.05, 40.0), 64, None, 0.3).unwrap_err();
        assert!(e.contains("fluid.stream.sponge"), "{e}");
        let e = UniformStream::new(raw(0.05, 8.0), 64, Some([0.0, 0.05]), 0.3).unwrap_err();
        assert!(e.contains("walls.velocity = [0.05, 0.05]"), "{e}");
        let s = UniformStream::new(raw(0.05, 8.0), 64, Some([0.05, 0.05]), 0.3).unwrap();
        assert!(s.check_clear(0, 30.0, 10.0, 64).is_ok());
        assert!(s.check_clear(0, 50.0, 10.0, 64).is_err());
        assert!(s.check_clear(0, 5.0, 10.0, 64).is_err());
    }
}
