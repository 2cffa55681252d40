//! Reading a node's own tables of a scene with errors that name the dotted key: shared by
//! every node so that all of them word bad input the same way.
use serde::Deserialize;

/// Turn a serde error at `path` (relative to `prefix`) into a user message naming the key.
pub fn serde_message(prefix: &str, path: &serde_path_to_error::Path, msg: &str) -> String {
    let mut full = prefix.to_string();
    for seg in path.iter() {
        match seg {
            serde_path_to_error::Segment::Seq { index } => full.push_str(&format!(".{index}")),
            serde_path_to_error::Segment::Map { key } => full.push_str(&format!(".{key}")),
            serde_path_to_error::Segment::Enum { variant } => full.push_str(&format!(".{variant}")),
            serde_path_to_error::Segment::Unknown => {}
        }
    }
    // toml appends "in `key`" lines; the first line is serde's message.
    let msg = msg.lines().next().unwrap_or("").trim_end();
    let quoted = msg.split('`').nth(1).unwrap_or("");
    if let Some(unknown) = unknown_key(msg) {
        // The path ends at the key itself; report the table holding it.
        let table = full
            .strip_suffix(&format!(".{quoted}"))
            .unwrap_or(&full)
            .to_string();
        return format!("{table}: {unknown}");
    }
    if msg.starts_with("missing field ") {
        return format!("{full}.{quoted} is required and missing");
    }
    format!("{full}: {}", plain_words(msg))
}

/// serde's and toml's wording of a value of the wrong kind in plain words, expected first:
/// "invalid type: floating point `1.5`, expected u64 in `time.steps`" reads "expected a whole
/// number (0 or more), got 1.5"; "invalid type: map, expected a sequence" reads "expected an
/// array, got a table". Any other message is returned as it is (its first line, without
/// toml's trailing "in `key`", which the caller names).
pub fn plain_words(msg: &str) -> String {
    let (msg, at) = message_line(msg);
    let plain = plain_words_of_line(msg);
    match at {
        Some(at) => format!("{plain} ({at})"),
        None => plain,
    }
}

/// The line of a serde or toml error that says what is wrong, and where in the file when
/// toml says (its span-aware errors open with "TOML parse error at line L, column C" and an
/// excerpt of the file, the message last).
pub fn message_line(msg: &str) -> (&str, Option<&str>) {
    let first = msg.lines().next().unwrap_or("").trim_end();
    match first.strip_prefix("TOML parse error at ") {
        Some(at) => (
            msg.lines()
                .rev()
                .map(str::trim_end)
                .find(|l| !l.is_empty())
                .unwrap_or(first),
            Some(at),
        ),
        None => (first, None),
    }
}

fn plain_words_of_line(msg: &str) -> String {
    let msg = match msg.rfind(" in `") {
        Some(i) if msg.ends_with('`') => &msg[..i],
        _ => msg,
    };
    let kind = |e: &str| -> String {
        match e {
            "u8" | "u16" | "u32" | "u64" | "usize" => "a whole number (0 or more)".into(),
            "i8" | "i16" | "i32" | "i64" | "isize" | "an integer" => "a whole number".into(),
            "f32" | "f64" => "a number".into(),
            "a sequence" => "an array".into(),
            "a map" => "a table".into(),
            "a boolean" => "true or false".into(),
            "an array of length 3" => "[x, y, z]".into(),
            e if e.starts_with("struct ") => "a table".into(),
            e => e.into(),
        }
    };
    let value = |g: &str| -> String {
        let quoted = |prefix: &str| {
            g.strip_prefix(prefix)
                .and_then(|r| r.strip_prefix('`'))
                .and_then(|r| r.strip_suffix('`'))
                .map(str::to_string)
        };
        if let Some(v) = quoted("floating point ")
            .or_else(|| quoted("integer "))
            .or_else(|| quoted("boolean "))
        {
            return v;
        }
        match g {
            "map" => "a table".into(),
            "sequence" => "an array".into(),
            g => match g.strip_prefix("string ") {
                Some(text) => format!("the text {text}"),
                None => g.into(),
            },
        }
    };
    let body = msg
        .strip_prefix("invalid type: ")
        .or_else(|| msg.strip_prefix("invalid value: "));
    if let Some((got, expected)) = body.and_then(|b| b.rsplit_once(", expected ")) {
        let (expected, got) = (kind(expected), value(got));
        // A number in quotes is text.
        let numeric = expected.contains("number") || expected.starts_with('[');
        let hint = if numeric && got.starts_with("the text ") {
            " (numbers are written without quotes)".to_string()
        } else if expected.starts_with("a whole number")
            && got.parse::<f64>().is_ok_and(|x| x.fract() == 0.0)
            && got.contains(['.', 'e', 'E'])
        {
            // 4.5e4 or 100.0 reads as a float in TOML.
            " (a float: write it without a decimal point or exponent)".to_string()
        } else {
            String::new()
        };
        return format!("expected {expected}, got {got}{hint}");
    }
    if let Some((n, expected)) = msg
        .strip_prefix("invalid length ")
        .and_then(|b| b.split_once(", expected "))
    {
        return format!("expected {}, got {n} values", kind(expected));
    }
    msg.to_string()
}

