//! A rigid fibre of N touching FPD beads tumbling at the centre of a Couette channel (S2023
//! section IV B), with the fitted aspect ratio r_c of Jeffery's orbit, S2023 eq. 19:
//! omega = (gamma / 2) [ (1 - r_c^2) / (1 + r_c^2) cos(2 theta) - 1 ].
//!
//! ```sh
//! cargo run --release -p fluid-node --example fpd_rigid_fibre -- \
//!     [beads=10] [d=4] [confinement=0.2] [lx=25] [wall=0.05] [re_ps=0.4] [reta=100] \
//!     [rxi=0.125] [stiffness=1] [angle_deg=90] [turn_deg=180] [max_steps=200000] [every=500]
//! ```
//!
//! Lattice units; `d` is the bead diameter, `lx` the channel length in diameters, `wall` the
//! wall speed V0 (walls at -V0 and +V0, H = N d / C, gamma = 2 V0 / H), `re_ps` S2023's
//! Re_ps = rho gamma l_c^2 / (4 eta_f), which sets the viscosity. S2023 uses r_eta = 100,
//! r_xi = 0.125, L_x = 25 d and, for its Jeffery fit (r_c ~ 0.132 for N = 10), C = 0.2 at
//! Re_ps << 1.
//!
//! Rigidity. S2023 keeps a fibre straight with stiff springs and bending forces (eqs. 9–12)
//! and moves every bead by its own eq. 5 velocity. Here the internal forces are those of a
//! shape-matching spring instead: the least-squares rigid placement T_i of the straight
//! template on the current beads (centroid C and angle theta, the best rotation of the
//! template about C) pulls each bead with F_i = k (T_i - R_i). These forces sum to zero, and
//! so does their torque about C, because theta is the least-squares angle
//! (sum (R_i - C) x (T_i - C) = 0); like S2023's internal forces they move no fibre as a
//! whole, they only keep its shape. Beads then move by S2023's step (3), R_i += V_i.
//! The stiffness k (lattice units, per bead) must keep the shape errors F / k well below a
//! lattice spacing while the bead mobility times k stays below one per step.
use fluid_node::fpd::{FpdConfig, FpdCoupling};
use fluid_node::mrt_d2q9::{MrtConfig, MrtD2q9, YBoundary};
use std::f64::consts::PI;
use std::time::Instant;

fn arg(name: &str, default: f64) -> f64 {
    std::env::args()
        .skip(1)
        .find_map(|a| {
            a.strip_prefix(&format!("{name}="))
                .map(|v| v.parse().unwrap_or_else(|e| panic!("{name}: {e}")))
        })
        .unwrap_or(default)
}

