//! S2023's flow groups given in a scene in place of the keys they set (S2023 eq. 18):
//!
//! - `fluid.confinement` C = l_c / H sets the gap: `fluid.grid = [nx]` becomes
//!   `[nx, round(l_c / C + 2 T)]` (2D scenes);
//! - `fluid.particle_shear_reynolds` Re_ps = rho gamma l_c^2 / (4 eta_f) sets
//!   `fluid.viscosity` = rho gamma l_c^2 / (4 Re_ps), with gamma = (top - bottom) / H.
//!
//! The gap H is the lattice's ny under FPD (T = 0: bounce-back walls at y = -1/2 and
//! ny - 1/2) and the rows between SPM's wall slabs, ny - 2 T (`walls.thickness` T), so the
//! same groups give the same flow with either fluid method
//! ([`cosim::scene_keys::wall_shear`]).
//!
//! l_c = N d is fibre 0's contour (`beads` x 2 `bead_radius`), as in the nodes' derived
//! values. Both groups span the fluid, wall and fibre tables, so they are resolved here, once,
//! before any node is configured: every node and both process layouts read the same
//! `fluid.grid` and `fluid.viscosity`. The fibre's own groups (K, K_s) stay with the fibre
//! node (`fibre.N.bending_number`, `fibre.N.stretch_number`), which reads the resolved
//! viscosity and gap. The nodes report the groups the resolved keys give
//! (`fluid.confinement`, `fluid.particle_shear_reynolds`), so a rounded gap shows there.

use crate::metrics::number;
use cosim::scene_keys::{positive, AtMost, Num, Sig};

/// The FPD fluid's default density (`fluid.density` absent), as the fluid node reads it.
const DEFAULT_DENSITY: f64 = 1.0;

/// What resolving changed, in words, and advice where a group could not be met exactly.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Resolved {
    /// One line a group: `fluid.confinement = 0.5 -> fluid.grid = [200, 160]`.
    pub lines: Vec<String>,
    /// A group the lattice cannot realise exactly (a gap rounded to whole nodes).
    pub notes: Vec<String>,
}

/// A group's value: a finite positive number, else a message naming the key.
fn group_value(fluid: &toml::Table, key: &str) -> Result<Option<f64>, String> {
    match fluid.get(key) {
        None => Ok(None),
        Some(v) => match number(Some(v)) {
            Some(x) => positive(&format!("fluid.{key}"), x).map(Some),
            None => Err(format!("fluid.{key}: expected a positive number, got {v}")),
        },
    }
}

/// Fibre 0's contour l_c = N d (S2023: l_c = N l0 with l0 = d = 2a).
fn contour(scene: &toml::Table, key: &str) -> Result<f64, String> {
    let f0 = scene
        .get("fibre")
        .and_then(|f| f.as_array())
        .and_then(|a| a.first())
        .and_then(|f| f.as_table());
    let beads = f0.and_then(|f| f.get("beads")).and_then(|b| b.as_integer());
    let radius = number(f0.and_then(|f| f.get("bead_radius")));
    match (beads, radius) {
        (Some(n), Some(a)) if n > 0 && a.is_finite() && a > 0.0 => Ok(n as f64 * 2.0 * a),
        _ => Err(format!(
            "fluid.{key} is defined on fibre 0's contour l_c = N d (S2023 eq. 18): the scene \
             needs fibre.0.beads and fibre.0.bead_radius"
        )),
    }
}

/// Pairs of keys that set the same thing: a group and the key it stands for. A scene file may
/// give one of each pair; an override (`--set`, a study's `[set]` and `[[vary]]`) of one
/// replaces the other, so that a scene given by its viscosity can be run at a Reynolds
/// number and the other way round.
const PAIRS: [(&str, &str); 5] = [
    ("particle_shear_reynolds", "viscosity"),
    ("confinement", "grid"),
    ("bending_number", "bending_stiffness"),
    ("stretch_number", "stretch_stiffness"),
    // `fibre.N.centred = true` places the fibre at the centre of the gap, whatever the gap.
    ("centred", "start"),
];

