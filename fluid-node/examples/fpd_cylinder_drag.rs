//! Steady drag on a fixed cylinder (one FPD bead held at rest) in a uniform stream, for a
//! few Reynolds numbers, against Dennis & Chang 1970 (REFERENCE.md section 2):
//! C_D = 2.846 (Re 10), 2.045 (Re 20), 1.522 (Re 40), C_D = F / (rho U^2 d / 2), Re = U d / nu.
//!
//! ```sh
//! cargo run --release -p fluid-node --example fpd_cylinder_drag -- \
//!     [re=10,20,40] [d=10] [height=20] [length=30] [u=0.05] [reta=50] [rxi=0.0125] \
//!     [walls=1] [sponge=4] [upstream=8] [max_time=150] [tol=1e-4]
//! ```
//!
//! Lengths `height`, `length`, `sponge` and `upstream` are in diameters, `max_time` in d / U; `re` is a
//! comma-separated list. S2023 Fig. 4 uses r_eta = 50 and r_xi = 0.0125, the defaults.
//!
//! Set-up (lattice units). The lattice is periodic in x; across y it is closed by walls
//! sliding at the stream speed U (`walls=1`, the far field seen from the cylinder; blockage
//! d / H) or periodic (`walls=0`, a column of cylinders H apart). The cylinder sits 8 d
//! downstream of the inlet (`upstream`). A sponge of `sponge` diameters at the end of the box, upstream
//! of the inlet through the periodic wrap, forces the flow back to the uniform stream:
//! f = sigma(x) rho (U - u), sigma rising smoothly to 0.1 per step, so the wake does not
//! re-enter.
//!
//! Holding the bead. S2023 drives a bead by a force and lets it move with eq. 5. A fixed
//! bead keeps its profile at its anchor and is given the force that holds its eq. 5
//! velocity V at zero: F = -k_p V - k_i sum V (a proportional-integral control, i.e. a
//! spring of stiffness k_i whose extension is the integrated velocity, plus a dashpot). In a
//! steady state V = 0 and F balances the hydrodynamic force exactly, so the drag is the
//! holding force. The gains are scaled by the bead's mass M = rho sum phi: k_p = M / 2
//! removes half of a velocity error per step, k_i = M / 20 keeps the spring slower than the
//! dashpot (a damped response).
use fluid_node::fpd::{FpdConfig, FpdCoupling};
use fluid_node::mrt_d2q9::{MrtConfig, MrtD2q9, YBoundary};
use std::time::Instant;

fn arg(name: &str, default: &str) -> String {
    std::env::args()
        .skip(1)
        .find_map(|a| a.strip_prefix(&format!("{name}=")).map(str::to_owned))
        .unwrap_or_else(|| default.to_owned())
}