/// serde's "unknown field `foo`, expected one of `a`, `b`" as "unknown key `foo` (expected
/// one of `a`, `b`)", with a guess at the key meant ([`did_you_mean`]); `None` for any
/// other message. The first line of `msg` that is such a message counts (toml puts an
/// excerpt of the file before it, or the key after it).
pub fn unknown_key(msg: &str) -> Option<String> {
    msg.lines().find_map(|l| unknown_field_line(l.trim_end()))
}

fn unknown_field_line(msg: &str) -> Option<String> {
    let (word, rest) = msg.strip_prefix("unknown field `")?.split_once('`')?;
    let expected = rest.strip_prefix(", expected ");
    let hint = expected.map_or_else(String::new, |e| {
        did_you_mean(word, e.split('`').skip(1).step_by(2))
    });
    let expected = expected
        .map(|e| format!(" (expected {e})"))
        .unwrap_or_default();
    Some(format!("unknown key `{word}`{hint}{expected}"))
}

/// `, did you mean `KEY`?` for the candidate a mistyped `word` most likely meant, else
/// nothing: the closest by optimal string alignment distance (a swap of two neighbours
/// counts once), if at most a third of the word's length (at least 1) away; failing that,
/// the shortest candidate the word begins (a word of four letters or more, such as
/// `tumbling_period` for `tumbling_period_gamma`). The first of equally good ones.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    let letters = word.chars().count();
    let allowed = (letters / 3).max(1);
    let mut closest: Option<(usize, &str)> = None;
    let mut completion: Option<&str> = None;
    for c in candidates {
        let d = strsim::osa_distance(word, c);
        if d <= allowed && closest.is_none_or(|(b, _)| d < b) {
            closest = Some((d, c));
        }
        if letters >= 4 && c.starts_with(word) && completion.is_none_or(|b| c.len() < b.len()) {
            completion = Some(c);
        }
    }
    closest
        .map(|(_, c)| c)
        .or(completion)
        .map_or_else(String::new, |c| format!(", did you mean `{c}`?"))
}

/// Deserialize the table `v` found at the dotted path `prefix`.
pub fn deserialize_at<T: for<'de> Deserialize<'de>>(
    prefix: &str,
    v: toml::Value,
) -> Result<T, String> {
    serde_path_to_error::deserialize(v).map_err(|e| {
        let path = e.path().clone();
        let inner = e.into_inner();
        serde_message(prefix, &path, &inner.to_string())
    })
}

/// A TOML value as a user reads it in a message.
pub fn describe_value(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("the string {s:?}"),
        toml::Value::Table(_) => "a table".into(),
        toml::Value::Array(_) => "an array".into(),
        // Very large or small numbers with an exponent, not hundreds of digits.
        toml::Value::Float(x) if Num::needs_exponent(*x) => Num(*x).to_string(),
        other => other.to_string(),
    }
}