/// After the override of `path`: drop the key of its pair (`PAIRS`) from the scene, and say
/// so. `fluid.confinement` keeps the grid's length (`[nx, ny]` becomes `[nx]`); a grid of
/// one size, `[nx]`, keeps the confinement; `centred = false` keeps `start`.
pub fn supersede(scene: &mut toml::Table, path: &str) -> Option<String> {
    let parts: Vec<&str> = path.split('.').collect();
    let (table, key, prefix) = match parts.as_slice() {
        ["fluid", key] => (
            scene.get_mut("fluid")?.as_table_mut()?,
            *key,
            "fluid".to_string(),
        ),
        ["fibre", n, key] => {
            let i: usize = n.parse().ok()?;
            let t = scene
                .get_mut("fibre")?
                .as_array_mut()?
                .get_mut(i)?
                .as_table_mut()?;
            (t, *key, format!("fibre.{n}"))
        }
        _ => return None,
    };
    let other = PAIRS.iter().find_map(|&(g, k)| match key {
        _ if key == g => Some(k),
        _ if key == k => Some(g),
        _ => None,
    })?;
    let line = |what: &str| {
        Some(format!(
            "--set {path} replaces the scene's {prefix}.{other}{what}"
        ))
    };
    match (key, other) {
        ("confinement", "grid") => match table.get_mut("grid") {
            Some(toml::Value::Array(g)) if g.len() > 1 => {
                g.truncate(1);
                line(" gap (fluid.grid keeps nx)")
            }
            _ => None,
        },
        ("centred", _) if table.get("centred").and_then(|c| c.as_bool()) != Some(true) => None,
        ("grid", _) => {
            let full = table
                .get("grid")
                .and_then(|g| g.as_array())
                .is_some_and(|g| g.len() > 1);
            if full && table.remove("confinement").is_some() {
                line("")
            } else {
                None
            }
        }
        _ => table.remove(other).and_then(|_| line("")),
    }
}

/// The `[fluid]` key of S2023's confinement C = l_c / H.
const C: &str = "confinement";

/// Replace `fluid.confinement` and `fluid.particle_shear_reynolds` in `scene` by the keys
/// they set. A scene with neither is left as it is.
pub fn resolve(scene: &mut toml::Table) -> Result<Resolved, String> {
    const RE: &str = "particle_shear_reynolds";
    let mut out = Resolved::default();
    let Some(toml::Value::Table(fluid)) = scene.get("fluid") else {
        return Ok(out);
    };
    let (c, re) = (group_value(fluid, C)?, group_value(fluid, RE)?);
    if c.is_none() && re.is_none() {
        return Ok(out);
    }
    let key = if c.is_some() { C } else { RE };
    let lc = contour(scene, key)?;
    // The rows the walls take: none for FPD (H = ny), two slabs of T for SPM (H = ny - 2 T).
    let margin = cosim::scene_keys::wall_margin(scene);
    // `dimensions` is checked by every node; here only a clear 3D is told apart.
    let two_d = cosim::scene_keys::dimensions(scene).ok().map(|d| d == 2);
    let fluid = scene
        .get_mut("fluid")
        .and_then(|f| f.as_table_mut())
        .expect("checked above");
    let grid: Vec<toml::Value> = match fluid.get("grid") {
        Some(toml::Value::Array(g)) => g.clone(),
        _ => Vec::new(),
    };
    // The gap is checked here, with messages about the groups; `wall_shear` reads it below.
    match c {
        Some(c) => set_gap(fluid, c, lc, margin, two_d, &grid, &mut out)?,
        None => check_gap(&grid, margin)?,
    }
    if let Some(re) = re {
        if fluid.contains_key("viscosity") {
            return Err(
                "fluid.particle_shear_reynolds sets fluid.viscosity = rho gamma l_c^2 / \
                 (4 Re_ps) (S2023 eq. 18): give one of the two, not both"
                    .into(),
            );
        }
        let rho = match fluid.get("density") {
            None => DEFAULT_DENSITY,
            v => number(v)
                .filter(|r| r.is_finite() && *r > 0.0)
                .ok_or("fluid.density: expected a positive number")?,
        };
        // gamma on the gap just set (or given), read as the fibre node reads it for K and K_s.
        let gamma =
            cosim::scene_keys::wall_shear(scene, "fluid.particle_shear_reynolds")?.shear_rate;
        let eta = rho * gamma * lc * lc / (4.0 * re);
        let fluid = scene
            .get_mut("fluid")
            .and_then(|f| f.as_table_mut())
            .expect("checked above");
        fluid.insert("viscosity".into(), toml::Value::Float(eta));
        fluid.remove(RE);
        out.lines.push(format!(
            "fluid.particle_shear_reynolds = {} -> fluid.viscosity = {} (rho gamma l_c^2 \
             / (4 Re_ps), gamma = {})",
            Num(re),
            Sig(eta),
            Sig(gamma)
        ));
    }
    Ok(out)
}

