//! Bad input ends with one clear message naming the key or path, a non-zero exit code and
//! no panic trace.
mod common;
use common::*;

fn write_scene(name: &str, text: &str) -> std::path::PathBuf {
    let dir = out_dir(&format!("bad-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

const GOOD: &str = r#"
dimensions = 2
[time]
dt = 0.005
steps = 10
[[fibre]]
model = "cohesive-beam"
beads = 5
bead_radius = 1.0
youngs_modulus = 1.0e4
clamp = [0]
"#;

fn expect_error(args: &[&str], needles: &[&str]) {
    let o = coordinator(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "expected failure for {args:?}, got success"
    );
    assert!(!err.contains("panicked"), "panic for {args:?}: {err}");
    assert!(
        err.starts_with("error: "),
        "no clear error for {args:?}: {err}"
    );
    for n in needles {
        assert!(err.contains(n), "message for {args:?} lacks `{n}`: {err}");
    }
}

fn check(name: &str, text: &str, needles: &[&str]) {
    let p = write_scene(name, text);
    expect_error(&["check", p.to_str().unwrap()], needles);
}

#[test]
fn the_good_scene_passes() {
    let p = write_scene("good", GOOD);
    let o = coordinator(&["check", p.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn unknown_top_level_key() {
    check("unknown-top", &format!("colour = 3\n{GOOD}"), &["colour"]);
}

/// A mistyped key is answered with the key it most likely meant, whoever reads it: the
/// coordinator (`time`), the fibre node (`fibre.N`), the fluid node (`fluid`), or `--set`.
#[test]
fn a_mistyped_key_gets_a_guess() {
    check(
        "typo-time",
        &GOOD.replace("steps = 10", "step = 10"),
        &["key `time.step`: unknown key `step`, did you mean `steps`?"],
    );
    check(
        "typo-fibre",
        &GOOD.replace("youngs_modulus", "youngs_modulu"),
        &["fibre.0: unknown key `youngs_modulu`, did you mean `youngs_modulus`?"],
    );
    check(
        "typo-fluid",
        "dimensions = 2\n[time]\ndt = 0.1\nsteps = 10\n\
         [fluid]\nmethod = \"spm\"\ngrid = [32, 32]\nviscosty = 1.0\n",
        &["fluid.viscosty: unknown key (set to 1.0), did you mean `viscosity`?"],
    );
    check(
        "typo-metric",
        &format!("{GOOD}[analysis]\nmetrics = [\"tip_deflection\"]\n"),
        &["unknown metric `tip_deflection`, did you mean `tip_deflection_over_length`?"],
    );
    let scene = write_scene("typo-study", GOOD);
    let study = scene.with_file_name("typo.study.toml");
    std::fs::write(
        &study,
        "name = \"typo\"\nscene = \"scene.toml\"\nmetrik = \"tip_rotation\"\n",
    )
    .unwrap();
    expect_error(
        &["study", study.to_str().unwrap(), "--check"],
        &["unknown key `metrik`, did you mean `metric`?"],
    );
    let p = write_scene("typo-set", GOOD);
    expect_error(
        &["check", p.to_str().unwrap(), "--set", "tiem.steps=3"],
        &["the scene has no `tiem`, did you mean `time`?"],
    );
}

#[test]
fn unknown_fibre_key() {
    check(
        "unknown-fibre",
        &GOOD.replace("clamp = [0]", "clamp = [0]\nstiffnes = 3"),
        &["fibre.0", "stiffnes"],
    );
}

#[test]
fn wrong_type() {
    check(
        "wrong-type",
        &GOOD.replace("beads = 5", "beads = \"five\""),
        &["fibre.0.beads"],
    );
    check(
        "wrong-type-time",
        &GOOD.replace("steps = 10", "steps = 1.5"),
        &["time.steps"],
    );
}

#[test]
fn negative_radius() {
    check(
        "negative-radius",
        &GOOD.replace("bead_radius = 1.0", "bead_radius = -1.0"),
        &["fibre.0.bead_radius", "-1"],
    );
}

#[test]
fn zero_beads() {
    check(
        "zero-beads",
        &GOOD.replace("beads = 5", "beads = 0"),
        &["fibre.0.beads"],
    );
}

#[test]
fn clamp_out_of_range() {
    check(
        "clamp-range",
        &GOOD.replace("clamp = [0]", "clamp = [7]"),
        &["fibre.0.clamp", "7"],
    );
}

#[test]
fn time_step_above_the_stability_limit() {
    check(
        "unstable-dt",
        &GOOD.replace("dt = 0.005", "dt = 0.5"),
        &["time.dt", "stiffness"],
    );
}

/// A stiffness so large that the frequency estimate overflows: no time step to quote, so
/// the refusal names the key instead of "lower time.dt to at most 0".
#[test]
fn stiffness_beyond_any_time_step() {
    check(
        "overflowing-stiffness",
        &GOOD.replace("youngs_modulus = 1.0e4", "youngs_modulus = 1e300"),
        &["too stiff for any time step", "fibre.0.youngs_modulus"],
    );
    // A bead-spring chain: the keys its constants come from, as its table gives them.
    let bead_spring = GOOD.replace("cohesive-beam", "bead-spring");
    check(
        "overflowing-bead-spring-modulus",
        &bead_spring.replace("youngs_modulus = 1.0e4", "youngs_modulus = 1e300"),
        &["lower its stiffness (fibre.0.youngs_modulus)"],
    );
    check(
        "overflowing-bead-spring-spring",
        &format!("{bead_spring}stretch_stiffness = 1e300\n"),
        &["lower its stiffness (fibre.0.stretch_stiffness and fibre.0.youngs_modulus)"],
    );
}

#[test]
fn set_path_that_does_not_exist() {
    let p = write_scene("set-path", GOOD);
    expect_error(
        &["check", p.to_str().unwrap(), "--set", "fibre.3.beads=4"],
        &["fibre.3"],
    );
    expect_error(
        &["check", p.to_str().unwrap(), "--set", "nothing.here=4"],
        &["nothing"],
    );
    expect_error(
        &["check", p.to_str().unwrap(), "--set", "fibre.0.beads"],
        &["PATH=VALUE"],
    );
}

#[test]
fn unreadable_file() {
    expect_error(
        &["check", "/nonexistent/scene.toml"],
        &["/nonexistent/scene.toml"],
    );
}

#[test]
fn not_toml() {
    check("not-toml", "this is [ not toml", &["TOML"]);
}

#[test]
fn unwritable_out() {
    let p = write_scene("unwritable", GOOD);
    let blocker = p.parent().unwrap().join("a-file");
    std::fs::write(&blocker, b"x").unwrap();
    let out = blocker.join("sub");
    expect_error(
        &[
            "run",
            p.to_str().unwrap(),
            "--in-process",
            "--quiet",
            "--out",
            out.to_str().unwrap(),
        ],
        &["--out"],
    );
}

/// The fluid node provides `capillarity` now (the only effect a scene could ask for that no
/// component provided), so an empty `[fluid.binary]` reaches the fluid node, which names
/// the missing key.
/// The SPM scenes below give GOOD's radius-1 beads a thin profile (`fluid.xi = 0.1`), or
/// the fibre node would refuse them first as too light for the explicit exchange.
#[test]
fn an_incomplete_binary_fluid_is_refused_by_the_fluid_node() {
    check(
        "binary-fluid",
        &format!(
            "{GOOD}\n[fluid]\nmethod = \"spm\"\ngrid = [16, 16]\nviscosity = 1.0\nxi = 0.1\n[fluid.binary]\n"
        ),
        &["fluid.binary.initial", "is required and missing"],
    );
}

#[test]
fn fluid_keys_are_checked_by_the_fluid_node() {
    check(
        "fluid-no-grid",
        &format!("{GOOD}\n[fluid]\nmethod = \"spm\"\nviscosity = 1.0\nxi = 0.1\n"),
        &["fluid.grid"],
    );
    check(
        "fluid-method",
        &format!("{GOOD}\n[fluid]\nmethod = \"lbm\"\n"),
        &["fluid.method", "lbm"],
    );
}

/// A profile cut-off far beyond the grid is refused, promptly: it once made the fibre node's
/// profile integrals overflow, and its stiffness check then iterated on NaN for minutes.
#[test]
fn a_huge_profile_cut_off_is_refused() {
    let scene = config("spm/tumbling.toml");
    expect_error(
        &[
            "check",
            scene.to_str().unwrap(),
            "--set",
            "fluid.xi_cutoff=1e300",
        ],
        &["fluid.xi_cutoff"],
    );
}

/// A metric that cannot be computed (here: a tumbling period from a run too short to pass
/// the vertical twice) does not fail the finished run: the run completes, exits 0, keeps the
/// other metrics, and names the missing one with the reason in the output and in the
/// summary's `metric_errors`.
#[test]
fn a_metric_that_cannot_be_computed_does_not_fail_the_run() {
    let out = out_dir("metric-not-computed");
    let cfg = config("spm/jeffery_rigid.toml");
    let o = coordinator(&[
        "run",
        cfg.to_str().unwrap(),
        "--in-process",
        "--quiet",
        "--set",
        "time.steps=20",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        text.contains("tumbling_period_gamma: not computed: metric `tumbling_period_gamma`: fibre 0 did not pass the vertical twice; run longer"),
        "{text}"
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["status"], "completed");
    assert!(s["metric_errors"]["tumbling_period_gamma"]
        .as_str()
        .unwrap()
        .contains("run longer"));
    let e = s["metrics"]["min_end_to_end_over_length"]["value"]
        .as_f64()
        .unwrap();
    assert!((0.99..=1.0).contains(&e), "{e}");
    let _ = std::fs::remove_dir_all(&out);
}

/// A fibre that starts inside a wall or on top of another fibre is refused by `check` and at
/// step 0 by the fluid node (which knows the walls and the box), naming the fibre, the bead
/// and the key, in either layout and for both fluid methods; the scenes' own starts pass.
#[test]
fn a_fibre_starting_in_a_wall_or_on_another_is_refused() {
    // `run_scene` with two steps; the output directory is removed afterwards.
    let run = |name: &str, scene: &std::path::Path, sets: &[&str], in_process: bool| {
        let name = format!("start-{name}");
        let mut o = vec!["time.steps=2".to_string()];
        o.extend(sets.iter().map(|s| s.to_string()));
        let extra: &[&str] = if in_process { &["--in-process"] } else { &[] };
        let r = run_scene(&name, scene, &o, extra);
        let _ = out_dir(&name);
        match r {
            Ok(_) => (true, String::new()),
            Err(e) => (false, e),
        }
    };
    let tumbling = config("spm/tumbling.toml");
    let in_wall = ["fibre.0.start=[48,2,0]", "output.fields_interval=0"];
    for in_process in [true, false] {
        let (ok, err) = run("spm-wall", &tumbling, &in_wall, in_process);
        assert!(!ok && !err.contains("panicked"), "{err}");
        assert!(
            err.contains(
                "fibre 0 bead 0 starts at y = 2 with radius 4: it reaches into the bottom wall, \
                 whose face is at y = 3.5"
            ) && err.contains("move fibre.0.start"),
            "in-process {in_process}: {err}"
        );
    }
    // `check` finds the same without running a step.
    expect_error(
        &["check", tumbling.to_str().unwrap(), "--set", in_wall[0]],
        &[
            "fibre 0 bead 0 starts at y = 2 with radius 4",
            "bottom wall",
        ],
    );
    // 20 beads of diameter 8 upwards from y = 28 cross the top wall of the 96-tall box.
    let long = ["fibre.0.beads=20", "output.fields_interval=0"];
    let (_, err) = run("spm-long", &tumbling, &long, true);
    assert!(
        err.contains("fibre 0 bead 8 starts at y = 92") && err.contains("top wall"),
        "{err}"
    );
    let fpd = config("fpd/jeffery_rigid.toml");
    let (_, err) = run("fpd-wall", &fpd, &["fibre.0.start=[32,1,0]"], true);
    assert!(
        err.contains(
            "fibre 0 bead 0 starts at y = 1 with radius 2: it reaches into the bottom wall, \
             whose face is at y = -0.5"
        ),
        "{err}"
    );
    // A second fibre whose first bead lies 2 above the first fibre's second bead.
    let fibre = "[[fibre]]\nmodel = \"cohesive-beam\"\nbeads = 3\nbead_radius = 3.0\n\
                 youngs_modulus = 1.0\ndensity = 2.0\n";
    let two = write_scene(
        "two-fibres",
        &format!(
            "dimensions = 2\n[time]\ndt = 0.5\nsteps = 2\n[fluid]\nmethod = \"spm\"\n\
             grid = [64, 64]\nviscosity = 1.0\n{fibre}start = [20.0, 30.0, 0.0]\n\
             {fibre}start = [26.0, 32.0, 0.0]\n"
        ),
    );
    let (ok, err) = run("two", &two, &[], true);
    assert!(!ok, "{err}");
    assert!(
        err.contains("fibre 1 bead 0 at (26, 32) overlaps fibre 0 bead 1 at (26, 30): centres 2 apart, radii summing to 6"),
        "{err}"
    );
    let (ok, err) = run("two-apart", &two, &["fibre.1.start=[26,36,0]"], true);
    assert!(ok, "{err}");
    for (name, scene) in [("spm-ok", &tumbling), ("fpd-ok", &fpd)] {
        let (ok, err) = run(name, scene, &["output.fields_interval=0"], true);
        assert!(ok, "{name}: {err}");
    }
}

/// A scene the nodes refuse changes nothing in `--out`: the earlier run's log, summary and
/// exported tables stay as they were, and the message does not point at a log. (It used to
/// replace them with a `failed` summary and an empty log.)
#[test]
fn a_refused_scene_leaves_the_earlier_run_in_its_folder() {
    let p = write_scene("refused-keeps", GOOD);
    let out = out_dir("refused-keeps");
    let o = run_command(&p, &out)
        .args(["--in-process", "--set", "time.steps=20"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let e = coordinator(&["export", out.to_str().unwrap()]);
    assert!(e.status.success(), "{}", String::from_utf8_lossy(&e.stderr));
    let files = [
        "run.mcap",
        "summary.json",
        "beads.csv",
        "diagnostics.csv",
        "scene.toml",
    ];
    let before: Vec<Vec<u8>> = files
        .iter()
        .map(|f| std::fs::read(out.join(f)).unwrap())
        .collect();
    for layout in [&["--in-process"][..], &[][..]] {
        let o = run_command(&p, &out)
            .args(["--set", "fibre.0.youngs_modulu=1"])
            .args(layout)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        assert!(err.contains("youngs_modulu"), "{err}");
        assert!(!err.contains("log written so far"), "{err}");
        for (f, b) in files.iter().zip(&before) {
            assert!(
                std::fs::read(out.join(f)).ok().as_ref() == Some(b),
                "{f} changed by a refused scene ({layout:?})"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    // Into a folder that did not exist, a refused scene leaves none behind.
    let o = run_command(&p, &out)
        .args(["--set", "fibre.0.youngs_modulu=1", "--in-process"])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(!out.exists(), "a refused scene left {}", out.display());
}

/// Numbers on the command line are refused in words, negative ones included (clap would
/// otherwise take `-5` for an option, or say "invalid digit found in string"), and
/// `--lock-step`, a way of running processes, is refused beside `--in-process`. Nothing
/// runs: every refusal comes before the scene is read.
#[test]
fn command_line_numbers_and_conflicts() {
    let cases: &[(&[&str], &str)] = &[
        (
            &["run", "--checkpoint-interval=-1"],
            "expected a whole number of steps, 0 (no checkpoints) or more",
        ),
        (
            &["run", "--checkpoint-interval", "2.5"],
            "expected a whole number of steps",
        ),
        (
            &["run", "--node-timeout", "-5"],
            "--node-timeout: expected a positive number of seconds, got -5",
        ),
        (
            &["run", "--in-process", "--lock-step"],
            "'--in-process' cannot be used with '--lock-step'",
        ),
        (
            &["study", "no-such.study.toml", "--jobs", "-2"],
            "expected a whole number of variants to run at once, from 1",
        ),
        (
            &["study", "no-such.study.toml", "--jobs", "0"],
            "expected a whole number of variants to run at once, from 1",
        ),
    ];
    for (args, needle) in cases {
        expect_error(args, &[needle]);
    }
}