/// A number as a message shows it: as `Display` writes it (`6`, `0.25`, `-1`), except
/// that magnitudes from 1e16 up or below 1e-5 are written with an exponent (`1e300`,
/// `-2.5e-7`) rather than as hundreds of digits. A precision applies to either form
/// (`{:.3}`: `0.125`, `1.000e300`); a width or alignment does not (format into a string
/// first to pad it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Num(pub f64);

impl Num {
    /// Whether `x` is written with an exponent.
    fn needs_exponent(x: f64) -> bool {
        let a = x.abs();
        a.is_finite() && (a >= 1e16 || (a > 0.0 && a < 1e-5))
    }
}

impl std::fmt::Display for Num {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (Self::needs_exponent(self.0), f.precision()) {
            (true, Some(p)) => write!(f, "{:.*e}", p, self.0),
            (true, None) => write!(f, "{:e}", self.0),
            (false, Some(p)) => write!(f, "{:.*}", p, self.0),
            (false, None) => write!(f, "{}", self.0),
        }
    }
}

/// A computed number as a report shows it: seven significant digits with the trailing
/// zeros dropped, written plainly from 1e-3 to below 1e7 (`108`, `0.6976744`, `1`) and with
/// an exponent outside (`1.388837e-4`, `6.02e23`). A width or precision does not apply.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sig(pub f64);

impl std::fmt::Display for Sig {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() {
            return write!(f, "{}", if x == 0.0 { 0.0 } else { x });
        }
        // The exponent after rounding to seven digits (9.9999996 rounds to 1.000000e1).
        let e = format!("{x:.6e}");
        let (mantissa, exp) = e.split_once('e').unwrap_or((&e, "0"));
        let exp: i32 = exp.parse().unwrap_or(0);
        let trim = |t: &str| -> String {
            if t.contains('.') {
                t.trim_end_matches('0').trim_end_matches('.').to_string()
            } else {
                t.to_string()
            }
        };
        if (-3..7).contains(&exp) {
            let decimals = (6 - exp) as usize;
            write!(f, "{}", trim(&format!("{x:.decimals$}")))
        } else {
            write!(f, "{}e{exp}", trim(mantissa))
        }
    }
}

/// A bound a message quotes for the user to set ("lower time.dt to at most ..."), as [`Sig`]
/// writes it but rounded down at its seventh significant digit, so that the value quoted
/// passes the check it comes from (rounded to nearest, 0.011344917 would read 0.01134492,
/// just above the bound).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtMost(pub f64);

/// [`AtMost`] for a lower bound ("raise ... to at least ..."): rounded up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AtLeast(pub f64);

/// `x` as [`Sig`] writes it, rounded towards minus infinity (`up`: plus infinity) at its
/// seventh significant digit: the nearest seven-digit value if it reads back on the right
/// side of `x` (so that a short value such as 0.005 reads as itself), else the next one
/// towards the bound, each checked by reading the text back.
fn bound_text(x: f64, up: bool) -> String {
    if x == 0.0 || !x.is_finite() {
        return Sig(x).to_string();
    }
    let p = 10f64.powi(x.abs().log10().floor() as i32 - 6);
    let scaled = x / p;
    let (towards, beyond) = if up {
        (scaled.ceil(), scaled.ceil() + 1.0)
    } else {
        (scaled.floor(), scaled.floor() - 1.0)
    };
    for whole in [scaled.round(), towards, beyond] {
        let text = Sig(whole * p).to_string();
        let back: f64 = text.parse().unwrap_or(f64::NAN);
        if (up && back >= x) || (!up && back <= x) {
            return text;
        }
    }
    Sig(x).to_string()
}

impl std::fmt::Display for AtMost {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", bound_text(self.0, false))
    }
}

impl std::fmt::Display for AtLeast {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", bound_text(self.0, true))
    }
}

