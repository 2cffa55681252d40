//! How light a bead may be under the explicit SPM momentum exchange (L2020 eqs. 35–38).
//!
//! Each step the fluid node hands a bead the impulse `rho ∫ phi_i (u* - u_i)` over its whole
//! smoothed profile, and the penalty then sets the profile's fluid to the bead's new motion.
//! If the surrounding flow takes a fraction `k` of the profile fluid's excess motion in one
//! step, the bead's velocity relative to the flow is multiplied by `1 - k m_phi / M` per
//! step, with `m_phi = rho ∫ phi_i` the fluid in the profile and `M` the bead's mass; the
//! spin likewise by `1 - k I_phi / I`, with `I_phi = rho ∫ phi_i d²`. Since `k <= 1`, the
//! exchange is stable for any flow when both ratios stay below 2; beyond, it depends on `k`,
//! which grows with `nu dt / xi²`.
//!
//! The spin ratio is the one that bites: the diffuse profile puts its excess at the rim, so
//! at r_b = 6, xi = 2, xi_c = 5 the profile holds 1.15 (2D) and 1.46 (3D) times the sharp
//! volume but 1.99 and 2.85 times the sharp moment of inertia ([`cosim::profile`]). Measured
//! on the capillary tumbling scenes (r_b = 6, xi = 2, xi_c = 5): in 2D (nu dt / xi² = 2.5)
//! a spin ratio of 1.99 runs and 2.2 blows up within 50 steps; in 3D (nu dt / xi² = 0.63)
//! 2.34 runs and 2.48 blows up (the mass ratios were 1.2-1.3 in all of these). With the
//! bead's moment of inertia taken from its profile (`fibre.N.bead_inertia = "profile"`) the
//! 3D scene runs at bead density 1, which failed at step 34 before. The implicit exchange
//! (`fibre.N.exchange = "implicit"`, `crate::fibre`) takes the drag at the new velocity and
//! has no such limit: these beads are not checked.
use cosim::profile::{profile_moment, profile_volume};
use cosim::scene_keys::{AtLeast, Num};

/// Largest accepted ratio of the fluid in a bead's profile to the bead, in mass and in
/// moment of inertia: the bound below which the explicit exchange is stable for any flow.
pub const MAX_PROFILE_TO_BEAD: f64 = 2.0;

/// The fluid a bead's smoothed profile holds against the bead itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExchangeRatios {
    /// `rho ∫ phi_i / M`.
    pub mass: f64,
    /// `rho ∫ phi_i d² / I`.
    pub inertia: f64,
}

/// The profile of L2020 eq. 25 (interface width and cut-off, grid units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothedProfile {
    pub xi: f64,
    pub cutoff: f64,
}

impl SmoothedProfile {
    /// Mass and moment of inertia of one bead's profile filled at `density`.
    pub fn mass_inertia(&self, density: f64, radius: f64, dims: usize) -> (f64, f64) {
        (
            density * profile_volume(radius, self.xi, self.cutoff, dims),
            density * profile_moment(radius, self.xi, self.cutoff, dims),
        )
    }
}

/// The ratios for a bead of `mass` and `inertia` in a fluid of `fluid_density`.
pub fn ratios(
    profile: SmoothedProfile,
    fluid_density: f64,
    radius: f64,
    dims: usize,
    mass: f64,
    inertia: f64,
) -> ExchangeRatios {
    let (m, i) = profile.mass_inertia(fluid_density, radius, dims);
    ExchangeRatios {
        mass: m / mass,
        inertia: i / inertia,
    }
}

/// Refuse a bead too light for the explicit exchange, naming the ratio, the limit and the
/// cures. `p` is the fibre's key prefix (`fibre.N`).
pub fn check(p: &str, r: ExchangeRatios, density: f64) -> Result<(), String> {
    if r.mass.is_nan() || r.inertia.is_nan() {
        // inf / inf (or 0 / 0): the bead and its profile both overflow, in mass or in moment
        // of inertia, through the radius or the two densities.
        return Err(format!(
            "{p}: a bead and the fluid in its smoothed profile cannot be compared: their \
             masses or moments of inertia overflow; lower {p}.bead_radius (it must fit the \
             fluid's grid), {p}.density or fluid.density"
        ));
    }
    let worst = r.mass.max(r.inertia);
    if worst < MAX_PROFILE_TO_BEAD {
        return Ok(());
    }
    let (what, ratio) = if r.inertia >= r.mass {
        ("moment of inertia", r.inertia)
    } else {
        ("mass", r.mass)
    };
    Err(format!(
        "{p}: the beads are too light for the explicit SPM momentum exchange: the fluid in a \
         bead's smoothed profile (L2020 eq. 25, fluid.xi, fluid.xi_cutoff) has {:.3} times \
         the bead's {what}, at or above the limit {MAX_PROFILE_TO_BEAD} below which the \
         exchange is stable for any flow; raise {p}.density to at least {}, set \
         {p}.bead_inertia = \"profile\" to give the bead the moment of inertia of its profile, \
         or set {p}.exchange = \"implicit\" (stable for any ratio)",
        Num(ratio),
        AtLeast(density * worst / MAX_PROFILE_TO_BEAD * 1.0001)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fibre::bead_mass_inertia;

    /// The numbers quoted in the module docs, for density-1 beads of radius 6.
    #[test]
    fn ratios_of_the_capillary_beads() {
        let wide = SmoothedProfile {
            xi: 2.0,
            cutoff: 5.0,
        };
        for (dims, mass, inertia) in [(2, 1.154, 1.985), (3, 1.461, 2.851)] {
            let (m, i) = bead_mass_inertia(1.0, 6.0, dims == 2);
            let r = ratios(wide, 1.0, 6.0, dims, m, i);
            assert!((r.mass - mass).abs() < 1e-3, "{dims}D {r:?}");
            assert!((r.inertia - inertia).abs() < 1e-3, "{dims}D {r:?}");
        }
        // A radius whose bead and profile overflow is refused with a reason, not a NaN.
        let (m, i) = bead_mass_inertia(1.0, 1e200, false);
        let r = ratios(wide, 1.0, 1e200, 3, m, i);
        let e = check("fibre.0", r, 1.0).unwrap_err();
        assert!(
            e.contains("lower fibre.0.bead_radius") && !e.contains("NaN"),
            "{e}"
        );
    }

    #[test]
    fn refusal_names_the_ratio_the_limit_and_the_cures() {
        let ok = ExchangeRatios {
            mass: 1.2,
            inertia: 1.99,
        };
        assert!(check("fibre.0", ok, 1.0).is_ok());
        let light = ExchangeRatios {
            mass: 1.3,
            inertia: 2.48,
        };
        let e = check("fibre.0", light, 0.8).unwrap_err();
        for s in [
            "2.480",
            "moment of inertia",
            "limit 2",
            "fibre.0.density to at least 0.99",
            "bead_inertia = \"profile\"",
            "exchange = \"implicit\"",
        ] {
            assert!(e.contains(s), "{s:?} missing from: {e}");
        }
    }
}
