//! Pairs of beads that may be close, across all fibres of a scene: a hashed cell list that
//! knows the fluid's periodic box.
//!
//! Read through the Verlet list of [`crate::near_pairs`], which the contacts and the overlap
//! diagnostics use. Every unordered pair `i < j` whose beads lie within
//! `reach` of each other (minimum-image distance along the periodic axes) is visited exactly
//! once, with further pairs visited or not as the cells fall; callers test the distance.
//!
//! Periodic axes: the fluid's box wraps along x (and y without walls, z in 3D), so two beads
//! on either side of the seam are neighbours. Along such an axis the box is cut into
//! `n = floor(L / reach)` cells (at least 1), each at least `reach` wide, and a bead's cell is
//! that of its position wrapped into the box; neighbouring cells wrap round. The positions
//! themselves stay unwrapped (the fibre node never wraps them): separations are taken as
//! minimum images. Along other axes cells are `reach` wide and unbounded.
//!
//! The visiting order depends only on the positions (buckets in a fixed hash, beads in index
//! order within a bucket), so sums over the pairs are reproducible bit for bit. Buffers are
//! allocated in [`BeadPairs::new`]; visiting allocates nothing.
use crate::quaternion::Vec3;

/// Scenes of at most this many beads visit every pair.
pub const ALL_PAIRS_UP_TO: usize = 32;

/// The cell list over a fixed number of beads.
#[derive(Debug, Clone)]
pub struct BeadPairs {
    /// Box length along each periodic axis (None: the axis does not wrap).
    period: [Option<f64>; 3],
    /// Cell width per axis (length).
    width: [f64; 3],
    /// Cells along each periodic axis (unused for the others).
    cells: [i64; 3],
    /// The offsets to the neighbouring cells that a bead looks into, distinct after
    /// wrapping. Half the stencil: its own cell (the beads after it) and the 13 (2D: 4)
    /// cells ahead of it, each other cell seen from one side only. With a periodic axis of two
    /// cells, where ahead and behind are one cell, every neighbouring cell, the beads after
    /// it.
    stencil: Vec<[i64; 3]>,
    half: bool,
    planar: bool,
    /// Each bead's cell, bucket and the beads in bucket order (empty: all pairs).
    cell_of: Vec<[i64; 3]>,
    bucket_of: Vec<u32>,
    start: Vec<u32>,
    order: Vec<u32>,
}

impl BeadPairs {
    /// A cell list for `beads` beads whose pairs of interest lie within `reach` (length) of
    /// each other, in `dims` (2 or 3) dimensions, with the box lengths `period` along the
    /// axes that wrap.
    pub fn new(beads: usize, reach: f64, period: [Option<f64>; 3], dims: usize) -> Self {
        let planar = dims == 2;
        let mut period = period;
        if planar {
            period[2] = None;
        }
        let mut width = [reach; 3];
        let mut cells = [0i64; 3];
        for a in 0..3 {
            if let Some(l) = period[a] {
                let n = ((l / reach).floor() as i64).max(1);
                cells[a] = n;
                width[a] = l / n as f64;
            }
        }
        let along: [Vec<i64>; 3] = std::array::from_fn(|a| match period[a] {
            _ if planar && a == 2 => vec![0],
            Some(_) if cells[a] < 3 => (0..cells[a]).collect(),
            _ => vec![-1, 0, 1],
        });
        // Along a periodic axis of two cells, ahead and behind are the same cell.
        let half = along.iter().all(|o| o.len() != 2);
        let mut stencil = Vec::new();
        for &ox in &along[0] {
            for &oy in &along[1] {
                for &oz in &along[2] {
                    // Ahead: the first non-zero offset positive (or the cell itself).
                    let o = [ox, oy, oz];
                    if !half || o.iter().find(|&&x| x != 0).is_none_or(|&x| x > 0) {
                        stencil.push(o);
                    }
                }
            }
        }
        let listed = beads > ALL_PAIRS_UP_TO;
        let buckets = if listed {
            (2 * beads).next_power_of_two()
        } else {
            0
        };
        Self {
            period,
            width,
            cells,
            stencil,
            half,
            planar,
            cell_of: vec![[0; 3]; if listed { beads } else { 0 }],
            bucket_of: vec![0; if listed { beads } else { 0 }],
            start: vec![0; if listed { buckets + 1 } else { 0 }],
            order: vec![0; if listed { beads } else { 0 }],
        }
    }

