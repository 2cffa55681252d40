//! The 3D Stokes reference for the Jeffery period of chains of touching spheres
//! (`coordinator/src/reference/stokes_chain_3d.rs`, rigid multiblob) at each shell
//! resolution, with the spheroid check and Harris & Pittman's law for cylinders:
//!
//!     cargo run --release -p coordinator --example stokes_chain_periods_3d
use coordinator::reference::{jeffery, stokes_chain_3d as mb};

fn main() {
    let levels = [1u32, 2, 3];
    println!("Spheroids (Jeffery: B = (e^2 - 1) / (e^2 + 1)):");
    println!("| e | exact B | B at 42 / 162 / 642 blobs | extrapolated from 42 and 162 |");
    println!("|---|---|---|---|");
    for e in [2.0, 3.0, 4.0] {
        let exact = (e * e - 1.0) / (e * e + 1.0);
        let got: Vec<f64> = levels
            .iter()
            .map(|&l| {
                let (b, a) = mb::spheroid_blobs(e, l);
                mb::bretherton(&b, a)
            })
            .collect();
        let list: Vec<String> = got.iter().map(|b| format!("{b:.4}")).collect();
        println!(
            "| {e} | {exact:.4} | {} | {:.4} |",
            list.join(" / "),
            got[1] - (got[0] - got[1]) / 2.0
        );
    }
    println!("\nChains of touching spheres:");
    println!("| N_b | B at 42 / 162 / 642 blobs per sphere | B extrapolated (the reference) | e | gamma T | Harris & Pittman | REFERENCE.md table |");
    println!("|---|---|---|---|---|---|---|");
    for n in 2..=6 {
        let bs: Vec<f64> = levels
            .iter()
            .filter(|&&l| l < 3 || n <= 4)
            .map(|&l| mb::chain_bretherton_at(n, l))
            .collect();
        let b = mb::chain_bretherton(n);
        let list: Vec<String> = bs.iter().map(|b| format!("{b:.4}")).collect();
        println!(
            "| {n} | {} | {b:.4} | {:.3} | {:.2} | {:.2} | {:.2} |",
            list.join(" / "),
            mb::equivalent_aspect_ratio(b),
            mb::period_gamma(b),
            jeffery::chain_period_gamma(n),
            jeffery::chain_period_gamma_table(n)
        );
    }
}
