//! How the S-shaped bending moment of a rigid chain of discs in strain grows with its
//! thickness at a fixed length, with the discs locked to the chain or turning freely about
//! their centres (rollers, as the bead-spring model's beads are): ten discs, centres 2
//! apart, radius 1 (touching) down to 0.25, in unbounded 2D Stokes flow
//! (`coordinator/src/reference/stokes_chain_2d.rs`). Prints the chain's Bretherton constant
//! B, 1 - B, the largest joint moment over mu E L^2 (strain rate E of `u = (y, x)`, 2D:
//! moments per unit depth; L = 20, the chain's length at radius 1), and the quasi-static S a
//! flexible chain would take under that moment, as its largest distance from the chord over
//! L per unit mu E L^3 / EI:
//!
//!     cargo run --release -p coordinator --example stokes_chain_moments
use coordinator::reference::stokes_chain_2d as bem;

fn main() {
    let beads = 10;
    let length = 2.0 * beads as f64;
    println!(
        "| discs | radius / half-spacing | B | 1 - B | max |M| / (mu E L^2) | S: max |w| / L per mu E L^3 / EI | change from half the nodes |"
    );
    println!("|---|---|---|---|---|---|---|");
    for spinning in [false, true] {
        for radius in [1.0, 0.9, 0.75, 0.5, 0.25] {
            let max = |m: &[f64]| m.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            let (b, m) = bem::chain_bending_moments(beads, radius, 64, spinning);
            let (_, coarse) = bem::chain_bending_moments(beads, radius, 32, spinning);
            println!(
                "| {} | {radius} | {b:.5} | {:.5} | {:.3e} | {:.3e} | {:.1e} |",
                if spinning { "rollers" } else { "locked" },
                1.0 - b,
                max(&m) / length.powi(2),
                bem::s_deflection_per_load(&m),
                (max(&m) - max(&coarse)).abs() / max(&m)
            );
        }
    }
}
