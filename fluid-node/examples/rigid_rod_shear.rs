//! A rigid rod of touching discs in 2D Couette flow, moved as one rigid body by the fluid
//! node's impulses (no fibre node, no elasticity): the SPM side of the Jeffery orbit alone.
//!
//! ```sh
//! cargo run --release -p fluid-node --example rigid_rod_shear -- \
//!     [beads=6] [radius=6] [spacing=12] [grid=180] [dt=0.7] [nu=1] [wall=0.011944] \
//!     [steps=20000] [angle_deg=0] [density=1] [every=1000]
//! ```
//!
//! Prints gamma t, the rod angle theta (degrees, from +x) and omega / gamma next to Jeffery's
//! omega / gamma = -(r^2 sin^2 theta + cos^2 theta) / (r^2 + 1) for the geometric aspect ratio
//! r = (length + 2 radius) / (2 radius) along the rod axis.
use cosim::{BeadState, Component, Exchange, InProcessExchange, Phase, Port};
use fluid_node::FluidComponent;

fn arg(name: &str, default: f64) -> f64 {
    std::env::args()
        .skip(1)
        .find_map(|a| {
            a.strip_prefix(&format!("{name}="))
                .map(|v| v.parse().expect("number"))
        })
        .unwrap_or(default)
}

fn main() {
    let n = arg("beads", 6.0) as usize;
    let r = arg("radius", 6.0);
    let s = arg("spacing", 2.0 * r);
    let grid = arg("grid", 180.0) as usize;
    let dt = arg("dt", 0.7);
    let nu = arg("nu", 1.0);
    let wall = arg("wall", 0.011944);
    let steps = arg("steps", 20000.0) as u64;
    let every = arg("every", 1000.0) as u64;
    let rho_p = arg("density", 1.0);
    let mut theta = arg("angle_deg", 0.0).to_radians();
    let scene = format!(
        "dimensions = 2\n[time]\ndt = {dt}\n[fluid]\nmethod = \"spm\"\ngrid = [{grid}, {grid}]\n\
         viscosity = {nu}\ndensity = 1.0\nxi = 1.0\nxi_cutoff = 3.0\n\
         initial_velocity = \"couette\"\n[walls]\nvelocity = [{}, {wall}]\nthickness = 4.0\n\
         [[fibre]]\nbeads = {n}\nbead_radius = {r}\n",
        -wall
    );
    let mut fluid = FluidComponent::new();
    let mut x = InProcessExchange::new();
    let cfg = fluid
        .configure(&scene, &mut x)
        .unwrap_or_else(|e| panic!("{e}"));
    let gamma = cfg
        .derived
        .iter()
        .find(|(k, _)| k == "fluid.shear_rate")
        .unwrap()
        .1;
    let m = rho_p * std::f64::consts::PI * r * r;
    let ib = 0.5 * m * r * r;
    let offsets: Vec<f64> = (0..n)
        .map(|k| (k as f64 - 0.5 * (n as f64 - 1.0)) * s)
        .collect();
    let mass = m * n as f64;
    let inertia = offsets.iter().map(|o| m * o * o + ib).sum::<f64>();
    let mut c = [0.5 * grid as f64, 0.5 * grid as f64];
    let mut v = [0.0f64; 2];
    let mut w = 0.0f64;
    let aspect = ((n as f64 - 1.0) * s + 2.0 * r) / (2.0 * r);
    let states = |c: [f64; 2], v: [f64; 2], w: f64, th: f64| -> Vec<BeadState> {
        offsets
            .iter()
            .map(|o| {
                let rx = o * th.cos();
                let ry = o * th.sin();
                BeadState {
                    position: [c[0] + rx, c[1] + ry, 0.0],
                    orientation: [1.0, 0.0, 0.0, 0.0],
                    velocity: [v[0] - w * ry, v[1] + w * rx, 0.0],
                    angular_velocity: [0.0, 0.0, w],
                }
            })
            .collect()
    };
    println!(
        "# rigid rod: {n} beads r = {r} spacing {s}, aspect {aspect:.3}, grid {grid}^2, dt {dt}, \
         nu {nu}, gamma {gamma:.4e}, Re_L {:.3}, nu dt / xi^2 {:.3}",
        gamma * ((n as f64 - 1.0) * s + 2.0 * r).powi(2) / nu,
        nu * dt
    );
    println!("# gamma_t theta_deg omega_over_gamma jeffery centre_x centre_y");
    let mut imp = Vec::new();
    for step in 0..steps {
        c[0] += v[0] * dt;
        c[1] += v[1] * dt;
        theta += w * dt;
        x.publish_states(Port::BeadStates, step + 1, &states(c, v, w, theta))
            .unwrap();
        fluid
            .run_phase(step, Phase::FluidMomentumExchange, &mut x)
            .unwrap();
        x.read_impulses(Port::BeadImpulses, &mut imp).unwrap();
        let (mut jx, mut jy, mut l) = (0.0, 0.0, 0.0);
        for (o, j) in offsets.iter().zip(&imp) {
            let rx = o * theta.cos();
            let ry = o * theta.sin();
            jx += j.impulse[0];
            jy += j.impulse[1];
            l += rx * j.impulse[1] - ry * j.impulse[0] + j.angular_impulse[2];
        }
        v[0] += jx / mass;
        v[1] += jy / mass;
        w += l / inertia;
        x.publish_states(Port::BeadStates, step + 1, &states(c, v, w, theta))
            .unwrap();
        fluid.run_phase(step, Phase::FluidPenalty, &mut x).unwrap();
        if (step + 1) % every == 0 {
            let sn = theta.sin();
            let cs = theta.cos();
            let jeff = -(aspect * aspect * sn * sn + cs * cs) / (aspect * aspect + 1.0);
            println!(
                "{:.4} {:.3} {:.5} {:.5} {:.3} {:.3}",
                gamma * dt * (step + 1) as f64,
                theta.to_degrees(),
                w / gamma,
                jeff,
                c[0],
                c[1]
            );
        }
    }
}