/// Numbers as a message shows them, `[a, b, c]` (each as [`Num`]).
pub struct Nums<'a>(pub &'a [f64]);

impl std::fmt::Display for Nums<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[")?;
        for (i, &x) in self.0.iter().enumerate() {
            if i > 0 {
                write!(f, ", ")?;
            }
            write!(f, "{}", Num(x))?;
        }
        write!(f, "]")
    }
}

/// `v` if it is a finite positive number, else a message naming `path`.
pub fn positive(path: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!(
            "{path}: expected a positive number, got {}",
            Num(v)
        ))
    }
}

/// The scene's text parsed as TOML.
pub fn parse_table(scene_toml: &str) -> Result<toml::Table, String> {
    scene_toml
        .parse()
        .map_err(|e: toml::de::Error| format!("the scene is not valid TOML: {e}"))
}

/// A whole number of dimensions: 2 or 3, else what was expected (the coordinator and the
/// nodes word it alike).
pub fn two_or_three(n: i64) -> Result<u8, String> {
    match n {
        2 | 3 => Ok(n as u8),
        _ => Err(format!("expected 2 or 3, got {n}")),
    }
}

/// The top-level `dimensions` every node reads: 2 or 3, default 3.
pub fn dimensions(table: &toml::Table) -> Result<u8, String> {
    match table.get("dimensions") {
        None => Ok(3),
        Some(toml::Value::Integer(n)) => two_or_three(*n).map_err(|e| format!("dimensions: {e}")),
        Some(v) => Err(format!(
            "dimensions: expected 2 or 3, got {}",
            describe_value(v)
        )),
    }
}

/// The `time.dt` every node reads: required, positive.
pub fn time_step(table: &toml::Table) -> Result<f64, String> {
    match table.get("time") {
        None => Err("time.dt is required and missing (no [time] table)".into()),
        Some(toml::Value::Table(t)) => match t.get("dt") {
            None => Err("time.dt is required and missing".into()),
            Some(toml::Value::Float(x)) => positive("time.dt", *x),
            Some(toml::Value::Integer(i)) => positive("time.dt", *i as f64),
            Some(v) => Err(format!(
                "time.dt: expected a positive number, got {}",
                describe_value(v)
            )),
        },
        Some(v) => Err(format!("time: expected a table, got {}", describe_value(v))),
    }
}

/// Default `walls.thickness` of the SPM wall slabs, grid units.
pub const DEFAULT_WALL_THICKNESS: f64 = 4.0;

/// The plane Couette flow a scene's walls drive, read where S2023's groups are defined on it
/// (C = l_c / H, Re_ps, K, K_s; S2023 eq. 18 and section II C).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallShear {
    /// Fluid gap H between the walls (grid units): see [`wall_margin`].
    pub gap: f64,
    /// Shear rate gamma = |top - bottom| / H (1 / time).
    pub shear_rate: f64,
    /// Wall speed V0 = |top - bottom| / 2 (S2023 section IV A: walls at -V0 and V0).
    pub wall_speed: f64,
}

/// How much of the grid's `ny` the walls take, `ny - H`: nothing for `fluid.method =
/// "fpd-lbm"` (bounce-back walls at y = -1/2 and ny - 1/2), two slabs of `walls.thickness`
/// (default [`DEFAULT_WALL_THICKNESS`]) for SPM. Read, not validated: the fluid node checks
/// these keys itself.
pub fn wall_margin(table: &toml::Table) -> f64 {
    slab_thickness(table).map_or(0.0, |t| 2.0 * t)
}

/// `walls.thickness` (default [`DEFAULT_WALL_THICKNESS`]) of an SPM scene; `None` for
/// `fluid.method = "fpd-lbm"`, whose walls are the lattice's edges.
fn slab_thickness(table: &toml::Table) -> Option<f64> {
    let fpd = table
        .get("fluid")
        .and_then(|f| f.get("method"))
        .and_then(|m| m.as_str())
        == Some("fpd-lbm");
    (!fpd).then(|| {
        table
            .get("walls")
            .and_then(|w| w.get("thickness"))
            .and_then(number)
            .unwrap_or(DEFAULT_WALL_THICKNESS)
    })
}

