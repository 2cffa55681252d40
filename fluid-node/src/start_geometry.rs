//! Where the fibres start, checked once on the first bead states a run receives: a bead
//! inside a wall, two fibres on top of each other (a second `[[fibre]]` left at the default
//! `start`), or a fibre longer than the periodic box (touching its own image) is a mistake in
//! the scene, not physics, and the solvers would run it without complaint. Later steps are
//! not checked: what the beads do then is the simulation's business.
//!
//! Lengths in grid units. Overlap means the nominal discs / spheres (radius `r_b`, the
//! profile's phi = 1/2 surface) intersect; touching is allowed.

use std::collections::HashMap;

use cosim::scene_keys::Num;
use cosim::BeadState;

/// Relative slack on every distance comparison, so that beads placed exactly touching (a
/// wall or each other) pass whatever the last bit of their coordinates.
const SLACK: f64 = 1e-9;

/// The fluid's box as the beads see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartBox {
    /// 2 or 3.
    pub dims: usize,
    /// Box lengths along x, y, z (the grid sizes; z unused in 2D).
    pub size: [f64; 3],
    /// Axes along which the box wraps (the flow is periodic there).
    pub periodic: [bool; 3],
    /// The walls normal to y, if the scene has them.
    pub walls: Option<WallFaces>,
}

/// The fluid gap between two walls normal to y.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallFaces {
    /// y of the bottom wall's face (the fluid lies above it).
    pub bottom: f64,
    /// y of the top wall's face (the fluid lies below it).
    pub top: f64,
}

/// Check the beads' first positions: each bead clear of the walls, no two fibres
/// overlapping, no fibre overlapping its own periodic image. `beads_per_fibre` and `radius`
/// (one per bead, fibres in order) describe what `positions` holds. The error names the
/// fibre, the bead and the key to change.
pub fn check(
    geometry: &StartBox,
    beads_per_fibre: &[usize],
    radius: &[f64],
    positions: &[[f64; 3]],
) -> Result<(), String> {
    let n = positions.len();
    if radius.len() != n || beads_per_fibre.iter().sum::<usize>() != n {
        return Err(format!(
            "start geometry: {n} positions, {} radii and {} beads in the fibres",
            radius.len(),
            beads_per_fibre.iter().sum::<usize>()
        ));
    }
    // (fibre, bead within the fibre) of each bead.
    let owner: Vec<(usize, usize)> = beads_per_fibre
        .iter()
        .enumerate()
        .flat_map(|(f, &b)| (0..b).map(move |k| (f, k)))
        .collect();
    let d = geometry.dims;
    if let Some(w) = geometry.walls {
        for (i, p) in positions.iter().enumerate() {
            wall_clearance(w, geometry.size[1], owner[i], radius[i], p[1])?;
        }
    }
    // A bead as large as a periodic box touches itself.
    for (i, &r) in radius.iter().enumerate() {
        if let Some(a) = (0..d).find(|&a| geometry.periodic[a] && 2.0 * r > geometry.size[a]) {
            let (f, k) = owner[i];
            return Err(format!(
                "fibre {f} bead {k}: its diameter {} exceeds the periodic box's {} = {}, so \
                 it overlaps its own periodic image; enlarge fluid.grid or shrink \
                 fibre.{f}.bead_radius",
                2.0 * r,
                AXES[a],
                geometry.size[a]
            ));
        }
    }
    overlaps(geometry, &owner, radius, positions)
}

/// What a fluid node keeps from configure to check the first bead states it receives.
#[derive(Debug, Clone, PartialEq)]
pub struct StartCheck {
    pub geometry: StartBox,
    pub beads_per_fibre: Vec<usize>,
    /// One per bead, fibres in order.
    pub radius: Vec<f64>,
}

impl StartCheck {
    /// [`check`] on the states' positions.
    pub fn check(&self, states: &[BeadState]) -> Result<(), String> {
        let positions: Vec<[f64; 3]> = states.iter().map(|s| s.position).collect();
        check(
            &self.geometry,
            &self.beads_per_fibre,
            &self.radius,
            &positions,
        )
        .map_err(|e| format!("the fibres' start positions: {e}"))
    }
}

const AXES: [&str; 3] = ["x", "y", "z"];