/// `fluid.confinement = C`: set the gap H = l_c / C (S2023 eq. 18) as fluid.grid's second
/// size, on top of the walls' `margin` rows, and say so in `out`.
fn set_gap(
    fluid: &mut toml::Table,
    c: f64,
    lc: f64,
    margin: f64,
    two_d: Option<bool>,
    grid: &[toml::Value],
    out: &mut Resolved,
) -> Result<(), String> {
    if two_d == Some(false) {
        return Err(
            "fluid.confinement sets the gap of a 2D scene (S2023 are 2D): a 3D scene gives \
             fluid.grid = [nx, ny, nz]"
                .into(),
        );
    }
    let nx = match grid {
        [nx] if nx.is_integer() => nx.clone(),
        _ => {
            return Err(format!(
                "fluid.confinement sets the gap H = l_c / C (S2023 eq. 18), so fluid.grid \
                 takes the length alone: grid = [nx] (got {})",
                fluid
                    .get("grid")
                    .map_or("no fluid.grid".to_string(), |g| g.to_string())
            ))
        }
    };
    let exact = lc / c;
    let ny = (exact + margin).round();
    let h = ny - margin;
    if h < 1.0 {
        return Err(format!(
            "fluid.confinement = {}: the gap l_c / C = {} is below one lattice node",
            Num(c),
            Num(exact)
        ));
    }
    // The fluid's smallest grid, named here rather than as a fluid.grid the user never set.
    let min_rows = fluid_node::config::MIN_GRID as f64;
    if ny < min_rows {
        return Err(format!(
            "fluid.confinement = {}: the gap l_c / C = {} (l_c = {lc}) makes fluid.grid = \
             [{nx}, {ny}], below the fluid's {min_rows} rows; expected C at most {}",
            Num(c),
            Num(exact),
            AtMost(lc / (min_rows - margin - 0.5))
        ));
    }
    fluid.insert(
        "grid".into(),
        toml::Value::Array(vec![nx.clone(), toml::Value::Integer(ny as i64)]),
    );
    fluid.remove(C);
    let gap = if margin > 0.0 {
        format!("H = ny - 2 T = {h} = l_c / C")
    } else {
        "H = ny = l_c / C".to_string()
    };
    out.lines.push(format!(
        "fluid.confinement = {} -> fluid.grid = [{nx}, {ny}] ({gap}, l_c = {})",
        Num(c),
        Sig(lc)
    ));
    if (h - exact).abs() > 1e-9 * exact {
        out.notes.push(format!(
            "fluid.confinement = {}: the gap l_c / C = {} is rounded to {h} lattice \
             nodes, so the scene runs at C = {} (the summary's fluid.confinement)",
            Num(c),
            Sig(exact),
            Sig(lc / h)
        ));
    }
    Ok(())
}

/// Re_ps = rho gamma l_c^2 / (4 eta_f) (S2023 eq. 18) of a scene whose groups are resolved;
/// `None` where a key it needs is missing.
fn particle_shear_reynolds(scene: &toml::Table) -> Option<f64> {
    let fluid = scene.get("fluid")?.as_table()?;
    let eta = number(fluid.get("viscosity")).filter(|e| *e > 0.0)?;
    let rho = fluid
        .get("density")
        .map_or(Some(DEFAULT_DENSITY), |d| number(Some(d)))?;
    let gamma = cosim::scene_keys::wall_shear(scene, C).ok()?.shear_rate;
    let lc = contour(scene, C).ok()?;
    Some(rho * gamma * lc * lc / (4.0 * eta))
}

