//! How deep the beads of one fibre reach into each other: the `self_overlap` diagnostic.
//!
//! Neither paper keeps two beads that are not neighbours along the chain apart (L2020's
//! cohesive beam and S2023's bead-spring fibre both let them pass through each other), and
//! `fibre.N.self_contact` is off by default. A soft fibre that folds hard or coils can then
//! bring its beads into one another, after which its elastic energy and (under SPM, where
//! overlapping profiles are normalised) its hydrodynamics are no longer those of a solid
//! fibre. The fibre node reports the deepest overlap `2 r_b - |X_i - X_j|` every step (0 while
//! clear, grid spacings), and the coordinator keeps its largest value and warns
//! (`coordinator/src/overlap_watch.rs`).
//!
//! Pairs counted: beads `i < j` of one fibre with `j - i >= 2` whose distance along the
//! straight rest shape, `(j - i) l0`, is at least the diameter. Pairs that overlap at rest
//! (a spacing `l0` below the radius) are left out: their overlap is the fibre's design.
//!
//! Cost. A full check visits the pairs within `2 r_b + skin` (skin `2 r_b`) of each other from
//! a Verlet list ([`crate::near_pairs`], rebuilt from a cell list once a bead has moved an
//! eighth of a diameter), O(N); fibres of at most [`ALL_PAIRS_UP_TO`] beads visit every
//! pair. After a full check the fibre's clearance (the smallest gap `|X_i - X_j| - 2 r_b`
//! over the pairs counted; at most the skin for the cell list, which does not see pairs
//! further apart) bounds how far beads must move before any pair can touch: while twice the
//! largest displacement of a bead since that check stays below it, every pair is still
//! clear and nothing is checked. So a straight or gently bent fibre is checked once in many
//! steps, a folded one every step. The value is a function of the positions alone (only a
//! provably clear fibre is skipped, and it reports 0), whatever the history of checks: a
//! resumed run reports the same bits as one never stopped.
use crate::near_pairs::NearPairs;
use crate::quaternion::Vec3;

/// Fibres with at most this many beads visit all pairs in a full check.
pub const ALL_PAIRS_UP_TO: usize = 32;

/// The watch over one fibre: its geometry, the last full check and the pair list (allocated
/// in [`SelfOverlap::new`]; [`SelfOverlap::measure`] allocates only when the list outgrows
/// its buffer).
#[derive(Debug, Clone)]
pub struct SelfOverlap {
    /// Centre distance below which two beads overlap, `2 r_b` (length).
    diameter: f64,
    /// Smallest index difference of a pair counted.
    min_gap: usize,
    /// Cell size of the cell list, `diameter + skin` (length).
    cell: f64,
    /// Positions at the last full check.
    reference: Vec<Vec3>,
    /// Clearance at the last full check (length; NaN before the first, negative while
    /// overlapping).
    margin: f64,
    /// The pairs within a cell of each other (None: all pairs are visited).
    pairs: Option<NearPairs>,
}

impl SelfOverlap {
    /// The watch over a fibre of `beads` beads of radius `bead_radius` spaced `spacing` apart
    /// at rest, in `dims` (2 or 3) dimensions.
    pub fn new(beads: usize, bead_radius: f64, spacing: f64, dims: usize) -> Self {
        let diameter = 2.0 * bead_radius;
        // Smallest gap g >= 2 with g * spacing >= diameter (a tiny tolerance so that a spacing
        // of exactly r_b still counts second neighbours).
        let at_rest = (diameter / spacing * (1.0 - 1e-12)).ceil();
        let min_gap = if at_rest.is_finite() {
            (at_rest as usize).max(2)
        } else {
            usize::MAX
        };
        Self {
            diameter,
            min_gap,
            // A wider skin means fewer full checks of a fibre on the move, each visiting
            // more pairs: in the fibre_step bench (a 1000-bead fibre bending fast) the
            // diagnostic costs 8.7 us a step with a skin of 2 r_b, 13.5 us with r_b.
            cell: 2.0 * diameter,
            reference: vec![Vec3::zeros(); beads],
            margin: f64::NAN,
            pairs: (beads > ALL_PAIRS_UP_TO)
                .then(|| NearPairs::new(beads, 2.0 * diameter, 0.25 * diameter, [None; 3], dims)),
        }
    }

    /// The deepest overlap of two counted beads at `pos` (length; 0 while all are clear).
    pub fn measure(&mut self, pos: &[Vec3]) -> f64 {
        debug_assert_eq!(pos.len(), self.reference.len());
        if self.margin > 0.0 {
            let mut moved2: f64 = 0.0;
            for (p, r) in pos.iter().zip(&self.reference) {
                moved2 = moved2.max((p - r).norm_squared());
            }
            // Each pair's distance changed by at most twice the largest displacement; the
            // tolerance covers the rounding of the distances the margin came from.
            if 2.0 * moved2.sqrt() < self.margin - 1e-9 * self.cell {
                return 0.0;
            }
        }
        let clearance = if self.pairs.is_none() {
            self.all_pairs(pos)
        } else {
            self.near_pairs(pos)
        };
        self.reference.copy_from_slice(pos);
        self.margin = clearance;
        (-clearance).max(0.0)
    }

