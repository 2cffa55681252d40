//! Watching for beads where no bead should be: inside a wall, inside another bead of its
//! own fibre, or inside a bead of another fibre.
//!
//! Neither paper keeps a bead out of a wall: under SPM a wall is a slab of fluid moved by the
//! penalty, under FPD a bounce-back face that only slows a bead near it, and a fibre tumbling
//! or resting close to a wall can sink into it (docs/validation/spm.md, "A fibre next to a
//! wall"). Nor does either keep two beads of one fibre apart that are not neighbours along
//! it, and a soft fibre that folds or coils can pass through itself (spm.md, "Beads passing
//! through each other"), and neither keeps two fibres apart. The fibre node reports all three
//! every step: `wall_overlap`, how far the deepest bead's sphere reaches past a wall's face,
//! `self_overlap`, how deep two beads of one fibre reach into each other, and
//! `fibre_overlap`, how deep beads of two fibres do (0 while clear). The coordinator keeps the largest value
//! of each over the run and warns in the summary when it exceeds [`WARN_FRACTION`] of the
//! smallest bead radius: the hydrodynamics and elasticity of the scene are then no longer
//! those of solid beads.

/// Overlaps above this fraction of the bead radius are warned about while some fibre has no
/// contact (`fibre.N.wall_contact`, `fibre.N.self_contact`, `fibre.N.fibre_contact`).
pub const WARN_FRACTION: f64 = 0.01;

/// With the contact on every fibre, a bead pressed against a wall overlaps it by the contact
/// spring's compression: a thousandth of the radius on the SPM built-in example, 0.6 % of it
/// under FPD (docs/validation/spm.md). Only a tenth of the radius is warned about.
pub const WARN_FRACTION_WITH_CONTACT: f64 = 0.1;

/// What an [`OverlapWatch`] watches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Overlap {
    /// Beads past a wall's face (`wall_overlap`; the contact `fibre.N.wall_contact`).
    Wall,
    /// Beads of one fibre inside each other (`self_overlap`; the contact `fibre.N.self_contact`).
    SelfOverlap,
    /// Beads of two fibres inside each other (`fibre_overlap`; the contact
    /// `fibre.N.fibre_contact`).
    FibreOverlap,
}

impl Overlap {
    /// The fibre node's diagnostic.
    pub fn diagnostic(self) -> &'static str {
        match self {
            Self::Wall => "wall_overlap",
            Self::SelfOverlap => "self_overlap",
            Self::FibreOverlap => "fibre_overlap",
        }
    }

    /// The fibre key that turns the contact on.
    pub fn contact_key(self) -> &'static str {
        match self {
            Self::Wall => "wall_contact",
            Self::SelfOverlap => "self_contact",
            Self::FibreOverlap => "fibre_contact",
        }
    }
}

/// The largest overlap seen, and at which step (the step whose report gave it).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OverlapWatch {
    /// Largest overlap so far (grid spacings); 0 while every bead has stayed clear.
    pub largest: f64,
    /// Step after which it was reported (1-based, as the log's steps).
    pub step: u64,
}

/// The watches of a run, as a checkpoint keeps them (each absent in checkpoints written
/// before it existed: then from the resume on): the three overlaps, and the energy of a
/// closed fibre system ([`crate::energy_watch`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunWatches {
    #[serde(default)]
    pub wall_watch: OverlapWatch,
    #[serde(default)]
    pub self_watch: OverlapWatch,
    #[serde(default)]
    pub fibre_watch: OverlapWatch,
    #[serde(default)]
    pub energy_watch: crate::energy_watch::EnergyWatch,
}

impl RunWatches {
    /// Take one step's diagnostics into every overlap watch.
    pub fn observe(&mut self, step: u64, diagnostics: &[(String, f64)]) {
        self.wall_watch.observe(step, Overlap::Wall, diagnostics);
        self.self_watch
            .observe(step, Overlap::SelfOverlap, diagnostics);
        self.fibre_watch
            .observe(step, Overlap::FibreOverlap, diagnostics);
    }
}

impl OverlapWatch {
    /// Take one step's diagnostics (the fibre node's `what.diagnostic()`, if it reports one).
    pub fn observe(&mut self, step: u64, what: Overlap, diagnostics: &[(String, f64)]) {
        let name = what.diagnostic();
        if let Some((_, v)) = diagnostics.iter().find(|(k, _)| k == name) {
            if *v > self.largest {
                self.largest = *v;
                self.step = step;
            }
        }
    }