fn wall_clearance(
    w: WallFaces,
    ny: f64,
    (f, k): (usize, usize),
    r: f64,
    y: f64,
) -> Result<(), String> {
    // y is taken as given, not modulo the box: SPM's slabs sit in a periodic box, but the
    // fibre node's wall contact and overlap watch measure from the faces as they are.
    let slack = SLACK * r.max(1.0);
    let (side, face) = if y - r < w.bottom - slack {
        ("bottom", w.bottom)
    } else if y + r > w.top + slack {
        ("top", w.top)
    } else {
        return Ok(());
    };
    let beyond = if !(-0.5..ny - 0.5).contains(&y) {
        format!(
            ", outside the box (y from -0.5 to {}; walls do not wrap)",
            ny - 0.5
        )
    } else {
        String::new()
    };
    Err(format!(
        "fibre {f} bead {k} starts at y = {}{beyond} with radius {r}: it reaches into the \
         {side} wall, whose face is at y = {face}. The fluid lies between y = {} and {}, so a \
         bead's centre must start between {} and {}; move fibre.{f}.start (or change \
         fibre.{f}.direction or fibre.{f}.beads)",
        Num(y),
        w.bottom,
        w.top,
        w.bottom + r,
        w.top - r
    ))
}

/// Pairs of beads closer than their radii, through a cell list (one pass, O(n)).
fn overlaps(
    geometry: &StartBox,
    owner: &[(usize, usize)],
    radius: &[f64],
    positions: &[[f64; 3]],
) -> Result<(), String> {
    let d = geometry.dims;
    let r_max = radius.iter().cloned().fold(0.0, f64::max);
    if positions.len() < 2 || r_max <= 0.0 {
        return Ok(());
    }
    // Cells at least 2 r_max wide along each axis, so that an overlapping pair lies in the
    // same or adjacent cells (adjacent across the periodic seam too).
    let mut cells = [1usize; 3];
    for a in 0..d {
        cells[a] = ((geometry.size[a] / (2.0 * r_max)).floor() as usize).clamp(1, 1 << 16);
    }
    let cell_of = |p: &[f64; 3]| -> [usize; 3] {
        let mut c = [0usize; 3];
        for a in 0..d {
            let l = geometry.size[a];
            let u = p[a].rem_euclid(l) / l;
            c[a] = ((u * cells[a] as f64) as usize).min(cells[a] - 1);
        }
        c
    };
    let key = |c: [usize; 3]| (c[0] * cells[1] + c[1]) * cells[2] + c[2];
    let mut bins: HashMap<usize, Vec<usize>> = HashMap::new();
    for (i, p) in positions.iter().enumerate() {
        bins.entry(key(cell_of(p))).or_default().push(i);
    }
    let mut neighbours = Vec::with_capacity(27);
    for (i, p) in positions.iter().enumerate() {
        let c = cell_of(p);
        neighbours.clear();
        for dz in [-1i64, 0, 1] {
            for dy in [-1i64, 0, 1] {
                for dx in [-1i64, 0, 1] {
                    let off = [dx, dy, dz];
                    if (d..3).any(|a| off[a] != 0) {
                        continue;
                    }
                    let mut m = [0usize; 3];
                    for a in 0..d {
                        m[a] = (c[a] as i64 + off[a]).rem_euclid(cells[a] as i64) as usize;
                    }
                    let k = key(m);
                    if !neighbours.contains(&k) {
                        neighbours.push(k);
                    }
                }
            }
        }
        for k in &neighbours {
            for &j in bins.get(k).map_or(&[][..], |v| v.as_slice()) {
                if j > i {
                    pair(geometry, owner, radius, positions, i, j)?;
                }
            }
        }
    }
    Ok(())
}

fn pair(
    geometry: &StartBox,
    owner: &[(usize, usize)],
    radius: &[f64],
    positions: &[[f64; 3]],
    i: usize,
    j: usize,
) -> Result<(), String> {
    let (p, q) = (positions[i], positions[j]);
    let (mut nearest2, mut direct2) = (0.0, 0.0);
    let mut across = None;
    for a in 0..geometry.dims {
        let dx = q[a] - p[a];
        direct2 += dx * dx;
        let m = if geometry.periodic[a] {
            let l = geometry.size[a];
            let shift = (dx / l).round();
            if shift != 0.0 {
                across = Some(a);
            }
            dx - shift * l
        } else {
            dx
        };
        nearest2 += m * m;
    }
    let reach = (radius[i] + radius[j]) * (1.0 - SLACK);
    if nearest2 >= reach * reach {
        return Ok(());
    }
    let ((f, k), (g, m)) = (owner[i], owner[j]);
    let dist = nearest2.sqrt();
    let sum = radius[i] + radius[j];
    if f != g {
        return Err(format!(
            "fibre {g} bead {m} at {} overlaps fibre {f} bead {k} at {}: centres {dist} \
             apart{}, radii summing to {sum}; give each fibre its own fibre.N.start",
            fmt_point(&q, geometry.dims),
            fmt_point(&p, geometry.dims),
            across.map_or(String::new(), |a| format!(
                " across the periodic box in {}",
                AXES[a]
            ))
        ));
    }
    // The same fibre: neighbours along the chain may overlap (spacing < 2 r_b); only a copy
    // of the fibre across the periodic box may not.
    if let Some(a) = across {
        if direct2 > nearest2 * (1.0 + SLACK) {
            return Err(format!(
                "fibre {f} overlaps its own periodic image: bead {m} at {} comes within {dist} \
                 of bead {k} at {} across the box (its length along {} is {}), radii summing \
                 to {sum}; enlarge fluid.grid or shorten fibre {f}",
                fmt_point(&q, geometry.dims),
                fmt_point(&p, geometry.dims),
                AXES[a],
                geometry.size[a]
            ));
        }
    }
    Ok(())
}