/// y of the inner faces (phi = 1/2) of SPM's two wall slabs of thickness `t` in a grid of
/// `ny` rows: halfway between nodes, `T - 1/2` and `ny - T - 1/2` (fluid-node `walls`).
pub fn slab_faces(ny: f64, t: f64) -> [f64; 2] {
    [t - 0.5, ny - t - 0.5]
}

/// y of FPD's half-way bounce-back walls on a lattice of `ny` rows: half a spacing outside
/// the first and the last row.
pub fn bounce_back_faces(ny: f64) -> [f64; 2] {
    [-0.5, ny - 0.5]
}

/// y of the bottom and the top wall's face of a scene with `[walls]` ([`slab_faces`] under
/// SPM, [`bounce_back_faces`] under FPD); `None` without walls or without `fluid.grid`'s
/// ny. Read, not validated, as [`wall_margin`].
pub fn wall_faces(table: &toml::Table) -> Option<[f64; 2]> {
    if !table.contains_key("walls") {
        return None;
    }
    let ny = table
        .get("fluid")
        .and_then(|f| f.get("grid"))
        .and_then(|g| g.as_array())
        .and_then(|g| g.get(1))
        .and_then(number)?;
    Some(match slab_thickness(table) {
        Some(t) => slab_faces(ny, t),
        None => bounce_back_faces(ny),
    })
}

/// A TOML number, integer or float.
pub fn number(v: &toml::Value) -> Option<f64> {
    v.as_float().or_else(|| v.as_integer().map(|i| i as f64))
}

/// The scene's [`WallShear`], or a message saying which key `need` (the key asking for it,
/// e.g. `fibre.0.bending_number`) is missing. Read, not validated, as [`wall_margin`].
pub fn wall_shear(table: &toml::Table, need: &str) -> Result<WallShear, String> {
    let ny = table
        .get("fluid")
        .and_then(|f| f.get("grid"))
        .and_then(|g| g.as_array())
        .and_then(|g| g.get(1))
        .and_then(number)
        .ok_or(format!(
            "{need} needs fluid.grid = [nx, ny] (the gap between the walls)"
        ))?;
    let margin = wall_margin(table);
    let gap = ny - margin;
    if !(gap > 0.0) {
        return Err(format!(
            "{need} needs a fluid gap between the walls: fluid.grid's ny = {ny} leaves {gap}"
        ));
    }
    let walls = table
        .get("walls")
        .and_then(|w| w.get("velocity"))
        .and_then(|v| v.as_array())
        .map(|v| v.iter().filter_map(number).collect::<Vec<_>>());
    match walls.as_deref() {
        Some([b, t]) if t != b && (t - b).is_finite() => Ok(WallShear {
            gap,
            shear_rate: (t - b).abs() / gap,
            wall_speed: 0.5 * (t - b).abs(),
        }),
        _ => Err(format!(
            "{need} needs a shear: walls.velocity = [bottom, top] with different speeds"
        )),
    }
}

#[cfg(test)]
mod wall_shear_tests {
    use super::*;

    const SPM: &str =
        "[fluid]\nmethod = \"spm\"\ngrid = [200, 168]\n[walls]\nvelocity = [-0.05, 0.05]\n";

