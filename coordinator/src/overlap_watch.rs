//! Watching for beads that reach into a wall.
//!
//! Neither paper keeps a bead out of a wall: under SPM a wall is a slab of fluid moved by the
//! penalty, under FPD a bounce-back face that only slows a bead near it, and a fibre tumbling
//! or resting close to a wall can sink into it (docs/validation/spm.md, "A fibre next to a
//! wall"). The fibre node reports `wall_overlap` every step: how far the deepest bead's sphere
//! reaches past a wall's face (0 while clear). The coordinator keeps its largest value over
//! the run and warns in the summary when it exceeds [`WARN_FRACTION`] of the smallest bead
//! radius, since the hydrodynamics of a bead inside a wall is then no longer the scene's.

/// Overlaps above this fraction of the bead radius are warned about while some fibre has no
/// wall contact.
pub const WARN_FRACTION: f64 = 0.01;

/// With `fibre.N.wall_contact = true` on every fibre, a bead resting on a wall overlaps it by
/// the contact spring's compression: a thousandth of the radius on the SPM built-in example,
/// 0.6 % of it under FPD (docs/validation/spm.md). Only a tenth of the radius is warned about.
pub const WARN_FRACTION_WITH_CONTACT: f64 = 0.1;

/// The largest `wall_overlap` seen, and at which step (the step whose report gave it).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallWatch {
    /// Largest overlap so far (grid spacings); 0 while every bead has stayed clear.
    pub largest: f64,
    /// Step after which it was reported (1-based, as the log's steps).
    pub step: u64,
}

impl WallWatch {
    /// Take one step's diagnostics (the fibre node's `wall_overlap`, if it reports one).
    pub fn observe(&mut self, step: u64, diagnostics: &[(String, f64)]) {
        if let Some((_, v)) = diagnostics.iter().find(|(k, _)| k == "wall_overlap") {
            if *v > self.largest {
                self.largest = *v;
                self.step = step;
            }
        }
    }

    /// The warning for the summary, if the overlap went past [`WARN_FRACTION`] of
    /// `bead_radius` ([`WARN_FRACTION_WITH_CONTACT`] if every fibre has the contact).
    /// `without_contact` lists the fibres that have no `wall_contact`.
    pub fn warning(&self, bead_radius: f64, without_contact: &[usize]) -> Option<String> {
        let fraction = if without_contact.is_empty() {
            WARN_FRACTION_WITH_CONTACT
        } else {
            WARN_FRACTION
        };
        if !(self.largest > fraction * bead_radius) {
            return None;
        }
        let mut w = format!(
            "a bead reached {:.4} grid spacings ({:.1} % of its radius {bead_radius}) past a \
             wall's face (largest wall_overlap, at step {})",
            self.largest,
            100.0 * self.largest / bead_radius,
            self.step
        );
        if without_contact.is_empty() {
            w.push_str(
                "; the wall contact holds the beads too softly for the load on them \
                 (its spring is the fibre's axial bond stiffness)",
            );
        } else {
            let keys: Vec<String> = without_contact
                .iter()
                .map(|n| format!("fibre.{n}.wall_contact = true"))
                .collect();
            w.push_str(&format!(
                "; nothing keeps beads out of the walls unless {} (docs/validation/spm.md, \
                 \"A fibre next to a wall\")",
                keys.join(", ")
            ));
        }
        Some(w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(v: f64) -> Vec<(String, f64)> {
        vec![("kinetic_energy".into(), 1.0), ("wall_overlap".into(), v)]
    }

    #[test]
    fn keeps_the_largest_overlap_and_its_step() {
        let mut w = WallWatch::default();
        for (step, v) in [(1, 0.0), (2, 0.3), (3, 0.7), (4, 0.2)] {
            w.observe(step, &report(v));
        }
        assert_eq!(
            w,
            WallWatch {
                largest: 0.7,
                step: 3
            }
        );
        // A report without the diagnostic (no fibre node) changes nothing.
        w.observe(5, &[("kinetic_energy".into(), 9.0)]);
        assert_eq!(w.step, 3);
    }

    #[test]
    fn warns_past_a_hundredth_of_the_radius_or_a_tenth_with_contact() {
        let mut w = WallWatch::default();
        w.observe(10, &report(0.039));
        assert_eq!(w.warning(4.0, &[0]), None);
        w.observe(11, &report(0.76));
        let msg = w.warning(4.0, &[0, 2]).unwrap();
        assert!(msg.contains("0.7600") && msg.contains("19.0 %") && msg.contains("step 11"));
        assert!(msg.contains("fibre.0.wall_contact = true, fibre.2.wall_contact = true"));
        let held = w.warning(4.0, &[]).unwrap();
        assert!(held.contains("too softly") && !held.contains("wall_contact = true"));
        // Every fibre held by the contact: only past a tenth of the radius.
        let mut w = WallWatch::default();
        w.observe(1, &report(0.39));
        assert_eq!(w.warning(4.0, &[]), None);
        assert!(w.warning(4.0, &[0]).is_some());
        // Clear all along: no warning whatever the radius.
        assert_eq!(WallWatch::default().warning(1e-9, &[0]), None);
    }
}
