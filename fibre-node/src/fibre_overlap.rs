//! How deep the beads of two different fibres reach into each other: the `fibre_overlap`
//! diagnostic.
//!
//! Neither paper keeps two fibres apart: both simulate one fibre at a time. A scene with
//! several fibres (`[[fibre]]` tables) lets them pass through each other unless
//! `fibre.N.fibre_contact` is on ([`crate::fibre_contact`]). The fibre node reports the
//! deepest overlap `r_a + r_b - |X_i - X_j|` over pairs of beads of different fibres every
//! step (0 while clear or with a single fibre, grid spacings), separations taken as minimum
//! images across the fluid's periodic box ([`crate::bead_pairs`]); the coordinator keeps its
//! largest value and warns (`coordinator/src/overlap_watch.rs`).
//!
//! Cost, as for [`crate::self_overlap`]: a full check visits the pairs through a cell list
//! with a skin of the largest bead diameter, and records the scene's clearance (the smallest
//! gap over the pairs, at most the skin). While twice the largest displacement of a bead
//! since that check stays below it, no pair can touch and nothing is checked. The value
//! depends on the positions alone: only a provably clear scene is skipped, and it reports 0.
//! Fibres in contact are checked every step; the pairs come from a Verlet list
//! ([`crate::near_pairs`]) rebuilt once a bead has moved half a bead radius, so a check
//! while the fibres touch costs the pairs near each bead, not a pass through the cells.
#[cfg(test)]
use crate::bead_pairs::BeadPairs;
use crate::near_pairs::NearPairs;
use crate::quaternion::Vec3;

/// The watch over the beads of all fibres of a scene.
#[derive(Debug, Clone)]
pub struct FibreOverlap {
    /// Each bead's fibre and radius, fibres in order.
    fibre_of: Vec<u32>,
    radius: Vec<f64>,
    /// Skin of the cell list: pairs up to `2 r_max + skin` apart are visited (length).
    skin: f64,
    pairs: NearPairs,
    /// All bead positions, gathered for a check.
    pos: Vec<Vec3>,
    /// Positions at the last full check.
    reference: Vec<Vec3>,
    /// Clearance at the last full check (NaN before the first, negative while overlapping).
    margin: f64,
}

impl FibreOverlap {
    /// The watch over fibres of `(beads, bead radius)`, in a box wrapping with the lengths
    /// `period` along its periodic axes, in `dims` dimensions. `None` with fewer than two
    /// fibres: there is nothing to watch.
    pub fn new(fibres: &[(usize, f64)], period: [Option<f64>; 3], dims: usize) -> Option<Self> {
        if fibres.len() < 2 {
            return None;
        }
        let (mut fibre_of, mut radius) = (Vec::new(), Vec::new());
        for (n, &(beads, r)) in fibres.iter().enumerate() {
            fibre_of.extend(std::iter::repeat_n(n as u32, beads));
            radius.extend(std::iter::repeat_n(r, beads));
        }
        let beads = radius.len();
        let diameter = 2.0 * radius.iter().cloned().fold(0.0, f64::max);
        Some(Self {
            fibre_of,
            radius,
            skin: diameter,
            pairs: NearPairs::new(beads, 2.0 * diameter, 0.25 * diameter, period, dims),
            pos: Vec::with_capacity(beads),
            reference: vec![Vec3::zeros(); beads],
            margin: f64::NAN,
        })
    }

    /// The deepest overlap of two beads of different fibres at the positions `fibres` gives,
    /// one slice per fibre in order (length; 0 while all are clear).
    pub fn measure<'a>(&mut self, fibres: impl IntoIterator<Item = &'a [Vec3]>) -> f64 {
        self.pos.clear();
        for p in fibres {
            self.pos.extend_from_slice(p);
        }
        debug_assert_eq!(self.pos.len(), self.reference.len());
        if self.margin > 0.0 {
            let mut moved2: f64 = 0.0;
            for (p, r) in self.pos.iter().zip(&self.reference) {
                moved2 = moved2.max((p - r).norm_squared());
            }
            // Each pair's distance changed by at most twice the largest displacement; the
            // tolerance covers the rounding of the distances the margin came from.
            if 2.0 * moved2.sqrt() < self.margin - 1e-9 * self.skin {
                return 0.0;
            }
        }
        let mut least = self.skin;
        let (fibre_of, radius) = (&self.fibre_of, &self.radius);
        self.pairs.for_each_pair(
            &self.pos,
            |i, j| fibre_of[i] != fibre_of[j],
            |i, j, d| least = least.min(d.norm() - radius[i] - radius[j]),
        );
        self.reference.copy_from_slice(&self.pos);
        self.margin = least;
        (-least).max(0.0)
    }
}

