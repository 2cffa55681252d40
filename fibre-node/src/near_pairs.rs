//! A Verlet list over [`BeadPairs`]: the pairs of beads within `reach + skin` of each other
//! when the list was built, kept while no bead has moved half the skin since.
//!
//! The cell list costs a hash and a scattered read per neighbouring cell and bead; a bead
//! in a fluid moves a hundredth of a grid spacing a step or less, so the same pairs are
//! found step after step. The list is built from the cell list, with the pairs a caller's
//! `keep` admits and whose minimum-image distance is below `reach + skin`, and reused: a pair
//! left out was at least `reach + skin` apart, and while twice the largest displacement of a
//! bead since the build stays below `skin` it is still at least `reach` apart. Every call
//! then visits every admitted pair within `reach` exactly once, from the list.
//!
//! The list is kept sorted, pairs `(i, j)` with `i < j` in increasing order: a sum over the
//! pairs within `reach` takes them in index order whatever the positions the list was built
//! at, so it gives the same bits in a run resumed from a checkpoint (which builds its list
//! afresh) as in the run it continues. The list's buffer grows to the largest list seen and
//! keeps that size; nothing else is allocated after [`NearPairs::new`].
use crate::bead_pairs::BeadPairs;
use crate::quaternion::Vec3;

/// The Verlet list over a fixed number of beads.
#[derive(Debug, Clone)]
pub struct NearPairs {
    pairs: BeadPairs,
    /// The pairs of interest lie within `reach`; the list holds those within `reach + skin`.
    reach: f64,
    skin: f64,
    list: Vec<(u32, u32)>,
    /// Positions at the last build (none yet: `built` false).
    built_at: Vec<Vec3>,
    built: bool,
    rebuilds: u64,
}

impl NearPairs {
    /// A list for `beads` beads whose pairs of interest lie within `reach` (length) of each
    /// other, rebuilt once a bead has moved `skin / 2` (length, > 0), in `dims` (2 or 3)
    /// dimensions with the box lengths `period` along the axes that wrap.
    pub fn new(beads: usize, reach: f64, skin: f64, period: [Option<f64>; 3], dims: usize) -> Self {
        assert!(skin > 0.0 && reach > 0.0, "reach {reach} and skin {skin}");
        Self {
            pairs: BeadPairs::new(beads, reach + skin, period, dims),
            reach,
            skin,
            list: Vec::with_capacity(2 * beads),
            built_at: vec![Vec3::zeros(); beads],
            built: false,
            rebuilds: 0,
        }
    }

    /// Visit every pair `(i, j)`, `i < j`, that `keep(i, j)` admits and whose beads lie
    /// within `reach` of each other exactly once (and possibly some further apart), in
    /// increasing order of `(i, j)`, as `visit(i, j, X_i - X_j)` with the minimum-image
    /// separation. `keep` must give the same answer for a pair at every call (it is asked
    /// only when the list is built).
    pub fn for_each_pair(
        &mut self,
        pos: &[Vec3],
        keep: impl Fn(usize, usize) -> bool,
        mut visit: impl FnMut(usize, usize, Vec3),
    ) {
        debug_assert_eq!(pos.len(), self.built_at.len());
        if !self.built || !self.still_valid(pos) {
            self.build(pos, keep);
        }
        for &(i, j) in &self.list {
            let (i, j) = (i as usize, j as usize);
            visit(i, j, self.pairs.separation(&pos[i], &pos[j]));
        }
    }

    /// How often the list was built.
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// Whether no bead moved far enough since the build for a pair left out to come within
    /// `reach`. Positions are never wrapped, so displacements are plain differences; the
    /// tolerance covers the rounding of the distances the list was cut at.
    fn still_valid(&self, pos: &[Vec3]) -> bool {
        let mut moved2: f64 = 0.0;
        for (p, q) in pos.iter().zip(&self.built_at) {
            moved2 = moved2.max((p - q).norm_squared());
        }
        2.0 * moved2.sqrt() < self.skin - 1e-9 * (self.reach + self.skin)
    }

    fn build(&mut self, pos: &[Vec3], keep: impl Fn(usize, usize) -> bool) {
        let cut2 = (self.reach + self.skin).powi(2);
        let list = &mut self.list;
        list.clear();
        self.pairs.for_each_pair(pos, |i, j, d| {
            let (i, j) = (i.min(j), i.max(j));
            if d.norm_squared() < cut2 && keep(i, j) {
                list.push((i as u32, j as u32));
            }
        });
        list.sort_unstable();
        self.built_at.copy_from_slice(pos);
        self.built = true;
        self.rebuilds += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xorshift::Xorshift;

    /// Beads on random walks in a box periodic in x and z (3D) or x (2D), some walking
    /// fast: at every step the list visits exactly the admitted pairs within reach (each
    /// once, in index order, with the separation the definition gives, bit for bit), and it
    /// is rebuilt far less often than every step.
    #[test]
    fn visits_every_admitted_pair_within_reach_while_the_beads_walk() {
        for dims in [2usize, 3] {
            let (beads, side, reach, skin) = (300, 30.0, 2.0, 0.5);
            let period = [Some(side), None, if dims == 3 { Some(side) } else { None }];
            let mut seed = Xorshift(0x2545_F491_4F6C_DD1D);
            let mut pos: Vec<Vec3> = (0..beads)
                .map(|_| {
                    let z = if dims == 3 { seed.uniform() } else { 0.0 };
                    Vec3::new(seed.uniform(), seed.uniform(), z) * side
                })
                .collect();
            let keep = |i: usize, j: usize| (i / 5) != (j / 5);
            let mut near = NearPairs::new(beads, reach, skin, period, dims);
            let image = BeadPairs::new(0, 1.0, period, dims);
            let steps = 200;
            for step in 0..steps {
                let mut seen = Vec::new();
                let mut last = None;
                near.for_each_pair(&pos, keep, |i, j, d| {
                    assert!(i < j && last < Some((i, j)), "{last:?} then {:?}", (i, j));
                    last = Some((i, j));
                    if d.norm() < reach {
                        seen.push((i, j, d.norm().to_bits()));
                    }
                });
                let mut want = Vec::new();
                for i in 0..beads {
                    for j in i + 1..beads {
                        let d = image.separation(&pos[i], &pos[j]);
                        if keep(i, j) && d.norm() < reach {
                            want.push((i, j, d.norm().to_bits()));
                        }
                    }
                }
                assert_eq!(seen, want, "dims {dims}, step {step}");
                for (k, p) in pos.iter_mut().enumerate() {
                    let speed = if k % 7 == 0 { 0.1 } else { 0.02 };
                    let z = if dims == 3 { seed.uniform() - 0.5 } else { 0.0 };
                    *p += Vec3::new(seed.uniform() - 0.5, seed.uniform() - 0.5, z) * speed;
                }
            }
            let rebuilds = near.rebuilds();
            println!("dims {dims}: {rebuilds} builds over {steps} steps");
            assert!(rebuilds > 1 && rebuilds < steps / 4, "{rebuilds}");
        }
    }
}