fn num(name: &str, default: f64) -> f64 {
    arg(name, &default.to_string())
        .parse()
        .unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Dennis & Chang 1970 (REFERENCE.md section 2).
fn dennis_chang(re: f64) -> Option<f64> {
    [(10.0, 2.846), (20.0, 2.045), (40.0, 1.522)]
        .iter()
        .find(|(r, _)| (r - re).abs() < 1e-9)
        .map(|&(_, c)| c)
}

struct Case {
    d: f64,
    height: f64,
    length: f64,
    u: f64,
    reta: f64,
    rxi: f64,
    walls: bool,
    sponge: f64,
    upstream: f64,
    max_time: f64,
    tol: f64,
}

/// Returns (C_D, time in d / U, steps, wall seconds, nodes).
fn run(case: &Case, re: f64) -> Result<(f64, f64, u64, f64, usize), String> {
    let Case { d, u, .. } = *case;
    let nx = (case.length * d).round() as usize;
    let ny = (case.height * d).round() as usize;
    let nu = u * d / re;
    let y_boundary = if case.walls {
        YBoundary::Walls { bottom: u, top: u }
    } else {
        YBoundary::Periodic
    };
    let mut lat = MrtD2q9::new(MrtConfig::new(nx, ny, y_boundary, nu))?;
    let mut cfg = FpdConfig::new(0.5 * d, nu);
    cfg.viscosity_ratio = case.reta;
    cfg.interface_ratio = case.rxi;
    let mut fpd = FpdCoupling::new(cfg, &mut lat, 1).map_err(|e| e.to_string())?;
    lat.initialize_with(|_, _| (1.0, u, 0.0))?;
    // Centre of the channel, whose walls lie at y = -1/2 and ny - 1/2.
    let anchor = [[case.upstream * d, 0.5 * ny as f64 - 0.5]];
    fpd.apply(&mut lat, &anchor, &[[0.0; 2]])
        .map_err(|e| e.to_string())?;
    let mass = fpd.profile_volume(0);
    let (kp, ki) = (0.5 * mass, 0.05 * mass);
    // Sponge columns and their rates, sigma = 0.1 sin^2 rising over the first half.
    let width = (case.sponge * d).round() as usize;
    let sponge: Vec<(usize, f64)> = (nx - width..nx)
        .map(|x| {
            let s = ((x - (nx - width)) as f64 + 0.5) / (0.5 * width as f64);
            let ramp = (0.5 * std::f64::consts::PI * s.min(1.0)).sin();
            (x, 0.1 * ramp * ramp)
        })
        .collect();
    let box_right = anchor[0][0] + cfg.reach() + 1.0;
    if box_right >= (nx - width) as f64 {
        return Err("the sponge reaches the cylinder: make the box longer".into());
    }
    let mut v = [[0.0; 2]];
    let mut integral = [0.0; 2];
    let mut force = [[0.0; 2]];
    let window = (2.0 * d / u).round() as u64; // two convective times d / U
    let max_steps = (case.max_time * d / u).round() as u64;
    let cd_of = |fx: f64| fx / (0.5 * u * u * d);
    let (mut sum, mut last): (f64, Option<f64>) = (0.0, None);
    let start = Instant::now();
    let mut step = 0u64;
    let cd = loop {
        // Sponge: relax toward (U, 0) with the velocity of the last step.
        for y in 0..ny {
            for &(x, s) in &sponge {
                let (rho, ux, uy) = lat.node(x, y);
                let k = lat.index(x, y);
                let (fx, fy) = lat.force_mut();
                fx[k] = s * rho * (u - ux);
                fy[k] = -s * rho * uy;
            }
        }
        fpd.spread_forces(&mut lat, &force)
            .map_err(|e| e.to_string())?;
        lat.step();
        step += 1;
        fpd.bead_velocities(&lat, &mut v)
            .map_err(|e| e.to_string())?;
        for c in 0..2 {
            integral[c] += v[0][c];
            force[0][c] = -kp * v[0][c] - ki * integral[c];
        }
        // The fluid's force on the bead is minus the holding force.
        sum += -force[0][0];
        if step.is_multiple_of(window) {
            let mean = cd_of(sum / window as f64);
            sum = 0.0;
            if !mean.is_finite() {
                return Err(format!("diverged at step {step}"));
            }
            if let Some(prev) = last {
                if (mean / prev - 1.0).abs() < case.tol {
                    break mean;
                }
            }
            last = Some(mean);
            if step >= max_steps {
                eprintln!("re {re}: not converged to {} after {step} steps", case.tol);
                break mean;
            }
        }
    };
    let wall = start.elapsed().as_secs_f64();
    Ok((cd, step as f64 * u / d, step, wall, nx * ny))
}

fn main() {
    let case = Case {
        d: num("d", 10.0),
        height: num("height", 20.0),
        length: num("length", 30.0),
        u: num("u", 0.05),
        reta: num("reta", 50.0),
        rxi: num("rxi", 0.0125),
        walls: num("walls", 1.0) != 0.0,
        sponge: num("sponge", 4.0),
        upstream: num("upstream", 8.0),
        max_time: num("max_time", 150.0),
        tol: num("tol", 1e-4),
    };
    let res: Vec<f64> = arg("re", "10,20,40")
        .split(',')
        .map(|s| s.trim().parse().expect("re: a list of numbers"))
        .collect();
    println!(
        "# fixed FPD cylinder: d = {} lattice units, box {} x {} d ({}), U = {}, r_eta = {}, \
         r_xi = {} (xi = {:.3} lattice units), blockage d/H = {:.3}",
        case.d,
        case.length,
        case.height,
        if case.walls {
            "sliding walls in y"
        } else {
            "periodic in y"
        },
        case.u,
        case.reta,
        case.rxi,
        case.rxi * case.d,
        1.0 / case.height
    );
    println!("# Re  C_D  Dennis&Chang  ratio  time_dU  steps  wall_s  MLUPS");
    for re in res {
        match run(&case, re) {
            Ok((cd, t, steps, wall, nodes)) => {
                let reference = dennis_chang(re);
                println!(
                    "{re} {cd:.4} {} {} {t:.1} {steps} {wall:.2} {:.2}",
                    reference.map_or("-".into(), |c| format!("{c:.3}")),
                    reference.map_or("-".into(), |c| format!("{:.4}", cd / c)),
                    nodes as f64 * steps as f64 / wall / 1e6
                );
            }
            Err(e) => println!("{re} failed: {e}"),
        }
    }
}