    /// The warning for the summary, if the overlap went past [`WARN_FRACTION`] of
    /// `bead_radius` ([`WARN_FRACTION_WITH_CONTACT`] if every fibre has the contact).
    /// `without_contact` lists the fibres that have no contact of this kind.
    pub fn warning(
        &self,
        what: Overlap,
        bead_radius: f64,
        without_contact: &[usize],
    ) -> Option<String> {
        let fraction = if without_contact.is_empty() {
            WARN_FRACTION_WITH_CONTACT
        } else {
            WARN_FRACTION
        };
        if !(self.largest > fraction * bead_radius) {
            return None;
        }
        let share = 100.0 * self.largest / bead_radius;
        let (largest, step) = (self.largest, self.step);
        let mut w = match what {
            Overlap::Wall => format!(
                "a bead reached {largest:.4} grid spacings ({share:.1} % of its radius \
                 {bead_radius}) past a wall's face (largest wall_overlap, at step {step})"
            ),
            Overlap::SelfOverlap => format!(
                "two beads of one fibre reached {largest:.4} grid spacings ({share:.1} % of \
                 the radius {bead_radius}) into each other (largest self_overlap, at step \
                 {step})"
            ),
            Overlap::FibreOverlap => format!(
                "beads of two fibres reached {largest:.4} grid spacings ({share:.1} % of the \
                 radius {bead_radius}) into each other (largest fibre_overlap, at step {step})"
            ),
        };
        if without_contact.is_empty() {
            w.push_str(&format!(
                "; the {} holds the beads too softly for the load on them (its spring is the \
                 fibre's axial bond stiffness)",
                match what {
                    Overlap::Wall => "wall contact",
                    Overlap::SelfOverlap => "self contact",
                    Overlap::FibreOverlap => "contact between fibres",
                }
            ));
        } else {
            let keys: Vec<String> = without_contact
                .iter()
                .map(|n| format!("fibre.{n}.{} = true", what.contact_key()))
                .collect();
            let (kept, doc) = match what {
                Overlap::Wall => ("beads out of the walls", "A fibre next to a wall"),
                Overlap::SelfOverlap => (
                    "the beads of a fibre apart",
                    "Beads passing through each other",
                ),
                Overlap::FibreOverlap => ("two fibres apart", "Fibres passing through each other"),
            };
            w.push_str(&format!(
                "; nothing keeps {kept} unless {} (docs/validation/spm.md, \"{doc}\")",
                keys.join(", ")
            ));
        }
        Some(w)
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    fn report(wall: f64, beads: f64) -> Vec<(String, f64)> {
        vec![
            ("kinetic_energy".into(), 1.0),
            ("wall_overlap".into(), wall),
            ("self_overlap".into(), beads),
            ("fibre_overlap".into(), 2.0 * beads),
        ]
    }

    #[test]
    fn keeps_the_largest_overlap_and_its_step() {
        let mut w = RunWatches::default();
        for (step, v) in [(1, 0.0), (2, 0.3), (3, 0.7), (4, 0.2)] {
            w.observe(step, &report(v, 0.1 * step as f64));
        }
        assert_eq!(
            w.wall_watch,
            OverlapWatch {
                largest: 0.7,
                step: 3
            }
        );
        assert_eq!((w.self_watch.largest, w.self_watch.step), (0.4, 4));
        assert_eq!((w.fibre_watch.largest, w.fibre_watch.step), (0.8, 4));
        // A report without the diagnostics (no fibre node) changes nothing.
        w.observe(5, &[("kinetic_energy".into(), 9.0)]);
        assert_eq!(
            (w.wall_watch.step, w.self_watch.step, w.fibre_watch.step),
            (3, 4, 4)
        );
    }

    #[test]
    fn warns_past_a_hundredth_of_the_radius_or_a_tenth_with_contact() {
        for what in [Overlap::Wall, Overlap::SelfOverlap, Overlap::FibreOverlap] {
            let key = what.contact_key();
            // `report` gives fibre_overlap twice self_overlap.
            let v = |x: f64| {
                if what == Overlap::FibreOverlap {
                    0.5 * x
                } else {
                    x
                }
            };
            let mut w = OverlapWatch::default();
            w.observe(10, what, &report(0.039, v(0.039)));
            assert_eq!(w.warning(what, 4.0, &[0]), None);
            w.observe(11, what, &report(0.76, v(0.76)));
            let msg = w.warning(what, 4.0, &[0, 2]).unwrap();
            assert!(msg.contains("0.7600") && msg.contains("19.0 %") && msg.contains("step 11"));
            assert!(msg.contains(&format!("fibre.0.{key} = true, fibre.2.{key} = true")));
            assert!(msg.contains(what.diagnostic()), "{msg}");
            let held = w.warning(what, 4.0, &[]).unwrap();
            assert!(held.contains("too softly") && !held.contains(" = true"));
            // Every fibre held by the contact: only past a tenth of the radius.
            let mut w = OverlapWatch::default();
            w.observe(1, what, &report(0.39, v(0.39)));
            assert_eq!(w.warning(what, 4.0, &[]), None);
            assert!(w.warning(what, 4.0, &[0]).is_some());
            // Clear all along: no warning whatever the radius.
            assert_eq!(OverlapWatch::default().warning(what, 1e-9, &[0]), None);
        }
        // Each watch reads its own diagnostic.
        let mut w = RunWatches::default();
        w.observe(7, &report(0.0, 2.5));
        assert_eq!(w.wall_watch, OverlapWatch::default());
        assert!(w
            .self_watch
            .warning(Overlap::SelfOverlap, 4.0, &[1])
            .unwrap()
            .contains("into each other"));
    }
}
