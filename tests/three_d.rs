//! 3D checks of the cohesive beam: isotropy of bending.
mod common;
use common::*;

/// A cantilever loaded out of plane (-z) bends exactly as one loaded in plane (-y).
#[test]
fn out_of_plane_load_bends_like_in_plane() {
    let base = |force: &str| {
        vec![
            "dimensions=3".to_string(),
            "time.steps=3000".into(),
            "time.rest_tolerance=1e-3".into(),
            format!("fibre.0.loads.0.force={force}"),
        ]
    };
    let a = run_in_process(
        &config("cantilever.toml"),
        &base("[0.0,-48.4814,0.0]"),
        "3d-in-plane",
    );
    let b = run_in_process(
        &config("cantilever.toml"),
        &base("[0.0,0.0,-48.4814]"),
        "3d-out-of-plane",
    );
    let (da, _) = metric(&a, "tip_deflection_over_length");
    let (db, _) = metric(&b, "tip_deflection_over_length");
    println!("in plane {da:.15}, out of plane {db:.15}");
    assert!(da > 0.1, "the cantilever did not bend: {da}");
    assert!(
        ((da - db) / da).abs() < 1e-9,
        "in plane {da} vs out of plane {db}"
    );
}