    /// Smallest `|X_i - X_j| - diameter` over all counted pairs (+inf without any).
    fn all_pairs(&self, pos: &[Vec3]) -> f64 {
        let mut least = f64::INFINITY;
        for i in 0..pos.len() {
            for j in i.saturating_add(self.min_gap)..pos.len() {
                least = least.min((pos[i] - pos[j]).norm() - self.diameter);
            }
        }
        least
    }

    /// As [`Self::all_pairs`] over the pairs within a cell of each other; pairs further
    /// apart are at least a cell apart, so the result is capped at the skin.
    fn near_pairs(&mut self, pos: &[Vec3]) -> f64 {
        let (diameter, min_gap) = (self.diameter, self.min_gap);
        let mut least = self.cell - diameter;
        if let Some(pairs) = &mut self.pairs {
            pairs.for_each_pair(
                pos,
                |i, j| j >= i.saturating_add(min_gap),
                |_, _, d| least = least.min(d.norm() - diameter),
            );
        }
        least
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xorshift::Xorshift;

    /// A chain of touching beads (spacing = diameter) whose bond directions wander, kept in
    /// a box of `side` by reflection: a random walk that crosses itself in a small box.
    fn coil(beads: usize, radius: f64, side: f64, planar: bool, seed: &mut Xorshift) -> Vec<Vec3> {
        let mut pos = vec![Vec3::new(
            0.5 * side,
            0.5 * side,
            if planar { 0.5 } else { 0.5 * side },
        )];
        let mut dir = Vec3::new(1.0, 0.0, 0.0);
        for _ in 1..beads {
            let mut kick = Vec3::new(seed.uniform() - 0.5, seed.uniform() - 0.5, 0.0);
            if !planar {
                kick.z = seed.uniform() - 0.5;
            }
            dir = (dir + kick).normalize();
            let mut next = *pos.last().unwrap() + dir * (2.0 * radius);
            for a in 0..if planar { 2 } else { 3 } {
                if next[a] < 0.0 || next[a] > side {
                    dir[a] = -dir[a];
                    next[a] = pos.last().unwrap()[a] + dir[a] * (2.0 * radius);
                }
            }
            pos.push(next);
        }
        pos
    }

    /// The plain definition: the smallest `d - 2 r_b` over the pairs counted (`cap` at most).
    fn clearance_by_definition(pos: &[Vec3], radius: f64, min_gap: usize, cap: f64) -> f64 {
        let mut least = cap;
        for i in 0..pos.len() {
            for j in i + min_gap..pos.len() {
                least = least.min((pos[i] - pos[j]).norm() - 2.0 * radius);
            }
        }
        least
    }

    #[test]
    fn a_straight_fibre_is_clear_and_a_fold_is_measured() {
        let r = 1.5;
        let straight: Vec<Vec3> = (0..10)
            .map(|k| Vec3::new(2.0 * r * k as f64, 0.0, 0.0))
            .collect();
        let mut w = SelfOverlap::new(10, r, 2.0 * r, 3);
        assert_eq!(w.measure(&straight), 0.0);
        // Bead 9 folded back onto bead 0, 0.4 short of touching its centre.
        let mut folded = straight.clone();
        folded[9] = Vec3::new(0.4, 0.0, 0.0);
        assert!((w.measure(&folded) - (2.0 * r - 0.4)).abs() < 1e-12);
        // Neighbours never count, however close.
        let mut pinched = straight.clone();
        pinched[1] = Vec3::new(0.1, 0.0, 0.0);
        assert_eq!(w.measure(&pinched), 0.0);
    }

    #[test]
    fn pairs_that_overlap_at_rest_are_left_out() {
        // Spacing 0.6 r_b: beads up to three apart overlap in the straight fibre.
        let r = 1.0;
        let pos: Vec<Vec3> = (0..8)
            .map(|k| Vec3::new(0.6 * k as f64, 0.0, 0.0))
            .collect();
        let mut w = SelfOverlap::new(8, r, 0.6, 3);
        assert_eq!(w.min_gap, 4);
        assert_eq!(w.measure(&pos), 0.0);
        // A spacing of exactly r_b still counts second neighbours (touching at rest).
        assert_eq!(SelfOverlap::new(8, 1.0, 1.0, 3).min_gap, 2);
    }

    #[test]
    fn cell_list_and_skipping_give_the_plain_definition() {
        // Coils of 200 beads (cell list) and 20 (all pairs), 2D and 3D, dense (a box of ten
        // radii) and loose (a hundred), moved in small random steps so that some steps are
        // skipped and others checked; every step must give the bits of a fresh watch and the
        // value of the definition.
        let mut seed = Xorshift(0x2545_F491_4F6C_DD1D);
        let mut skipped = 0;
        let cases = [(200, 10.0), (20, 10.0), (200, 100.0), (20, 100.0)];
        for ((beads, side), planar) in cases.into_iter().flat_map(|c| [(c, false), (c, true)]) {
            let radius = 1.25;
            let mut pos = coil(beads, radius, side * radius, planar, &mut seed);
            let dims = if planar { 2 } else { 3 };
            let mut w = SelfOverlap::new(beads, radius, 2.0 * radius, dims);
            let mut overlapping = 0;
            for _ in 0..200 {
                // The cell list sees gaps up to the skin, all pairs every gap.
                let cap = if beads > ALL_PAIRS_UP_TO {
                    radius
                } else {
                    f64::INFINITY
                };
                let least = clearance_by_definition(&pos, radius, 2, cap);
                let expect = (-least).max(0.0);
                let got = w.measure(&pos);
                let fresh = SelfOverlap::new(beads, radius, 2.0 * radius, dims).measure(&pos);
                assert_eq!(got.to_bits(), fresh.to_bits());
                assert!((got - expect).abs() < 1e-12, "{got} against {expect}");
                if w.reference == pos {
                    // Checked: the clearance it keeps is the definition's (to rounding).
                    assert!(
                        (w.margin - least).abs() < 1e-12,
                        "{} against {least}",
                        w.margin
                    );
                } else {
                    skipped += 1;
                }
                if got > 0.0 {
                    overlapping += 1;
                }
                for p in pos.iter_mut() {
                    p.x += 0.02 * (seed.uniform() - 0.5);
                    p.y += 0.02 * (seed.uniform() - 0.5);
                    if !planar {
                        p.z += 0.02 * (seed.uniform() - 0.5);
                    }
                }
            }
            // The long dense coils cross themselves; the others may not.
            if beads == 200 && side == 10.0 {
                assert!(overlapping > 0, "{beads} {planar}");
            }
        }
        // Some steps were skipped (a clear fibre that moved little) and still agreed.
        assert!(skipped > 0);
    }

    #[test]
    fn the_cell_list_finds_the_closest_pair_of_scattered_beads() {
        // Beads strewn at random (a fibre cut into pieces), so dense that their closest pair
        // is usually within the skin of touching, in a random direction: 200 scatterings per
        // dimension, each checked against all pairs.
        let mut seed = Xorshift(0x9E37_79B9_7F4A_7C15);
        let (r, beads) = (1.0, 64);
        for (dims, side) in [(3, 40.0), (2, 200.0)] {
            let mut within_skin = 0;
            for _ in 0..200 {
                let pos: Vec<Vec3> = (0..beads)
                    .map(|_| {
                        let z = if dims == 3 {
                            side * seed.uniform()
                        } else {
                            0.0
                        };
                        Vec3::new(side * seed.uniform() - 7.0, side * seed.uniform(), z)
                    })
                    .collect();
                let mut w = SelfOverlap::new(beads, r, 2.0 * r, dims);
                let got = w.measure(&pos);
                let least = clearance_by_definition(&pos, r, 2, 2.0 * r);
                assert_eq!(w.margin, least, "dims {dims}");
                assert_eq!(got, (-least).max(0.0));
                if least < r {
                    within_skin += 1;
                }
            }
            assert!(within_skin > 100, "dims {dims}: {within_skin}");
        }
    }

    #[test]
    fn a_clear_fibre_is_checked_only_after_moving_half_its_clearance() {
        let r = 1.0;
        let arc: Vec<Vec3> = (0..50)
            .map(|k| {
                let a = 0.1 * k as f64;
                Vec3::new(20.0 * a.cos(), 20.0 * a.sin(), 0.0)
            })
            .collect();
        let mut w = SelfOverlap::new(50, r, 2.0, 2);
        assert_eq!(w.measure(&arc), 0.0);
        let first = w.margin;
        assert!(first > 0.0 && first <= 2.0 * r + 1e-12, "{first}");
        // Drift the whole fibre by less than half the clearance: no new check.
        let drifted: Vec<Vec3> = arc
            .iter()
            .map(|p| p + Vec3::new(0.4 * first, 0.0, 0.0))
            .collect();
        assert_eq!(w.measure(&drifted), 0.0);
        assert_eq!(w.reference, arc);
        // Past half of it: checked again (still clear, the drift is rigid).
        let further: Vec<Vec3> = arc
            .iter()
            .map(|p| p + Vec3::new(0.6 * first, 0.0, 0.0))
            .collect();
        assert_eq!(w.measure(&further), 0.0);
        assert_eq!(w.reference, further);
    }
}