/// The y of the centre of the gap, `(ny - 1) / 2`, and of the midpoint of each fibre the
/// scene places by `start` (index, y), in a scene whose groups are resolved.
fn midpoints(scene: &toml::Table) -> Option<(f64, Vec<(usize, f64)>)> {
    let ny = scene.get("fluid")?.get("grid")?.as_array()?.get(1)?;
    let centre = 0.5 * (number(Some(ny))? - 1.0);
    let fibres = scene.get("fibre")?.as_array()?;
    let placed = fibres
        .iter()
        .enumerate()
        .filter_map(|(n, f)| {
            let f = f.as_table()?;
            let y0 = number(f.get("start")?.as_array()?.get(1))?;
            let beads = f.get("beads")?.as_integer()? as f64;
            let spacing = match f.get("spacing") {
                Some(s) => number(Some(s))?,
                None => 2.0 * number(f.get("bead_radius"))?,
            };
            let dir: Vec<f64> = match f.get("direction") {
                Some(d) => d
                    .as_array()?
                    .iter()
                    .filter_map(|x| number(Some(x)))
                    .collect(),
                None => vec![1.0, 0.0, 0.0],
            };
            let norm = dir.iter().map(|x| x * x).sum::<f64>().sqrt();
            let dy = dir.get(1).copied()? / norm;
            Some((n, y0 + 0.5 * (beads - 1.0) * spacing * dy)).filter(|(_, y)| y.is_finite())
        })
        .collect();
    Some((centre, placed))
}

/// Notes for a scene whose gap an override set through `fluid.confinement`: what the new
/// gap changes that the override did not name. `original` is the scene before its overrides,
/// `scene` after them (both before [`resolve`]); a scene that does not resolve gets no note
/// (resolve's own message follows).
///
/// - With `fluid.viscosity` held, the shear rate follows the gap, and so does Re_ps; S2023
///   vary C at fixed Re_ps (Fig. 10a).
/// - A fibre placed by `start` at the centre of the scene's gap stays where it was, off the
///   centre of the new one (`fibre.N.centred = true` follows the gap).
pub fn confinement_override_notes(original: &toml::Table, scene: &toml::Table) -> Vec<String> {
    let resolved = |t: &toml::Table| {
        let mut t = t.clone();
        resolve(&mut t).ok().map(|_| t)
    };
    let (Some(before), Some(after)) = (resolved(original), resolved(scene)) else {
        return Vec::new();
    };
    let mut notes = Vec::new();
    let given_re = scene
        .get("fluid")
        .is_some_and(|f| f.get("particle_shear_reynolds").is_some());
    if let (Some(was), Some(now), false) = (
        particle_shear_reynolds(&before),
        particle_shear_reynolds(&after),
        given_re,
    ) {
        if (now - was).abs() > 1e-9 * was {
            notes.push(format!(
                "fluid.confinement: the new gap keeps fluid.viscosity, so the shear rate \
                 follows the gap and Re_ps = rho gamma l_c^2 / (4 eta_f) (S2023 eq. 18) is \
                 {} here against {} in the scene; to hold it, give \
                 fluid.particle_shear_reynolds = {} too (S2023 vary C at fixed Re_ps, \
                 Fig. 10a)",
                Sig(now),
                Sig(was),
                Sig(was)
            ));
        }
    }
    if let (Some((old_centre, old)), Some((centre, new))) = (midpoints(&before), midpoints(&after))
    {
        for ((n, was), (_, now)) in old.iter().zip(&new) {
            if (was - old_centre).abs() < 1e-6 && (now - centre).abs() > 1e-6 {
                notes.push(format!(
                    "fibre.{n}.start: the scene placed the fibre's midpoint at the centre of \
                     its gap, y = {}; the new gap's centre is y = {}, and the fibre starts \
                     where it was; set fibre.{n}.centred = true (in place of start) to centre \
                     it in any gap",
                    Num(*was),
                    Num(centre)
                ));
            }
        }
    }
    notes
}

