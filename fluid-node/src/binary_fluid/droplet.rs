//! Diagnostics of a droplet (`initial = "droplet"`) for the Laplace law: its radius and the
//! jump of the mechanical pressure across its surface ([`CahnHilliard::pressure`]).
//!
//! - centre: the periodic (circular) mean of the nodes on the droplet's side of ψ = 0;
//! - bulk values ψ_in, ψ_out, p_in, p_out, μ: means over the nodes farther than
//!   `3√2 ξ` (where tanh has reached 0.995) inside or outside the surface, solids excluded
//!   (the radius for these two sets is first taken from the count of nodes with ψ on the
//!   droplet's side);
//! - `droplet_radius`: the equimolar radius, from the volume `V = (Σψ - N ψ_out) /
//!   (ψ_in - ψ_out)` that a sharp droplet with the measured bulk values and the same mean ψ
//!   would have (`V = π R²` in 2D, `4/3 π R³` in 3D). The ψ⁴ free energy is symmetric in ψ,
//!   so the equimolar surface is also the surface of tension (no Tolman correction);
//! - `pressure_jump`: `p_in - p_out`, against σ/R (2D) and 2σ/R (3D);
//! - `pressure_jump_mu`: `μ (ψ_in - ψ_out)`, the same jump at equilibrium from the uniform
//!   chemical potential alone (module docs of `cahn_hilliard::pressure`).
//!
//! The whole-field passes cost about two phase-field steps, so they run only in full reports
//! ([`cosim::Detail`]), which the coordinator asks for at the steps it logs.
use crate::cahn_hilliard::{CahnHilliard, Fluid};
use crate::grid::Grid;
use std::f64::consts::{PI, SQRT_2, TAU};

/// Droplet diagnostics, in their fixed order, in full reports.
pub const DROPLET_DIAGNOSTICS: [&str; 3] = ["droplet_radius", "pressure_jump", "pressure_jump_mu"];

/// What [`measure`] finds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Droplet {
    pub centre: [f64; 3],
    /// Equimolar radius.
    pub radius: f64,
    pub psi_in: f64,
    pub psi_out: f64,
    pub pressure_jump: f64,
    pub pressure_jump_mu: f64,
}

/// Scratch of the droplet diagnostics, allocated at the first full report.
pub struct Scratch {
    pressure: Vec<f64>,
    mu: Vec<f64>,
    force: Vec<Vec<f64>>,
}

impl Scratch {
    pub fn new(g: Grid) -> Self {
        Self {
            pressure: vec![0.0; g.cells()],
            mu: vec![0.0; g.cells()],
            force: vec![vec![0.0; g.cells()]; g.dims],
        }
    }
}

/// The droplet of fluid `inside` in `ch`, or `None` when ψ has no node on the droplet's
/// side, or no bulk node outside it (the droplet fills the box).
pub fn measure(ch: &mut CahnHilliard, inside: Fluid, s: &mut Scratch) -> Option<Droplet> {
    ch.pressure(&mut s.pressure, &mut s.force).ok()?;
    s.mu.copy_from_slice(ch.chemical_potential());
    let g = ch.grid();
    let n = g.sizes();
    let (psi, phi) = (ch.psi(), ch.phi());
    let sign = inside.psi();
    let coords = |i: usize| {
        let x = i % g.nx;
        let y = (i / g.nx) % g.ny;
        let z = i / (g.nx * g.ny);
        [x, y, z]
    };
    // Centre: the circular mean per axis of the nodes on the droplet's side.
    let mut cs = [[0.0f64; 2]; 3];
    let mut count = 0usize;
    for (i, &p) in psi.iter().enumerate() {
        if sign * p > 0.0 {
            count += 1;
            let r = coords(i);
            for c in 0..g.dims {
                let a = TAU * r[c] as f64 / n[c] as f64;
                cs[c][0] += a.cos();
                cs[c][1] += a.sin();
            }
        }
    }
    if count == 0 {
        return None;
    }
    let mut centre = [0.0; 3];
    for c in 0..g.dims {
        let a = cs[c][1].atan2(cs[c][0]);
        centre[c] = (a / TAU * n[c] as f64).rem_euclid(n[c] as f64);
    }
    let radius_of = |v: f64| {
        if g.dims == 2 {
            (v / PI).sqrt()
        } else {
            (3.0 * v / (4.0 * PI)).cbrt()
        }
    };
    let r0 = radius_of(count as f64);
    let margin = 3.0 * SQRT_2 * ch.config().xi;
    // Means over the bulk inside and outside: [count, ψ, p, μ].
    let mut inner = [0.0f64; 4];
    let mut outer = [0.0f64; 4];
    let mut nearest = (f64::INFINITY, 0usize);
    for (i, &p) in psi.iter().enumerate() {
        if phi[i] > 0.0 {
            continue;
        }
        let r = coords(i);
        let d2: f64 = (0..g.dims)
            .map(|c| {
                let l = n[c] as f64;
                let d = r[c] as f64 - centre[c];
                let d = d - l * (d / l).round();
                d * d
            })
            .sum();
        let d = d2.sqrt();
        if d < nearest.0 {
            nearest = (d, i);
        }
        let acc = if d <= r0 - margin {
            &mut inner
        } else if d >= r0 + margin {
            &mut outer
        } else {
            continue;
        };
        acc[0] += 1.0;
        acc[1] += p;
        acc[2] += s.pressure[i];
        acc[3] += s.mu[i];
    }
    if outer[0] == 0.0 {
        return None;
    }
    if inner[0] == 0.0 {
        // A droplet thinner than two interface widths: its centre node stands for the bulk.
        let i = nearest.1;
        inner = [1.0, psi[i], s.pressure[i], s.mu[i]];
    }
    let mean = |a: [f64; 4], k: usize| a[k] / a[0];
    let (psi_in, psi_out) = (mean(inner, 1), mean(outer, 1));
    let total = ch.mean_psi() * g.cells() as f64;
    let volume = (total - g.cells() as f64 * psi_out) / (psi_in - psi_out);
    let mu = 0.5 * (mean(inner, 3) + mean(outer, 3));
    Some(Droplet {
        centre,
        radius: radius_of(volume),
        psi_in,
        psi_out,
        pressure_jump: mean(inner, 2) - mean(outer, 2),
        pressure_jump_mu: mu * (psi_in - psi_out),
    })
}
