//! How the S-shaped bending moment of a rigid chain of discs in strain grows with its
//! thickness at a fixed length: ten discs, centres 2 apart, radius 1 (touching) down to 0.25,
//! in unbounded 2D Stokes flow (`coordinator/src/reference/stokes_chain_2d.rs`). Prints the
//! chain's Bretherton constant B, 1 - B, and the largest joint moment over mu E L^3 (strain
//! rate E of `u = (y, x)`, length L = 20 between the end discs' outer points at radius 1):
//!
//!     cargo run --release -p coordinator --example stokes_chain_moments
use coordinator::reference::stokes_chain_2d as bem;

fn main() {
    let beads = 10;
    let length = 2.0 * beads as f64;
    println!("| disc radius / half-spacing | B | 1 - B | max |M| / (mu E L^3) | change from half the nodes |");
    println!("|---|---|---|---|---|");
    for radius in [1.0, 0.75, 0.5, 0.25] {
        let max = |m: &[f64]| m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let (b, m) = bem::chain_bending_moments(beads, radius, 64);
        let (_, coarse) = bem::chain_bending_moments(beads, radius, 32);
        let scale = length.powi(3);
        println!(
            "| {radius} | {b:.5} | {:.5} | {:.3e} | {:.1e} |",
            1.0 - b,
            max(&m) / scale,
            (max(&m) - max(&coarse)).abs() / scale
        );
    }
}