/// Without `fluid.confinement` the scene's own fluid.grid = [nx, ny, ..] must leave a gap
/// between the walls' `margin` rows.
fn check_gap(grid: &[toml::Value], margin: f64) -> Result<(), String> {
    let [_, ny, ..] = grid else {
        return Err(
            "fluid.particle_shear_reynolds needs the gap: fluid.grid = [nx, ny], or \
                    fluid.grid = [nx] with fluid.confinement"
                .into(),
        );
    };
    match number(Some(ny)).map(|ny| ny - margin) {
        Some(h) if h > 0.0 => Ok(()),
        _ => Err(
            "fluid.grid: expected [nx, ny] with positive sizes and a gap between the walls".into(),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// S2023 Fig. 7's scene at d = 8: N = 10 (l_c = 80), walls at -+0.05.
    const FIG7: &str = r#"
dimensions = 2
[fluid]
method = "fpd-lbm"
grid = [200]
confinement = 0.5
particle_shear_reynolds = 1.5
[walls]
velocity = [-0.05, 0.05]
[[fibre]]
beads = 10
bead_radius = 4.0
"#;

    fn table(text: &str) -> toml::Table {
        text.parse().unwrap()
    }

    fn err(text: &str) -> String {
        resolve(&mut table(text)).unwrap_err()
    }

    /// H = l_c / C = 160 and eta_f = rho gamma l_c^2 / (4 Re_ps) with gamma = 0.1 / 160:
    /// 6.25e-4 x 6400 / 6 = 2/3, the values `configs/fpd/flexible_shear.toml` gives by hand.
    #[test]
    fn s2023_fig7_groups_give_the_gap_and_viscosity_of_the_hand_made_scene() {
        let mut t = table(FIG7);
        let r = resolve(&mut t).unwrap();
        let fluid = t["fluid"].as_table().unwrap();
        assert_eq!(fluid["grid"].as_array().unwrap()[1].as_integer(), Some(160));
        let eta = fluid["viscosity"].as_float().unwrap();
        assert!((eta - 2.0 / 3.0).abs() < 1e-15, "{eta}");
        assert!(!fluid.contains_key("confinement"));
        assert!(!fluid.contains_key("particle_shear_reynolds"));
        assert_eq!(r.lines.len(), 2);
        assert!(r.notes.is_empty(), "{:?}", r.notes);
    }

    /// Under SPM the gap is the rows between the wall slabs (H = ny - 2 T): the same groups
    /// give `configs/spm/s2023_fig7_twin.toml`'s 200 x 168 grid with slabs of 4 and FPD's
    /// viscosity 2/3; slabs of 2.5 make a gap of 160 in 165 rows, and C = 0.87 rounds the
    /// rows, not the gap, to whole nodes (ny = 100, H = 92, as FPD's).
    #[test]
    fn spm_groups_count_the_gap_between_the_wall_slabs() {
        let spm = FIG7.replace("fpd-lbm", "spm");
        let mut t = table(&spm);
        let r = resolve(&mut t).unwrap();
        assert_eq!(t["fluid"]["grid"][1].as_integer(), Some(168));
        let eta = t["fluid"]["viscosity"].as_float().unwrap();
        assert!((eta - 2.0 / 3.0).abs() < 1e-15, "{eta}");
        assert!(r.lines[0].contains("ny - 2 T = 160"), "{}", r.lines[0]);
        assert!(r.notes.is_empty(), "{:?}", r.notes);
        let mut t = table(&spm.replace("0.05]\n", "0.05]\nthickness = 2.5\n"));
        resolve(&mut t).unwrap();
        assert_eq!(t["fluid"]["grid"][1].as_integer(), Some(165));
        let mut t = table(&spm.replace("0.5\n", "0.87\n"));
        let r = resolve(&mut t).unwrap();
        assert_eq!(t["fluid"]["grid"][1].as_integer(), Some(100));
        assert!(r.notes[0].contains("rounded to 92"), "{}", r.notes[0]);
        let eta = t["fluid"]["viscosity"].as_float().unwrap();
        let want = 0.1 / 92.0 * 6400.0 / 6.0;
        assert!((eta - want).abs() < 1e-15 * want, "{eta} vs {want}");
    }

    /// S2023's C = 0.87 at l_c = 80: H = 91.95 rounds to 92, C = 0.869565.
    #[test]
    fn a_gap_off_the_lattice_is_rounded_with_a_note() {
        let mut t = table(&FIG7.replace("0.5\n", "0.87\n"));
        let r = resolve(&mut t).unwrap();
        assert_eq!(t["fluid"]["grid"][1].as_integer(), Some(92));
        assert_eq!(r.notes.len(), 1);
        assert!(r.notes[0].contains("0.869565"), "{}", r.notes[0]);
        // The Reynolds number is met on the rounded gap: gamma = 0.1 / 92.
        let eta = t["fluid"]["viscosity"].as_float().unwrap();
        let want = 0.1 / 92.0 * 6400.0 / 6.0;
        assert!((eta - want).abs() < 1e-15 * want, "{eta} vs {want}");
    }

    #[test]
    fn one_group_alone_and_a_scene_without_groups() {
        let mut t = table(&FIG7.replace("particle_shear_reynolds = 1.5\n", "viscosity = 0.5\n"));
        let r = resolve(&mut t).unwrap();
        assert_eq!(r.lines.len(), 1);
        assert_eq!(t["fluid"]["viscosity"].as_float(), Some(0.5));
        let text = FIG7
            .replace("confinement = 0.5\n", "")
            .replace("[200]", "[200, 40]");
        let mut t = table(&text);
        resolve(&mut t).unwrap();
        let eta = t["fluid"]["viscosity"].as_float().unwrap();
        assert!((eta - 0.1 / 40.0 * 6400.0 / 6.0).abs() < 1e-15);
        let plain = FIG7
            .replace("confinement = 0.5\n", "")
            .replace("particle_shear_reynolds = 1.5\n", "");
        let mut t = table(&plain);
        let before = t.clone();
        assert_eq!(resolve(&mut t).unwrap(), Resolved::default());
        assert_eq!(t, before);
    }

    /// `configs/fpd/flexible_shear.toml` is given by its gap and viscosity: overriding its
    /// groups replaces them, and overriding a key back replaces the group.
    #[test]
    fn an_override_of_one_key_of_a_pair_replaces_the_other() {
        let hand = FIG7
            .replace("grid = [200]\n", "grid = [200, 160]\n")
            .replace("confinement = 0.5\n", "")
            .replace(
                "particle_shear_reynolds = 1.5\n",
                "viscosity = 0.6666666666666666\n",
            )
            .replace(
                "bead_radius = 4.0\n",
                "bead_radius = 4.0\nstretch_stiffness = 128.0\n",
            );
        let mut t = table(&hand);
        t["fluid"]
            .as_table_mut()
            .unwrap()
            .insert("confinement".into(), toml::Value::Float(0.87));
        let line = supersede(&mut t, "fluid.confinement").unwrap();
        assert!(line.contains("fluid.grid"), "{line}");
        assert_eq!(t["fluid"]["grid"].as_array().unwrap().len(), 1);
        t["fluid"]
            .as_table_mut()
            .unwrap()
            .insert("particle_shear_reynolds".into(), toml::Value::Float(1.5));
        supersede(&mut t, "fluid.particle_shear_reynolds").unwrap();
        assert!(!t["fluid"].as_table().unwrap().contains_key("viscosity"));
        resolve(&mut t).unwrap();
        assert_eq!(t["fluid"]["grid"][1].as_integer(), Some(92));
        let f0 = t["fibre"][0].as_table_mut().unwrap();
        f0.insert("stretch_number".into(), toml::Value::Float(240.0));
        supersede(&mut t, "fibre.0.stretch_number").unwrap();
        assert!(!t["fibre"][0]
            .as_table()
            .unwrap()
            .contains_key("stretch_stiffness"));
        // Back: a full grid replaces the confinement; a grid of nx alone keeps it.
        let mut t = table(FIG7);
        t["fluid"].as_table_mut().unwrap().insert(
            "grid".into(),
            toml::Value::Array(vec![toml::Value::Integer(100)]),
        );
        assert_eq!(supersede(&mut t, "fluid.grid"), None);
        assert!(t["fluid"].as_table().unwrap().contains_key("confinement"));
        t["fluid"].as_table_mut().unwrap().insert(
            "grid".into(),
            toml::Value::Array(vec![toml::Value::Integer(100), toml::Value::Integer(80)]),
        );
        assert!(supersede(&mut t, "fluid.grid").is_some());
        assert!(!t["fluid"].as_table().unwrap().contains_key("confinement"));
        // A centred fibre drops its start; centred = false keeps it.
        let mut t = table(&FIG7.replace(
            "bead_radius = 4.0\n",
            "bead_radius = 4.0\nstart = [1.0, 2.0, 0.0]\n",
        ));
        let f0 = t["fibre"][0].as_table_mut().unwrap();
        f0.insert("centred".into(), toml::Value::Boolean(false));
        assert_eq!(supersede(&mut t, "fibre.0.centred"), None);
        let f0 = t["fibre"][0].as_table_mut().unwrap();
        f0.insert("centred".into(), toml::Value::Boolean(true));
        assert!(supersede(&mut t, "fibre.0.centred").is_some());
        assert!(!t["fibre"][0].as_table().unwrap().contains_key("start"));
        // Keys outside the pairs are left alone.
        assert_eq!(supersede(&mut t, "fluid.density"), None);
        assert_eq!(supersede(&mut t, "time.dt"), None);
    }

    #[test]
    fn what_cannot_be_resolved_is_named() {
        let e = err(&FIG7.replace("[200]", "[200, 160]"));
        assert!(e.contains("grid = [nx]"), "{e}");
        let e = err(&FIG7.replace("[fluid]\n", "[fluid]\nviscosity = 1.0\n"));
        assert!(e.contains("not both"), "{e}");
        let e = err(&FIG7.replace("dimensions = 2", "dimensions = 3"));
        assert!(e.contains("2D"), "{e}");
        let e = err(&FIG7.replace("[-0.05, 0.05]", "[0.05, 0.05]"));
        assert!(e.contains("shear"), "{e}");
        let e = err(&FIG7.replace("beads = 10\n", ""));
        assert!(e.contains("fibre.0.beads"), "{e}");
        let e = err(&FIG7.replace("= 0.5\n", "= -0.5\n"));
        assert!(
            e.contains("fluid.confinement") && e.contains("positive"),
            "{e}"
        );
        let e = err(&FIG7.replace("confinement = 0.5\n", ""));
        assert!(e.contains("fluid.grid"), "{e}");
    }

    /// A confinement whose gap falls below the fluid's smallest grid names itself and the
    /// largest C that fits, rounded down so that the C quoted passes.
    #[test]
    fn too_large_a_confinement_quotes_one_that_fits() {
        let e = err(&FIG7.replace("confinement = 0.5\n", "confinement = 20.0\n"));
        assert!(e.contains("fluid.confinement = 20"), "{e}");
        let quoted = e.rsplit("expected C at most ").next().unwrap();
        assert!(quoted.parse::<f64>().is_ok(), "{e}");
        let mut t =
            table(&FIG7.replace("confinement = 0.5\n", &format!("confinement = {quoted}\n")));
        resolve(&mut t).unwrap_or_else(|e| panic!("C = {quoted}: {e}"));
    }

    /// `--set fluid.confinement` on a scene given by its viscosity and a fibre's `start` at the
    /// centre of its gap (configs/fpd/flexible_shear.toml: C = 0.5, Re_ps = 1.5, y = 79.5):
    /// the notes name the Re_ps the new gap gives and the centre the fibre misses; with Re_ps
    /// and `centred` set alongside, as docs/validation/fpd_shape_diagram.study.toml does,
    /// there is nothing to note.
    #[test]
    fn a_confinement_override_says_what_the_new_gap_changes_besides() {
        let text = include_str!("../../configs/fpd/flexible_shear.toml");
        let notes = |sets: &[&str]| {
            let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
            crate::scene::from_text(text, "flexible_shear.toml", &sets)
                .unwrap()
                .2
                .notes
        };
        let n = notes(&["fluid.confinement=0.8"]);
        // H = 80 / 0.8 = 100: gamma = 0.1 / 100, Re_ps = 1.5 x 160 / 100 = 2.4.
        assert_eq!(n.len(), 2, "{n:?}");
        assert!(
            n[0].contains("is 2.4 here against 1.5 in the scene"),
            "{}",
            n[0]
        );
        assert!(
            n[1].contains("y = 79.5; the new gap's centre is y = 49.5"),
            "{}",
            n[1]
        );
        let held = notes(&[
            "fluid.confinement=0.8",
            "fluid.particle_shear_reynolds=1.5",
            "fibre.0.centred=true",
        ]);
        assert!(held.is_empty(), "{held:?}");
        assert!(notes(&["fluid.viscosity=0.5"]).is_empty());
    }
}
