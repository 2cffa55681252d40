//! Cantilever under a tip load against small-deflection theory and the elastica
//! (L2020 section 3.1, eq. 43, Fig. 5; REFERENCE.md section 1).
mod common;
use common::*;

/// Tip force giving load parameter `alpha` for the cantilever scene (r_b = 1, E = 1e4).
fn tip_force(alpha: f64, beads: usize) -> String {
    let ei = 1.0e4 * std::f64::consts::PI / 4.0;
    let l = 2.0 * (beads as f64 - 1.0);
    format!("fibre.0.loads.0.force=[0.0,{},0.0]", -alpha * ei / (l * l))
}

fn run(alpha: f64, beads: usize, test: &str) -> serde_json::Value {
    let overrides = vec![format!("fibre.0.beads={beads}"), tip_force(alpha, beads)];
    let s = run_in_process(&config("cantilever.toml"), &overrides, test);
    assert_eq!(s["status"], "at-rest", "{test}: did not come to rest: {s}");
    s
}

fn small_deflection(alpha: f64, beads: usize) {
    let s = run(alpha, beads, &format!("cantilever-small-{alpha}-{beads}"));
    let (value, _) = metric(&s, "tip_deflection_over_length");
    let linear = alpha / 3.0;
    let err = (value / linear - 1.0).abs();
    println!(
        "alpha {alpha}, N_b {beads}: delta/L = {value:.6}, alpha/3 = {linear:.6}, error {:.3} %",
        100.0 * err
    );
    assert!(
        err < 0.02,
        "small deflection off alpha/3 by {:.3} % (alpha {alpha}, N_b {beads})",
        100.0 * err
    );
}

#[test]
fn small_deflection_alpha_0_1_any_bead_count() {
    small_deflection(0.1, 5);
    small_deflection(0.1, 10);
}

#[test]
fn small_deflection_alpha_0_3() {
    small_deflection(0.3, 5);
    small_deflection(0.3, 10);
}

fn large_deflection(alpha: f64) {
    let s = run(alpha, 10, &format!("cantilever-large-{alpha}"));
    let (value, reference) = metric(&s, "tip_deflection_over_length");
    let err = (value / reference - 1.0).abs();
    println!(
        "alpha {alpha}, N_b 10: delta/L = {value:.5}, elastica {reference:.5}, error {:.3} %",
        100.0 * err
    );
    assert!(
        err < 0.03,
        "alpha {alpha}: tip deflection off the elastica by {:.2} %",
        100.0 * err
    );
}

#[test]
fn large_deflection_alpha_1() {
    large_deflection(1.0);
}

#[test]
fn large_deflection_alpha_2() {
    large_deflection(2.0);
}

#[test]
fn large_deflection_alpha_5() {
    large_deflection(5.0);
}

#[test]
fn large_deflection_alpha_10() {
    large_deflection(10.0);
}

/// L2020 Fig. 5: with N_b = 5 large deflections are poorly resolved. Reported, and checked to
/// be worse than N_b = 10 (the paper's observation), not held to the 3 % bound.
#[test]
fn five_beads_are_worse_than_ten_at_large_deflection() {
    let e = |beads| {
        let s = run(5.0, beads, &format!("cantilever-nb{beads}-alpha5"));
        let (v, r) = metric(&s, "tip_deflection_over_length");
        println!(
            "alpha 5, N_b {beads}: delta/L = {v:.5}, elastica {r:.5}, error {:.2} %",
            100.0 * (v / r - 1.0).abs()
        );
        (v / r - 1.0).abs()
    };
    assert!(e(5) > e(10));
}

/// A load far past the table (alpha = 1000): the beam hangs along the load and its bonds
/// stretch by the axial strain P / (E pi r_b^2) = 77 %, which the inextensible elastica
/// leaves out. The metrics report the measured change of length (`axial_strain`, within 1 %
/// of P / (E A)) and say so in their note; the tip lies within 3 % of the elastica's
/// deflection stretched by that strain. (Before the elastica's closed form, its reference
/// here was wrong: shooting cannot resolve the root past alpha ~ 400.)
#[test]
fn a_stretched_cantilever_reports_its_strain() {
    let s = run(1000.0, 10, "cantilever-stretched");
    let m = &s["metrics"]["tip_deflection_over_length"];
    let strain = m["extra"]["axial_strain"].as_f64().unwrap();
    let (value, reference) = metric(&s, "tip_deflection_over_length");
    let p_over_ea = 1000.0 * 1.0e4 * std::f64::consts::PI
        / 4.0
        / (18.0 * 18.0)
        / (1.0e4 * std::f64::consts::PI);
    println!("strain {strain}, P / (E A) {p_over_ea}, delta/L {value}, elastica {reference}");
    assert!((strain / p_over_ea - 1.0).abs() < 0.01, "{m}");
    assert!(m["note"].as_str().unwrap().contains("inextensible"), "{m}");
    assert!(
        (value / ((1.0 + strain) * reference) - 1.0).abs() < 0.03,
        "{m}"
    );
    // The scene's own load stretches the beam by 0.15 %: no note.
    let s = run(2.0, 10, "cantilever-unstretched");
    let m = &s["metrics"]["tip_deflection_over_length"];
    assert!(
        m["extra"]["axial_strain"].as_f64().unwrap().abs() < 0.01,
        "{m}"
    );
    assert!(m.get("note").is_none(), "{m}");
}