/// Fibres without a fluid (no `[fluid]`: no fluid node checks their start) that start
/// exactly on top of each other, every bead of one where the other's is (a second
/// `[[fibre]]` left at the default `start`): the error names the pair. Fibres that merely
/// overlap pass (a suspension may start so, for `fibre.N.fibre_contact` to push apart; the
/// `fibre_overlap` watch reports it). `fibres`: each fibre's bead positions and radius.
pub fn check_coincident(fibres: &[(&[Vec3], f64)]) -> Result<(), String> {
    let same = |a: &[Vec3], b: &[Vec3], r: f64| {
        a.len() == b.len() && a.iter().zip(b).all(|(p, q)| (p - q).norm() <= 1e-9 * r)
    };
    for (g, (b, rb)) in fibres.iter().enumerate() {
        for (f, (a, ra)) in fibres[..g].iter().enumerate() {
            if same(a, b, ra.max(*rb)) {
                return Err(format!(
                    "fibre {g} starts exactly on fibre {f} (every one of its {} beads where \
                     fibre {f}'s is); give each fibre its own fibre.N.start",
                    b.len()
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fibres without a fluid: two at one start are refused, naming the pair; fibres that
    /// only overlap, or a single fibre, pass.
    #[test]
    fn fibres_at_one_start_are_refused() {
        let line =
            |y: f64| -> Vec<Vec3> { (0..5).map(|k| Vec3::new(2.0 * k as f64, y, 0.0)).collect() };
        let (a, b, c) = (line(0.0), line(1.0), line(0.0));
        assert_eq!(check_coincident(&[(&a, 1.0), (&b, 1.0)]), Ok(()));
        let e = check_coincident(&[(&a, 1.0), (&b, 1.0), (&c, 1.0)]).unwrap_err();
        assert!(e.starts_with("fibre 2 starts exactly on fibre 0"), "{e}");
        assert!(e.contains("fibre.N.start"), "{e}");
        assert_eq!(check_coincident(&[(&a, 1.0)]), Ok(()));
    }

    /// The definition over all pairs of beads of different fibres, minimum images.
    fn deepest(fibres: &[Vec<Vec3>], radii: &[f64], period: [Option<f64>; 3]) -> f64 {
        let image = BeadPairs::new(0, 1.0, period, 3);
        let mut deepest: f64 = 0.0;
        for a in 0..fibres.len() {
            for b in a + 1..fibres.len() {
                for p in &fibres[a] {
                    for q in &fibres[b] {
                        let gap = image.separation(p, q).norm() - radii[a] - radii[b];
                        deepest = deepest.max(-gap);
                    }
                }
            }
        }
        deepest
    }

    /// Three straight fibres of touching beads, along x, y and z, sliding past and through
    /// each other in a box periodic in x and z: every step the watch reports the
    /// definition's value to the bit, whether it checked or skipped.
    #[test]
    fn reports_the_deepest_overlap_between_fibres_step_by_step() {
        let radii = [2.0, 1.0, 1.5];
        let beads = [12usize, 20, 9];
        let period = [Some(60.0), None, Some(50.0)];
        let specs: Vec<(usize, f64)> = beads.iter().zip(radii).map(|(&n, r)| (n, r)).collect();
        let mut watch = FibreOverlap::new(&specs, period, 3).unwrap();
        let (mut overlapping, mut clear) = (0, 0);
        for step in 0..600 {
            let t = step as f64;
            let along = |f: usize, k: usize| 2.0 * radii[f] * k as f64;
            let fibres: Vec<Vec<Vec3>> = vec![
                (0..beads[0])
                    .map(|k| Vec3::new(0.2 * t + along(0, k), 0.0, 0.0))
                    .collect(),
                (0..beads[1])
                    .map(|k| Vec3::new(30.0 + 0.1 * t, along(1, k) - 20.0, 6.0 * (0.03 * t).sin()))
                    .collect(),
                (0..beads[2])
                    .map(|k| {
                        Vec3::new(
                            10.0 - 0.15 * t,
                            5.0 + 4.0 * (0.05 * t).sin(),
                            along(2, k) - 12.0,
                        )
                    })
                    .collect(),
            ];
            let want = deepest(&fibres, &radii, period);
            let got = watch.measure(fibres.iter().map(|f| &f[..]));
            assert_eq!(
                got.to_bits(),
                want.to_bits(),
                "step {step}: {got} vs {want}"
            );
            if want > 0.0 {
                overlapping += 1;
            } else {
                clear += 1;
            }
        }
        assert!(overlapping > 50 && clear > 50, "{overlapping} {clear}");
    }

    #[test]
    fn one_fibre_has_nothing_to_watch_and_a_fibre_never_overlaps_itself() {
        assert!(FibreOverlap::new(&[(10, 1.0)], [None; 3], 2).is_none());
        // Two fibres far apart, each folded onto itself: no overlap between fibres.
        let folded: Vec<Vec3> = (0..6)
            .map(|k| Vec3::new(0.5 * k as f64, 0.0, 0.0))
            .collect();
        let far: Vec<Vec3> = folded
            .iter()
            .map(|p| p + Vec3::new(0.0, 20.0, 0.0))
            .collect();
        let mut w = FibreOverlap::new(&[(6, 1.0), (6, 1.0)], [Some(40.0), None, None], 2).unwrap();
        assert_eq!(w.measure([&folded[..], &far[..]]), 0.0);
        // Across the periodic seam in x: 39.5 and 0.5 are one spacing apart.
        let left = [Vec3::new(0.5, 5.0, 0.0)];
        let right = [Vec3::new(39.5, 5.5, 0.0)];
        let mut w = FibreOverlap::new(&[(1, 1.0), (1, 1.0)], [Some(40.0), None, None], 2).unwrap();
        let want = 2.0 - (1.0f64 + 0.25).sqrt();
        assert!((w.measure([&left[..], &right[..]]) - want).abs() < 1e-12);
    }
}
