//! Parameters, errors and closed-form relations of the phase field.
use std::f64::consts::SQRT_2;

/// A fluid constituent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fluid {
    /// ψ = +1.
    A,
    /// ψ = -1.
    B,
}

impl Fluid {
    /// Bulk value of the order parameter.
    pub fn psi(self) -> f64 {
        match self {
            Fluid::A => 1.0,
            Fluid::B => -1.0,
        }
    }
}

/// Time discretisation of the diffusive (Cahn–Hilliard) part.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// `ξ² ∇⁴` implicit with linear stabilisation S (the production scheme).
    SemiImplicit,
    /// Everything explicit (forward Euler), S unused: for comparison only; its time step is
    /// limited by `ξ² k⁴` at the grid scale.
    Explicit,
}

/// Parameters of the phase field. Lengths in grid units (spacing 1), time in the scene's
/// unit.
#[derive(Debug, Clone, PartialEq)]
pub struct CahnHilliardConfig {
    /// Interfacial length ξ (L2020 eqs. 25, 28), grid units. Default 2.
    pub xi: f64,
    /// Energy density scale `e0 = kB T0 / v0` (eq. 27): μ, F per volume and the capillary
    /// force density carry it. Default 1.
    pub e0: f64,
    /// Mobility M (eq. 32), length² / (e0 · time); the diffusivity is `D0 = e0 M` (eq. 41,
    /// see [`mobility_from_peclet`]). Default 1.
    pub mobility: f64,
    /// Time step. Default 1.
    pub dt: f64,
    /// Linear stabilisation S (dimensionless, in units of e0). The semi-implicit step is
    /// stable for every Δt when `S >= max g'/2` ([`super::limits::min_stabilisation`]: 2.815 for
    /// |ψ| <= 1.1 and φ <= 1). Default 3.
    pub stabilisation: f64,
    /// Default [`Scheme::SemiImplicit`].
    pub scheme: Scheme,
}

impl Default for CahnHilliardConfig {
    fn default() -> Self {
        Self {
            xi: 2.0,
            e0: 1.0,
            mobility: 1.0,
            dt: 1.0,
            stabilisation: 3.0,
            scheme: Scheme::SemiImplicit,
        }
    }
}

impl CahnHilliardConfig {
    /// `D0 = e0 M` (L2020 eq. 41), length² / time.
    pub fn diffusivity(&self) -> f64 {
        self.e0 * self.mobility
    }

    pub(super) fn validate(&self) -> Result<(), CahnHilliardError> {
        let positive = |name, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(CahnHilliardError::InvalidParameter {
                    name,
                    value,
                    reason: "must be finite and positive",
                })
            }
        };
        positive("xi", self.xi)?;
        positive("e0", self.e0)?;
        positive("mobility", self.mobility)?;
        positive("dt", self.dt)?;
        if !(self.stabilisation.is_finite() && self.stabilisation >= 0.0) {
            return Err(CahnHilliardError::InvalidParameter {
                name: "stabilisation",
                value: self.stabilisation,
                reason: "must be finite and non-negative",
            });
        }
        Ok(())
    }
}

/// What can go wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CahnHilliardError {
    #[error("cahn-hilliard: {name} = {value} is invalid: {reason}")]
    InvalidParameter {
        name: &'static str,
        value: f64,
        reason: &'static str,
    },
    #[error("cahn-hilliard: a {dims}D grid of {sizes:?} nodes is invalid: {reason}")]
    InvalidGrid {
        dims: usize,
        sizes: [usize; 3],
        reason: &'static str,
    },
    #[error("cahn-hilliard: {name} has {got} values where the grid has {expected}")]
    FieldLength {
        name: &'static str,
        expected: usize,
        got: usize,
    },
    #[error(
        "cahn-hilliard: time step too large ({name} limit): dt = {} exceeds {} ({detail})",
        cosim::scene_keys::Num(*.dt),
        cosim::scene_keys::Sig(*.dt_max)
    )]
    TimeStep {
        name: &'static str,
        dt: f64,
        dt_max: f64,
        detail: String,
    },
    #[error(
        "cahn-hilliard: the order parameter diverged at step {step} (max |psi| = {}); \
         the time step is above a stability limit",
        cosim::scene_keys::Sig(*.max_abs)
    )]
    Diverged { step: u64, max_abs: f64 },
    #[error(
        "cahn-hilliard: relaxation did not converge in {iterations} iterations \
         (max |mu| / e0 = {} > {})",
        cosim::scene_keys::Sig(*.residual),
        cosim::scene_keys::Sig(*.tolerance)
    )]
    NotConverged {
        iterations: usize,
        residual: f64,
        tolerance: f64,
    },
}

/// ψ* from the bead affinity ψ0, the minimum of the bulk energy inside a solid (L2020 eq. 31).
pub fn psi_star(psi0: f64) -> f64 {
    (2.0 * psi0 + psi0 * psi0 * psi0) / 3.0
}

/// The analytic A/B surface tension `σ_AB = (2 √2 / 3) e0 ξ` (excess of the flat profile
/// `tanh(x / (√2 ξ))`; L2020 section 3.3 with ξ = L0).
pub fn sigma_ab(e0: f64, xi: f64) -> f64 {
    2.0 * SQRT_2 / 3.0 * e0 * xi
}

/// Mobility from the Péclet number (L2020 eq. 41): `Pe = U0 L0 / D0`, `D0 = e0 M`, so
/// `M = U0 L0 / (Pe e0)`.
pub fn mobility_from_peclet(
    peclet: f64,
    u0: f64,
    l0: f64,
    e0: f64,
) -> Result<f64, CahnHilliardError> {
    for (name, value) in [("peclet", peclet), ("u0", u0), ("l0", l0), ("e0", e0)] {
        if !(value.is_finite() && value > 0.0) {
            return Err(CahnHilliardError::InvalidParameter {
                name,
                value,
                reason: "must be finite and positive",
            });
        }
    }
    Ok(u0 * l0 / (peclet * e0))
}