/// Least-squares rigid placement of the template offsets `s_i` (along the body axis) on the
/// beads `r`: centroid and angle.
fn fit(r: &[[f64; 2]], s: &[f64], periodic_x: f64) -> ([f64; 2], f64) {
    // Unwrap x relative to the first bead (the fibre may straddle the periodic boundary).
    let x0 = r[0][0];
    let ux = |x: f64| x0 + (x - x0 + 0.5 * periodic_x).rem_euclid(periodic_x) - 0.5 * periodic_x;
    let n = r.len() as f64;
    let c = [
        r.iter().map(|p| ux(p[0])).sum::<f64>() / n,
        r.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    let (mut sc, mut ss) = (0.0, 0.0);
    for (p, &si) in r.iter().zip(s) {
        let (px, py) = (ux(p[0]) - c[0], p[1] - c[1]);
        // t = (si, 0): t . p and t x p.
        sc += si * px;
        ss += si * py;
    }
    (c, ss.atan2(sc))
}

fn main() {
    let n = arg("beads", 10.0) as usize;
    let d = arg("d", 4.0);
    let conf = arg("confinement", 0.2);
    let lx = arg("lx", 25.0);
    let v0 = arg("wall", 0.05);
    let re_ps = arg("re_ps", 0.4);
    let reta = arg("reta", 100.0);
    let rxi = arg("rxi", 0.125);
    let k = arg("stiffness", 1.0);
    let turn = arg("turn_deg", 180.0).to_radians();
    let max_steps = arg("max_steps", 200_000.0) as u64;
    let every = arg("every", 500.0) as u64;
    let lc = n as f64 * d;
    let nx = (lx * d).round() as usize;
    let ny = (lc / conf).round() as usize;
    let gamma = 2.0 * v0 / ny as f64;
    let nu = gamma * lc * lc / (4.0 * re_ps);
    let mut lat = MrtD2q9::new(MrtConfig::new(
        nx,
        ny,
        YBoundary::Walls {
            bottom: -v0,
            top: v0,
        },
        nu,
    ))
    .unwrap_or_else(|e| panic!("{e}"));
    let mut cfg = FpdConfig::new(0.5 * d, nu);
    cfg.viscosity_ratio = reta;
    cfg.interface_ratio = rxi;
    let mut fpd = FpdCoupling::new(cfg, &mut lat, n).unwrap_or_else(|e| panic!("{e}"));
    // Start from the Couette profile through the wall planes y = -1/2 and ny - 1/2.
    lat.initialize_with(|_, y| (1.0, -v0 + gamma * (y as f64 + 0.5), 0.0))
        .unwrap();
    let offsets: Vec<f64> = (0..n)
        .map(|i| (i as f64 - 0.5 * (n as f64 - 1.0)) * d)
        .collect();
    let theta0 = arg("angle_deg", 90.0).to_radians();
    let centre = [0.5 * nx as f64, 0.5 * ny as f64 - 0.5];
    let mut pos: Vec<[f64; 2]> = offsets
        .iter()
        .map(|s| [centre[0] + s * theta0.cos(), centre[1] + s * theta0.sin()])
        .collect();
    let mut forces = vec![[0.0; 2]; n];
    let mut vel = vec![[0.0; 2]; n];
    println!(
        "# rigid FPD fibre: N = {n}, d = {d}, C = {conf}, channel {nx} x {ny}, V0 = {v0}, \
         gamma = {gamma:.3e}, nu_f = {nu:.4}, Re_ps = {re_ps}, r_eta = {reta}, r_xi = {rxi}, \
         k = {k}"
    );
    println!("# gamma_t theta_deg omega_over_gamma jeffery(r_c=0.1) max_shape_error");
    let start = Instant::now();
    let (mut theta_prev, mut turned) = (theta0, 0.0f64);
    let mut samples: Vec<(f64, f64)> = Vec::new();
    let mut step = 0u64;
    while step < max_steps && turned < turn {
        // Internal forces of the shape-matching spring.
        let (c, th) = fit(&pos, &offsets, nx as f64);
        let mut worst: f64 = 0.0;
        for ((f, p), s) in forces.iter_mut().zip(&pos).zip(&offsets) {
            let t = [c[0] + s * th.cos(), c[1] + s * th.sin()];
            let dx = (t[0] - p[0] + 0.5 * nx as f64).rem_euclid(nx as f64) - 0.5 * nx as f64;
            let dy = t[1] - p[1];
            *f = [k * dx, k * dy];
            worst = worst.max(dx.hypot(dy));
        }
        fpd.apply(&mut lat, &pos, &forces)
            .unwrap_or_else(|e| panic!("step {step}: {e}"));
        lat.step();
        step += 1;
        fpd.bead_velocities(&lat, &mut vel).unwrap();
        for (p, v) in pos.iter_mut().zip(&vel) {
            p[0] += v[0];
            p[1] += v[1];
        }
        if step.is_multiple_of(every) {
            let (_, th) = fit(&pos, &offsets, nx as f64);
            // The fibre's angle is defined modulo pi; unwrap against the last sample.
            let mut dth = th - theta_prev;
            dth -= PI * (dth / PI).round();
            let theta = theta_prev + dth;
            let omega = dth / every as f64;
            let mid = theta - 0.5 * dth;
            samples.push((mid, omega / gamma));
            let r = 0.1f64;
            let jeff = 0.5 * ((1.0 - r * r) / (1.0 + r * r) * (2.0 * mid).cos() - 1.0);
            println!(
                "{:.3} {:.2} {:.5} {:.5} {:.2e}",
                gamma * step as f64,
                mid.to_degrees(),
                omega / gamma,
                jeff,
                worst
            );
            turned += -dth;
            theta_prev = theta;
        }
    }
    let wall = start.elapsed().as_secs_f64();
    // Least squares of 2 omega / gamma + 1 = A cos(2 theta), A = (1 - r^2) / (1 + r^2).
    let (mut num, mut den) = (0.0, 0.0);
    for &(th, w) in &samples {
        let c2 = (2.0 * th).cos();
        num += (2.0 * w + 1.0) * c2;
        den += c2 * c2;
    }
    let a = num / den;
    let rc = ((1.0 - a) / (1.0 + a)).sqrt();
    println!(
        "# turned {:.1} deg in {step} steps (gamma t = {:.2}); fitted r_c = {rc:.4} \
         (geometric {:.4}, S2023 0.132); wall {wall:.1} s, {:.1} MLUPS",
        turned.to_degrees(),
        gamma * step as f64,
        1.0 / n as f64,
        (nx * ny) as f64 * step as f64 / wall / 1e6
    );
}
