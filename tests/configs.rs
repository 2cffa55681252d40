//! Every scene in `configs/` is valid: it parses, the components fit, and each node accepts
//! its tables and the time step (what `coordinator check` does); so is every variant of every
//! study in `docs/validation/`. Runs nothing.
mod common;
use common::*;

fn scenes(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            scenes(&p, out);
        } else if p.extension().is_some_and(|x| x == "toml") {
            out.push(p);
        }
    }
}

#[test]
fn every_scene_in_configs_checks() {
    let mut all = Vec::new();
    scenes(&root().join("configs"), &mut all);
    all.sort();
    assert!(
        all.len() >= 7,
        "expected the validation scenes, found {all:?}"
    );
    for p in &all {
        let scene = coordinator::scene::load(Some(p), &[])
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        coordinator::runner::check(&scene).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    }
}

/// Every study in `docs/validation/` is valid: it parses, and every variant's scene checks
/// with the study's metric among its metrics (what `coordinator study FILE --check` does).
/// Runs nothing; keeps the documented studies runnable as scenes and keys change.
#[test]
fn every_study_in_docs_validation_checks() {
    let dir = root().join("docs").join("validation");
    let mut studies: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".study.toml"))
        .collect();
    studies.sort();
    assert!(
        studies.len() >= 10,
        "expected the validation studies, found {studies:?}"
    );
    for p in &studies {
        let n = coordinator::study::check_file(p).unwrap_or_else(|e| panic!("{e}"));
        assert!(n > 0, "{}: no variants", p.display());
    }
}

/// docs/summary.md documents every diagnostic a node can report (each node's lists of names,
/// in their fixed order), so that a new diagnostic cannot land undocumented.
#[test]
fn every_diagnostic_is_documented() {
    let doc = std::fs::read_to_string(root().join("docs").join("summary.md")).unwrap();
    let table: Vec<&str> = doc
        .split("## Diagnostics")
        .nth(1)
        .expect("docs/summary.md has a Diagnostics section")
        .lines()
        .filter(|l| l.starts_with("| `"))
        .collect();
    // A name is documented where a row names it, whole (`name`) or as an axis of `x_, _y`.
    let documented = |name: &str| {
        let axis = name
            .rsplit_once('_')
            .filter(|(_, a)| ["x", "y", "z"].contains(a));
        table.iter().any(|row| {
            let cell = row.split(" | ").next().unwrap_or("");
            cell.contains(&format!("`{name}`"))
                || axis.is_some_and(|(stem, a)| {
                    cell.contains(&format!("`{stem}_x`"))
                        && (a == "x" || cell.contains(&format!("`_{a}`")))
                })
        })
    };
    let names = fibre_node::component::DIAGNOSTICS
        .iter()
        .chain(&fluid_node::component::DIAGNOSTICS)
        .chain(&fluid_node::component::EXCHANGE_DIAGNOSTICS)
        .chain(&[fluid_node::component::COUETTE_DIAGNOSTIC])
        .chain(&fluid_node::fpd_lbm::FPD_DIAGNOSTICS)
        .chain(&fluid_node::binary_fluid::PHASE_FIELD_DIAGNOSTICS)
        .chain(&fluid_node::binary_fluid::INTERFACE_DIAGNOSTICS)
        .chain(&fluid_node::binary_fluid::CONTACT_ANGLE_DIAGNOSTICS)
        .chain(&fluid_node::binary_fluid::droplet::DROPLET_DIAGNOSTICS);
    let missing: Vec<&&str> = names.filter(|n| !documented(n)).collect();
    assert!(
        missing.is_empty(),
        "not in docs/summary.md's Diagnostics: {missing:?}"
    );
}
