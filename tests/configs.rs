//! Every scene in `configs/` is valid: it parses, the components fit, and each node accepts
//! its tables and the time step (what `coordinator check` does). Runs nothing.
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