    /// The same gap of 160 as FPD's 160-node lattice and SPM's 168 rows less two slabs of 4.
    #[test]
    fn the_gap_is_the_lattice_for_fpd_and_the_rows_between_the_slabs_for_spm() {
        let spm = parse_table(SPM).unwrap();
        let fpd =
            parse_table(&SPM.replace("\"spm\"", "\"fpd-lbm\"").replace("168", "160")).unwrap();
        for t in [&spm, &fpd] {
            let s = wall_shear(t, "k").unwrap();
            assert_eq!(s.gap, 160.0);
            assert_eq!(s.wall_speed, 0.05);
            assert!((s.shear_rate - 0.1 / 160.0).abs() < 1e-18);
        }
        assert_eq!(wall_margin(&spm), 8.0);
        assert_eq!(wall_margin(&fpd), 0.0);
        let thick = parse_table(&format!("{SPM}thickness = 9\n")).unwrap();
        assert_eq!(wall_shear(&thick, "k").unwrap().gap, 150.0);
        // The faces the gap lies between.
        assert_eq!(wall_faces(&spm), Some([3.5, 163.5]));
        assert_eq!(wall_faces(&fpd), Some([-0.5, 159.5]));
        assert_eq!(wall_faces(&thick), Some([8.5, 158.5]));
        let open = parse_table("[fluid]\nmethod = \"spm\"\ngrid = [200, 168]\n").unwrap();
        assert_eq!(wall_faces(&open), None);
    }

