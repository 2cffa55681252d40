//! Time-step limits of the SPM flow solver, checked before step 0 and during the run.
//!
//! - Viscosity: none. The viscous term is integrated exactly (`exp(-nu k^2 dt)`).
//! - Advective CFL: explicit advection needs `max|u| dt / dx < 1`; configure asks for
//!   [`CFL_MAX`] = 0.5 with the largest speed known before the run (wall speeds, the initial
//!   Couette profile), and a run stops with an error when `max|u| dt` exceeds 1.
//! - Advection with exact viscosity: explicit Euler for advection multiplied by the exact
//!   viscous decay amplifies a Fourier mode by `exp(-nu k^2 dt) (1 + (u k dt)^2)^(1/2)`,
//!   which stays at most 1 for every k when `u^2 dt <= 2 nu`, since `exp(2x) >= 1 + 2x`.
//! - SPM accuracy, not stability: the velocity diffuses `sqrt(nu dt)` into a body between two
//!   penalties, so the error depends on `nu dt / xi^2` (REFERENCE.md section 6, Nakayama &
//!   Yamamoto 2005). It is reported as `fluid.spm_diffusion_number`, not refused.
use crate::config::{FluidConfig, InitialVelocity};
use cosim::scene_keys::Num;

/// Advective CFL number allowed before the run.
pub const CFL_MAX: f64 = 0.5;
/// Advective CFL number at which a running simulation is stopped.
pub const CFL_ABORT: f64 = 1.0;

/// One time-step limit, in the scene's time unit.
#[derive(Debug, Clone, PartialEq)]
pub struct TimeStepLimit {
    pub name: &'static str,
    pub dt_max: f64,
    /// How the limit follows from the scene, with numbers.
    pub detail: String,
}

/// The largest speed known before the run: wall speeds (and with them the initial Couette
/// profile). A flow driven by a body force starts at rest and is watched during the run.
pub fn initial_speed(cfg: &FluidConfig) -> f64 {
    let walls = cfg
        .walls
        .as_ref()
        .map_or(0.0, |w| w.velocity[0].abs().max(w.velocity[1].abs()));
    match cfg.initial_velocity {
        InitialVelocity::Rest | InitialVelocity::Couette => walls,
    }
}

/// The finite time-step limits of a scene.
pub fn limits(cfg: &FluidConfig) -> Vec<TimeStepLimit> {
    let u = initial_speed(cfg);
    let nu = cfg.kinematic_viscosity();
    let mut out = Vec::new();
    if u > 0.0 {
        out.push(TimeStepLimit {
            name: "advective CFL",
            dt_max: CFL_MAX / u,
            detail: format!(
                "max|u| dt / dx <= {CFL_MAX} with max|u| = {} (wall speeds), dx = 1",
                Num(u)
            ),
        });
        out.push(TimeStepLimit {
            name: "advection with exact viscosity (explicit Euler)",
            dt_max: 2.0 * nu / (u * u),
            detail: format!(
                "max|u|^2 dt <= 2 nu with max|u| = {}, nu = eta / rho = {}",
                Num(u),
                Num(nu)
            ),
        });
    }
    out
}

/// Refuse a time step above any limit, naming it with the numbers.
pub fn check(cfg: &FluidConfig) -> Result<Vec<TimeStepLimit>, String> {
    let all = limits(cfg);
    for l in &all {
        if cfg.dt > l.dt_max {
            return Err(format!(
                "time step too large for the fluid ({} limit): time.dt = {} exceeds {} \
                 ({}); lower time.dt or the wall speeds",
                l.name,
                Num(cfg.dt),
                cosim::scene_keys::Sig(l.dt_max),
                l.detail
            ));
        }
    }
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::parse_scene;

    fn scene(dt: f64, nu: f64, u: f64) -> FluidConfig {
        parse_scene(&format!(
            "dimensions = 2\n[time]\ndt = {dt}\n[fluid]\nmethod = \"spm\"\ngrid = [16, 32]\n\
             viscosity = {nu}\n[walls]\nvelocity = [{}, {u}]\n",
            -u
        ))
        .unwrap()
    }

    #[test]
    fn limits_are_named_with_numbers() {
        let ok = check(&scene(1.0, 0.5, 0.1)).unwrap();
        assert_eq!(ok[0].name, "advective CFL");
        assert!((ok[0].dt_max - 5.0).abs() < 1e-12);
        assert!((ok[1].dt_max - 100.0).abs() < 1e-9);
        let e = check(&scene(6.0, 0.5, 0.1)).unwrap_err();
        assert!(
            e.starts_with("time step too large for the fluid (advective CFL limit): time.dt = 6 exceeds 5 (max|u| dt"),
            "{e}"
        );
        let e = check(&scene(1.0, 0.001, 0.1)).unwrap_err();
        assert!(
            e.contains("(advection with exact viscosity (explicit Euler) limit): time.dt = 1 exceeds 0.2 ("),
            "{e}"
        );
        assert!(check(&scene(1e3, 0.5, 0.0)).unwrap().is_empty());
    }
}