fn fmt_point(p: &[f64; 3], dims: usize) -> String {
    let parts: Vec<String> = p[..dims].iter().map(|x| format!("{x}")).collect();
    format!("({})", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2D box 96 x 96 with SPM-like slabs of thickness 4: faces at 3.5 and 91.5.
    fn slab_box() -> StartBox {
        StartBox {
            dims: 2,
            size: [96.0, 96.0, 1.0],
            periodic: [true, true, false],
            walls: Some(WallFaces {
                bottom: 3.5,
                top: 91.5,
            }),
        }
    }

    fn chain(start: [f64; 3], step: [f64; 3], n: usize) -> Vec<[f64; 3]> {
        (0..n)
            .map(|k| {
                let t = k as f64;
                [
                    start[0] + t * step[0],
                    start[1] + t * step[1],
                    start[2] + t * step[2],
                ]
            })
            .collect()
    }

    #[test]
    fn a_fibre_in_the_gap_passes_and_one_in_a_wall_is_named() {
        let b = slab_box();
        let ok = chain([48.0, 28.0, 0.0], [0.0, 8.0, 0.0], 6);
        assert_eq!(check(&b, &[6], &[4.0; 6], &ok), Ok(()));
        // Touching the bottom face exactly is allowed.
        let touching = chain([48.0, 7.5, 0.0], [8.0, 0.0, 0.0], 3);
        assert_eq!(check(&b, &[3], &[4.0; 3], &touching), Ok(()));
        let low = chain([48.0, 7.0, 0.0], [8.0, 0.0, 0.0], 3);
        let e = check(&b, &[3], &[4.0; 3], &low).unwrap_err();
        assert!(
            e.starts_with("fibre 0 bead 0 starts at y = 7 with radius 4"),
            "{e}"
        );
        assert!(e.contains("bottom wall, whose face is at y = 3.5"), "{e}");
        assert!(e.contains("between 7.5 and 87.5"), "{e}");
        // 20 beads upwards from y = 28 run through the top wall.
        let long = chain([48.0, 28.0, 0.0], [0.0, 8.0, 0.0], 20);
        let e = check(&b, &[20], &[4.0; 20], &long).unwrap_err();
        assert!(e.starts_with("fibre 0 bead 8 starts at y = 92"), "{e}");
        assert!(e.contains("top wall"), "{e}");
    }

    #[test]
    fn walls_do_not_wrap_y() {
        let b = slab_box();
        // y = -50 would be y = 46 in the periodic box, mid-gap, but the fibre node's wall
        // contact and overlap watch take y as it is.
        let e = check(&b, &[1], &[4.0], &[[10.0, -50.0, 0.0]]).unwrap_err();
        assert!(e.contains("y = -50, outside the box"), "{e}");
        assert!(e.contains("bottom wall"), "{e}");
        let e = check(&b, &[1], &[4.0], &[[10.0, 500.0, 0.0]]).unwrap_err();
        assert!(
            e.contains("y = 500, outside the box (y from -0.5 to 95.5"),
            "{e}"
        );
        assert!(e.contains("top wall"), "{e}");
        let lattice = StartBox {
            walls: Some(WallFaces {
                bottom: -0.5,
                top: 199.5,
            }),
            periodic: [true, false, false],
            size: [100.0, 200.0, 1.0],
            ..b
        };
        assert_eq!(check(&lattice, &[1], &[2.0], &[[10.0, 1.5, 0.0]]), Ok(()));
        let e = check(&lattice, &[1], &[2.0], &[[10.0, 1.0, 0.0]]).unwrap_err();
        assert!(e.contains("bottom wall, whose face is at y = -0.5"), "{e}");
        let e = check(&lattice, &[1], &[2.0], &[[10.0, 250.0, 0.0]]).unwrap_err();
        assert!(e.contains("top wall"), "{e}");
    }

    #[test]
    fn two_fibres_at_one_start_are_refused_and_apart_they_pass() {
        let b = StartBox {
            walls: None,
            ..slab_box()
        };
        let mut two = chain([20.0, 20.0, 0.0], [8.0, 0.0, 0.0], 3);
        two.extend(chain([20.0, 20.0, 0.0], [8.0, 0.0, 0.0], 3));
        let e = check(&b, &[3, 3], &[4.0; 6], &two).unwrap_err();
        assert!(
            e.starts_with("fibre 1 bead 0 at (20, 20) overlaps fibre 0 bead 0 at (20, 20)"),
            "{e}"
        );
        // The second fibre 8 above the first: touching, allowed.
        let mut apart = chain([20.0, 20.0, 0.0], [8.0, 0.0, 0.0], 3);
        apart.extend(chain([20.0, 28.0, 0.0], [8.0, 0.0, 0.0], 3));
        assert_eq!(check(&b, &[3, 3], &[4.0; 6], &apart), Ok(()));
        // Across the periodic seam in x: bead at x = 94 and a bead of another fibre at 2.
        let seam = vec![[94.0, 50.0, 0.0], [2.0, 50.0, 0.0]];
        let e = check(&b, &[1, 1], &[4.0; 2], &seam).unwrap_err();
        assert!(
            e.contains("centres 4 apart across the periodic box in x"),
            "{e}"
        );
    }

    #[test]
    fn overlapping_neighbours_pass_but_a_fibre_longer_than_the_box_is_refused() {
        let b = StartBox {
            walls: None,
            ..slab_box()
        };
        // Spacing 6 < 2 r_b: overlapping neighbours along one fibre are the model's business.
        let dense = chain([10.0, 40.0, 0.0], [6.0, 0.0, 0.0], 12);
        assert_eq!(check(&b, &[12], &[4.0; 12], &dense), Ok(()));
        // 13 touching beads: from x = 4 to 100, so bead 12 meets bead 0's image.
        let long = chain([4.0, 40.0, 0.0], [8.0, 0.0, 0.0], 13);
        let e = check(&b, &[13], &[4.0; 13], &long).unwrap_err();
        assert!(
            e.starts_with("fibre 0 overlaps its own periodic image"),
            "{e}"
        );
        assert!(e.contains("along x is 96"), "{e}");
        // 12 touching beads span exactly 96: the ends touch their images, allowed.
        let fits = chain([4.0, 40.0, 0.0], [8.0, 0.0, 0.0], 12);
        assert_eq!(check(&b, &[12], &[4.0; 12], &fits), Ok(()));
    }

    #[test]
    fn three_d_and_a_bead_larger_than_the_box() {
        let b = StartBox {
            dims: 3,
            size: [32.0, 32.0, 32.0],
            periodic: [true; 3],
            walls: None,
        };
        let two = vec![[16.0, 16.0, 1.0], [16.0, 16.0, 30.0]];
        let e = check(&b, &[1, 1], &[2.0; 2], &two).unwrap_err();
        assert!(
            e.contains("centres 3 apart across the periodic box in z"),
            "{e}"
        );
        let e = check(&b, &[1], &[17.0], &[[16.0, 16.0, 16.0]]).unwrap_err();
        assert!(e.contains("exceeds the periodic box's x = 32"), "{e}");
        assert!(check(&b, &[1, 2], &[2.0; 2], &two).is_err());
    }

    #[test]
    fn the_cell_list_finds_what_all_pairs_find() {
        // A deterministic scatter of 300 beads of mixed radii in a 2D periodic box: the cell
        // list must report an overlap exactly when the all-pairs search does.
        let b = StartBox {
            walls: None,
            size: [200.0, 150.0, 1.0],
            ..slab_box()
        };
        let mut s = 12345u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut clear = 0;
        for trial in 0..40 {
            let n = 30 + trial;
            let pos: Vec<[f64; 3]> = (0..n)
                .map(|_| [next() * 400.0 - 100.0, next() * 150.0, 0.0])
                .collect();
            let rad: Vec<f64> = (0..n).map(|_| 0.5 + 1.5 * next()).collect();
            let per_fibre = vec![1; n];
            let owner: Vec<(usize, usize)> = (0..n).map(|f| (f, 0)).collect();
            let mut brute = Ok(());
            'outer: for i in 0..n {
                for j in i + 1..n {
                    if let Err(e) = pair(&b, &owner, &rad, &pos, i, j) {
                        brute = Err(e);
                        break 'outer;
                    }
                }
            }
            let fast = check(&b, &per_fibre, &rad, &pos);
            clear += usize::from(fast.is_ok());
            assert_eq!(
                fast.is_ok(),
                brute.is_ok(),
                "trial {trial}: {fast:?} / {brute:?}"
            );
        }
        // Both outcomes occur (18 of 40 trials are clear), so the comparison means something.
        assert!((5..=35).contains(&clear), "{clear} of 40 trials clear");
    }
}
