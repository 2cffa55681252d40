//! The 2D Stokes reference for the Jeffery period of chains of touching discs
//! (`coordinator/src/reference/stokes_chain_2d.rs`) next to Harris & Pittman's 3D law and
//! REFERENCE.md's table:
//!
//!     cargo run --release -p coordinator --example stokes_chain_periods
use coordinator::reference::{jeffery, stokes_chain_2d as bem};

fn main() {
    println!("| N_b | B (2D Stokes) | error | e | gamma T (2D Stokes) | Harris & Pittman | REFERENCE.md table |");
    println!("|---|---|---|---|---|---|---|");
    for n in 2..=10 {
        let b = bem::chain_bretherton(n);
        // The change from half the nodes per disc, as the error estimate.
        let err = (b - bem::chain_bretherton_at(n, bem::CHAIN_NODES / 2).0).abs();
        println!(
            "| {n} | {b:.5} | {err:.1e} | {:.3} | {:.2} | {:.2} | {:.2} |",
            bem::equivalent_aspect_ratio(b),
            bem::period_gamma(b),
            jeffery::chain_period_gamma(n),
            jeffery::chain_period_gamma_table(n)
        );
    }
}
