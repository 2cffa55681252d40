//! Torsion of a clamped rod: phi = T L / (G J) (REFERENCE.md section 1).
mod common;
use common::*;

#[test]
fn twist_angle_matches_t_l_over_g_j() {
    let s = run_in_process(&config("torsion.toml"), &[], "torsion");
    assert_eq!(s["status"], "at-rest", "{s}");
    let (value, reference) = metric(&s, "twist_angle");
    let err = (value / reference - 1.0).abs();
    println!(
        "twist {value:.6} rad, T L / (G J) = {reference:.6} rad, error {:.3} %",
        100.0 * err
    );
    assert!(err < 0.02, "twist angle off by {:.3} %", 100.0 * err);
    assert!(!s["effects"].as_array().unwrap().is_empty());
}

/// A 2D scene computes no twist: the effect is absent from the summary.
#[test]
fn two_dimensional_scene_has_no_twist_effect() {
    let s = run_in_process(
        &config("cantilever.toml"),
        &["time.steps=10".into()],
        "no-twist-2d",
    );
    let effects: Vec<&str> = s["effects"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|e| e.as_str())
        .collect();
    assert!(!effects.contains(&"twist"), "{effects:?}");
    assert!(effects.contains(&"beam-elasticity"), "{effects:?}");
}
