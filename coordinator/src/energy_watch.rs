//! Watching a closed fibre system's energy for a blow-up that stays finite.
//!
//! The coordinator ends a run whose diagnostics turn NaN or infinite, but an integration that
//! goes unstable slowly can grow for thousands of steps without overflowing, and would be
//! reported completed. Where nothing feeds the fibres energy (no fluid, no loads: only
//! elasticity, clamps, damping and contact), their mechanical energy, kinetic plus elastic
//! (`kinetic_energy + elastic_energy`, contact included), cannot grow: damping only removes
//! it, and symplectic Euler keeps a modified energy that the reported one follows within a
//! bounded factor. That factor is largest for a mode at the stability limit: for an
//! oscillator at h omega = 1.96, the 2 % margin configure keeps, the reported energy swings
//! by (1 + h omega / 2) / (1 - h omega / 2) = 74. So a growth past [`GROWTH_LIMIT`] = 1000
//! times the energy after the first step is an instability, typically contacts that stiffen
//! the fibres past the beam-stiffness limit checked before step 0 (two fibres meeting with
//! `fibre_contact`, at a time step near that limit, grew to 5e5 times their energy in 20 000
//! steps and were reported completed).

use serde::{Deserialize, Serialize};

/// Growth of the mechanical energy of a closed fibre system past which the run is unstable.
pub const GROWTH_LIMIT: f64 = 1e3;

/// The effects under which the fibres form a closed system: nothing in them does work on the
/// fibres. An effect outside this list (a fluid, loads, or one a new component announces)
/// switches the watch off.
pub const CLOSED_EFFECTS: &[&str] = &[
    cosim::effects::BEAM_ELASTICITY,
    cosim::effects::TWIST,
    cosim::effects::BEAD_ROTATION,
    cosim::effects::CLAMP,
    cosim::effects::DAMPING,
];

/// Whether a run with these effects is a closed fibre system.
pub fn applies(effects: &[String]) -> bool {
    effects.iter().all(|e| CLOSED_EFFECTS.contains(&e.as_str()))
}

/// The fibres' mechanical energy at the first step that reported some.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyWatch {
    /// Kinetic plus elastic energy at `step`; absent until a step reports a positive one (a
    /// fibre at rest and unstrained has none, and keeps none).
    pub reference: Option<f64>,
    /// Step after which `reference` was reported (1-based, as the log's steps).
    pub step: u64,
}

/// A growth past the limit: the energy, at which step, and the reference it grew from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blowup {
    pub energy: f64,
    pub reference: f64,
    pub reference_step: u64,
}

impl Blowup {
    /// The cause, for the instability message.
    pub fn describe(&self) -> String {
        format!(
            "the fibres' energy (kinetic + elastic) grew to {}, {} times its value {} after \
             step {}, with nothing in the scene to feed it (no fluid, no loads); an integration \
             that stays stable keeps it within a factor of 74",
            cosim::scene_keys::Sig(self.energy),
            cosim::scene_keys::Sig(self.energy / self.reference),
            cosim::scene_keys::Sig(self.reference),
            self.reference_step
        )
    }
}

impl EnergyWatch {
    /// Take one step's diagnostics (the fibre node's `kinetic_energy` and `elastic_energy`);
    /// a growth past [`GROWTH_LIMIT`] is returned.
    pub fn observe(&mut self, step: u64, diagnostics: &[(String, f64)]) -> Option<Blowup> {
        let value = |name: &str| diagnostics.iter().find(|(k, _)| k == name).map(|(_, v)| *v);
        let energy = value("kinetic_energy")? + value("elastic_energy")?;
        match self.reference {
            None if energy > 0.0 => {
                self.reference = Some(energy);
                self.step = step;
                None
            }
            Some(reference) if energy > GROWTH_LIMIT * reference => Some(Blowup {
                energy,
                reference,
                reference_step: self.step,
            }),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(kinetic: f64, elastic: f64) -> Vec<(String, f64)> {
        vec![
            ("kinetic_energy".into(), kinetic),
            ("elastic_energy".into(), elastic),
        ]
    }

    #[test]
    fn growth_past_the_limit_is_a_blowup() {
        let mut w = EnergyWatch::default();
        // At rest and unstrained: no reference yet.
        assert_eq!(w.observe(1, &report(0.0, 0.0)), None);
        assert_eq!(w.reference, None);
        assert_eq!(w.observe(2, &report(1.0, 2.0)), None);
        assert_eq!((w.reference, w.step), (Some(3.0), 2));
        // Swings within the limit, however often, are not.
        assert_eq!(w.observe(3, &report(2000.0, 999.0)), None);
        assert_eq!(w.observe(4, &report(1e-9, 0.0)), None);
        let b = w.observe(5, &report(2000.0, 1001.0)).unwrap();
        assert_eq!((b.energy, b.reference, b.reference_step), (3001.0, 3.0, 2));
        assert!(b.describe().contains("1000.333 times"), "{}", b.describe());
        // No energies reported (a fluid-only scene): nothing to watch.
        assert_eq!(EnergyWatch::default().observe(1, &[]), None);
    }

    #[test]
    fn only_closed_systems_are_watched() {
        let e = |names: &[&str]| names.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(applies(&e(&[
            "beam-elasticity",
            "bead-rotation",
            "damping"
        ])));
        assert!(!applies(&e(&["beam-elasticity", "external-loads"])));
        assert!(!applies(&e(&["beam-elasticity", "hydrodynamics", "walls"])));
        assert!(!applies(&e(&["beam-elasticity", "gravity"])));
    }
}