    /// `a - b`, as the nearest periodic image of `a` sees `b`.
    pub fn separation(&self, a: &Vec3, b: &Vec3) -> Vec3 {
        let mut d = a - b;
        for (k, p) in self.period.iter().enumerate() {
            if let Some(l) = p {
                d[k] -= l * (d[k] / l).round();
            }
        }
        if self.planar {
            d.z = 0.0;
        }
        d
    }

    fn cell(&self, p: &Vec3) -> [i64; 3] {
        let mut c = [0i64; 3];
        let axes = if self.planar { 2 } else { 3 };
        for (a, ca) in c.iter_mut().enumerate().take(axes) {
            // `as` saturates (NaN to 0): a broken position still lands in some cell.
            *ca = match self.period[a] {
                Some(l) => {
                    let i = (p[a].rem_euclid(l) / self.width[a]).floor() as i64;
                    i.clamp(0, self.cells[a] - 1)
                }
                None => (p[a] / self.width[a]).floor() as i64,
            };
        }
        c
    }

    fn bucket(&self, c: [i64; 3]) -> usize {
        let h = (c[0] as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (c[1] as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (c[2] as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
        // The high bits mix best; the table size is a power of two.
        let buckets = self.start.len() - 1;
        (h >> (64 - buckets.trailing_zeros())) as usize
    }

    /// Visit every pair of beads within `reach` of each other exactly once (and possibly some
    /// further apart), as `visit(i, j, X_i - X_j)` with the minimum-image separation; `i` and
    /// `j` may come in either order.
    pub fn for_each_pair(&mut self, pos: &[Vec3], mut visit: impl FnMut(usize, usize, Vec3)) {
        if self.order.is_empty() {
            for i in 0..pos.len() {
                for j in i + 1..pos.len() {
                    visit(i, j, self.separation(&pos[i], &pos[j]));
                }
            }
            return;
        }
        debug_assert_eq!(pos.len(), self.order.len());
        self.fill(pos);
        for i in 0..pos.len() {
            let c = self.cell_of[i];
            // A bucket may also hold beads of other cells (hash collisions): they are passed
            // over, so each pair is seen once, from the side the stencil gives.
            for o in &self.stencil {
                let mut n = [c[0] + o[0], c[1] + o[1], c[2] + o[2]];
                for (a, na) in n.iter_mut().enumerate() {
                    if self.period[a].is_some() {
                        *na = na.rem_euclid(self.cells[a]);
                    }
                }
                let after_only = !self.half || *o == [0; 3];
                let b = self.bucket(n);
                let (lo, hi) = (self.start[b] as usize, self.start[b + 1] as usize);
                for &j in &self.order[lo..hi] {
                    let j = j as usize;
                    if (j > i || !after_only) && self.cell_of[j] == n {
                        visit(i, j, self.separation(&pos[i], &pos[j]));
                    }
                }
            }
        }
    }

    /// Sort the beads into their buckets.
    fn fill(&mut self, pos: &[Vec3]) {
        for (i, p) in pos.iter().enumerate() {
            let c = self.cell(p);
            self.cell_of[i] = c;
            self.bucket_of[i] = self.bucket(c) as u32;
        }
        sort_into_buckets(
            &self.bucket_of[..pos.len()],
            &mut self.start,
            &mut self.order,
        );
    }
}

/// A counting sort of the beads by bucket: on return `order[start[b]..start[b + 1]]` holds
/// the beads of bucket `b` in increasing index order. `start` has one entry more than
/// there are buckets; `order` one a bead.
fn sort_into_buckets(bucket_of: &[u32], start: &mut [u32], order: &mut [u32]) {
    let buckets = start.len() - 1;
    start.fill(0);
    for &b in bucket_of {
        start[b as usize + 1] += 1;
    }
    for b in 0..buckets {
        start[b + 1] += start[b];
    }
    // Scatter, each start serving as its bucket's cursor.
    for (i, &b) in bucket_of.iter().enumerate() {
        order[start[b as usize] as usize] = i as u32;
        start[b as usize] += 1;
    }
    // The cursors ended on the next bucket's start; shift back.
    for b in (1..=buckets).rev() {
        start[b] = start[b - 1];
    }
    start[0] = 0;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xorshift::Xorshift;

    /// Pairs `(i, j, bits of X_i - X_j)`.
    type Pairs = Vec<(usize, usize, [u64; 3])>;

    /// The pairs within `reach`, sorted, from the cell list and from all pairs.
    fn both(pos: &[Vec3], reach: f64, period: [Option<f64>; 3], dims: usize) -> (Pairs, Pairs) {
        let mut listed = BeadPairs::new(pos.len(), reach, period, dims);
        assert!(pos.len() <= ALL_PAIRS_UP_TO || !listed.order.is_empty());
        let mut got = Vec::new();
        listed.for_each_pair(pos, |i, j, d| {
            // Either order: as (lower, higher), the separation turned with it (exactly, but
            // for the sign of a zero).
            let (i, j, d) = if i < j { (i, j, d) } else { (j, i, -d) };
            let d = d.map(|x| x + 0.0);
            if d.norm() < reach {
                got.push((i, j, [d.x.to_bits(), d.y.to_bits(), d.z.to_bits()]));
            }
        });
        let all = BeadPairs::new(0, reach, period, dims);
        let mut want = Vec::new();
        for i in 0..pos.len() {
            for j in i + 1..pos.len() {
                let d = all.separation(&pos[i], &pos[j]).map(|x| x + 0.0);
                if d.norm() < reach {
                    want.push((i, j, [d.x.to_bits(), d.y.to_bits(), d.z.to_bits()]));
                }
            }
        }
        let n = got.len();
        got.sort_unstable();
        got.dedup();
        assert_eq!(got.len(), n, "a pair was visited twice");
        (got, want)
    }

    /// Beads scattered over a box and a margin outside it (unwrapped positions), with and
    /// without periodic axes, including axes of one and two cells: the cell list finds
    /// exactly the pairs all pairs find, each once, with the same separations.
    #[test]
    fn finds_every_close_pair_once_across_the_periodic_seams() {
        let mut seed = Xorshift(0x2545_F491_4F6C_DD1D);
        let mut cases = 0;
        for dims in [2usize, 3] {
            for periodic in [
                [false, false, false],
                [true, false, true],
                [true, true, true],
            ] {
                for (side, reach) in [(40.0, 3.0), (40.0, 15.0), (7.0, 3.0), (10.0, 5.5)] {
                    let period: [Option<f64>; 3] =
                        std::array::from_fn(|a| periodic[a].then_some(side));
                    for _ in 0..10 {
                        let n = 60 + (seed.uniform() * 140.0) as usize;
                        let pos: Vec<Vec3> = (0..n)
                            .map(|_| {
                                let mut c = || (seed.uniform() * 1.5 - 0.25) * side;
                                let (x, y, z) = (c(), c(), c());
                                Vec3::new(x, y, if dims == 3 { z } else { 0.0 })
                            })
                            .collect();
                        let (got, want) = both(&pos, reach, period, dims);
                        assert_eq!(got, want, "dims {dims} periodic {periodic:?} side {side}");
                        cases += usize::from(!want.is_empty());
                    }
                }
            }
        }
        assert!(cases > 200, "{cases} cases with close pairs");
    }

    #[test]
    fn separations_are_minimum_images() {
        let p = BeadPairs::new(2, 2.0, [Some(10.0), None, Some(8.0)], 3);
        let d = p.separation(&Vec3::new(9.5, 0.0, 7.0), &Vec3::new(0.5, 3.0, -0.5));
        assert!((d - Vec3::new(-1.0, -3.0, -0.5)).norm() < 1e-12, "{d}");
        // In 2D z neither wraps nor counts.
        let q = BeadPairs::new(2, 2.0, [Some(10.0), Some(10.0), Some(3.0)], 2);
        let d = q.separation(&Vec3::new(19.0, -4.0, 5.0), &Vec3::new(0.0, 5.0, 0.0));
        assert!((d - Vec3::new(-1.0, 1.0, 0.0)).norm() < 1e-12, "{d}");
    }
}