    #[test]
    fn a_missing_shear_or_gap_is_named() {
        let still = parse_table(&SPM.replace("-0.05", "0.05")).unwrap();
        assert!(wall_shear(&still, "fibre.0.bending_number")
            .unwrap_err()
            .contains("fibre.0.bending_number needs a shear"));
        let flat = parse_table(&SPM.replace("[200, 168]", "[200]")).unwrap();
        assert!(wall_shear(&flat, "k")
            .unwrap_err()
            .contains("fluid.grid = [nx, ny]"));
        let thin = parse_table(&SPM.replace("168", "8")).unwrap();
        assert!(wall_shear(&thin, "k").unwrap_err().contains("leaves 0"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const KEYS: [&str; 5] = [
        "beads",
        "bead_radius",
        "force",
        "time",
        "tumbling_period_gamma",
    ];

    #[test]
    fn a_near_miss_gets_the_key_it_most_likely_meant() {
        assert_eq!(did_you_mean("bead", KEYS), ", did you mean `beads`?");
        assert_eq!(did_you_mean("forse", KEYS), ", did you mean `force`?");
        assert_eq!(did_you_mean("tiem", KEYS), ", did you mean `time`?");
        assert_eq!(
            did_you_mean("bead_raduis", KEYS),
            ", did you mean `bead_radius`?"
        );
    }

    #[test]
    fn a_word_far_from_every_key_gets_no_guess() {
        assert_eq!(did_you_mean("foo", KEYS), "");
        assert_eq!(did_you_mean("colour", KEYS), "");
        assert_eq!(did_you_mean("x", KEYS), "");
        // `tu` begins `tumbling_period_gamma` but is too short to be completed.
        assert_eq!(did_you_mean("tu", KEYS), "");
    }

    #[test]
    fn the_unknown_key_message_names_the_guess_before_the_list() {
        #[derive(Deserialize, Debug)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct Fibre {
            beads: i64,
        }
        let v: toml::Value = toml::from_str("bead = 3").unwrap();
        let e = deserialize_at::<Fibre>("fibre.0", v).unwrap_err();
        assert_eq!(
            e,
            "fibre.0: unknown key `bead`, did you mean `beads`? (expected `beads`)"
        );
    }

    #[test]
    fn numbers_in_messages_are_short_at_any_magnitude() {
        let shown = |x: f64| Num(x).to_string();
        for (x, text) in [
            (6.0, "6"),
            (-1.0, "-1"),
            (0.25, "0.25"),
            (0.0, "0"),
            (1.5e15, "1500000000000000"),
            (1e16, "1e16"),
            (-1e300, "-1e300"),
            (1e-300, "1e-300"),
            (2.5e-7, "2.5e-7"),
            (1e-5, "0.00001"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
        ] {
            assert_eq!(shown(x), text, "{x:e}");
        }
        assert_eq!(Nums(&[1e300, 0.0, -2.0]).to_string(), "[1e300, 0, -2]");
        let sig = |x: f64| Sig(x).to_string();
        for (x, text) in [
            (108.0, "108"),
            (1.0, "1"),
            (0.0, "0"),
            (-0.0, "0"),
            (224.9506123, "224.9506"),
            (0.697674418, "0.6976744"),
            (1.388837e-4, "1.388837e-4"),
            (0.001, "0.001"),
            (9.9999996, "10"),
            (9_999_999.6, "1e7"),
            (1234567.0, "1234567"),
            (-6.02e23, "-6.02e23"),
            (f64::INFINITY, "inf"),
        ] {
            assert_eq!(sig(x), text, "{x:e}");
        }
        assert_eq!(format!("{:.3}", Num(0.125)), "0.125");
        assert_eq!(format!("{:.3}", Num(1e300)), "1.000e300");
        assert_eq!(
            positive("fluid.xi", -1e300).unwrap_err(),
            "fluid.xi: expected a positive number, got -1e300"
        );
    }

    #[test]
    fn serde_words_become_plain_words() {
        for (msg, plain) in [
            (
                "invalid type: floating point `1.5`, expected u64 in `time.steps`",
                "expected a whole number (0 or more), got 1.5",
            ),
            (
                "invalid value: integer `-3`, expected u64",
                "expected a whole number (0 or more), got -3",
            ),
            (
                "invalid type: string \"100\", expected u64",
                "expected a whole number (0 or more), got the text \"100\" (numbers are \
                 written without quotes)",
            ),
            (
                "invalid type: integer `3`, expected struct TimeConfig",
                "expected a table, got 3",
            ),
            (
                "invalid type: map, expected a sequence",
                "expected an array, got a table",
            ),
            (
                "invalid type: string \"x\", expected f64",
                "expected a number, got the text \"x\" (numbers are written without quotes)",
            ),
            (
                "invalid type: string \"tip\", expected a sequence",
                "expected an array, got the text \"tip\"",
            ),
            (
                "invalid length 2, expected [x, y, z]",
                "expected [x, y, z], got 2 values",
            ),
            (
                "invalid type: integer `1`, expected a boolean",
                "expected true or false, got 1",
            ),
            ("something else entirely", "something else entirely"),
            (
                "invalid type: floating point `45000.0`, expected u64",
                "expected a whole number (0 or more), got 45000.0 (a float: write it without a \
                 decimal point or exponent)",
            ),
            (
                "TOML parse error at line 19, column 1\n   |\n19 | [vary]\n   | ^^^^^^\n\
                 invalid type: map, expected a sequence\n",
                "expected an array, got a table (line 19, column 1)",
            ),
        ] {
            assert_eq!(plain_words(msg), plain, "{msg}");
        }
    }

    /// A quoted bound passes its check: at most x reads at or below x, at least x at or
    /// above, with seven significant digits; a value with seven digits or fewer reads as is.
    #[test]
    fn quoted_bounds_pass_their_checks() {
        assert_eq!(AtMost(0.011344917).to_string(), "0.01134491");
        assert_eq!(AtLeast(0.011344911).to_string(), "0.01134492");
        assert_eq!(AtMost(0.005).to_string(), "0.005");
        assert_eq!(AtLeast(0.1).to_string(), "0.1");
        assert_eq!(AtMost(1.3e-5).to_string(), "1.3e-5");
        assert_eq!(AtMost(-2.0000004).to_string(), "-2.000001");
        assert_eq!(AtMost(0.0).to_string(), "0");
        assert_eq!(AtMost(f64::INFINITY).to_string(), "inf");
        let mut x = 0.7f64;
        for _ in 0..10_000 {
            // A deterministic spread over many decades.
            x = (x * 7919.0 + 0.123456789).fract();
            let v = x * 10f64.powi((x * 1e6) as i32 % 40 - 20);
            let down: f64 = AtMost(v).to_string().parse().unwrap();
            let up: f64 = AtLeast(v).to_string().parse().unwrap();
            assert!(down <= v && up >= v, "{v:e}: {down:e} {up:e}");
            assert!((v - down) <= 1.1e-6 * v && (up - v) <= 1.1e-6 * v, "{v:e}");
        }
    }
}
