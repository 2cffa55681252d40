//! Helpers shared by the fluid node's integration tests.
#![allow(dead_code)]
use cosim::{
    BeadImpulse, BeadState, Component, Configured, Exchange, InProcessExchange, Phase, PhaseReport,
    Port,
};
use fluid_node::FluidComponent;

pub fn configure(scene: &str) -> (FluidComponent, InProcessExchange, Configured) {
    let mut c = FluidComponent::new();
    let mut x = InProcessExchange::new();
    let cfg = c.configure(scene, &mut x).unwrap_or_else(|e| panic!("{e}"));
    (c, x, cfg)
}

pub fn diag(r: &PhaseReport, name: &str) -> f64 {
    r.diagnostics
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no diagnostic {name} in {r:?}"))
        .1
}

/// One fluid step without beads.
pub fn step(c: &mut FluidComponent, x: &mut InProcessExchange, n: u64) -> PhaseReport {
    c.run_phase(n, Phase::FluidMomentumExchange, x).unwrap();
    c.run_phase(n, Phase::FluidPenalty, x).unwrap()
}

/// One coupled-like step with prescribed bead states: `before` (positions n+1, velocities n)
/// for the momentum exchange, `after` (velocities n+1) for the penalty. Returns the impulses
/// and the penalty report.
pub fn bead_step(
    c: &mut FluidComponent,
    x: &mut InProcessExchange,
    n: u64,
    before: &[BeadState],
    after: &[BeadState],
) -> (Vec<BeadImpulse>, PhaseReport) {
    x.publish_states(Port::BeadPositions, n + 1, before)
        .unwrap();
    c.run_phase(n, Phase::FluidMomentumExchange, x).unwrap();
    let mut imp = Vec::new();
    x.read_impulses(Port::BeadImpulses, &mut imp).unwrap();
    x.publish_states(Port::BeadStates, n + 1, after).unwrap();
    let rep = c.run_phase(n, Phase::FluidPenalty, x).unwrap();
    (imp, rep)
}

/// Total fluid momentum rho Σ u (cell volume 1), summed in index order.
pub fn momentum(c: &FluidComponent, rho: f64) -> [f64; 3] {
    let mut m = [0.0; 3];
    for (k, comp) in c.velocity().iter().enumerate() {
        m[k] = rho * comp.iter().fold(0.0, |a, b| a + b);
    }
    m
}

/// A 2D SPM scene with walls and a clamped 3-bead fibre, 48 x 40.
pub const FIBRE_SCENE: &str = r#"
dimensions = 2
[time]
dt = 0.5
steps = 10
[fluid]
method = "spm"
grid = [48, 40]
viscosity = 1.0
[walls]
velocity = [-0.02, 0.02]
[[fibre]]
model = "cohesive-beam"
beads = 3
bead_radius = 3
youngs_modulus = 100
clamp = [0]
"#;

pub fn fibre_states(n: u64, v: f64) -> Vec<BeadState> {
    (0..3)
        .map(|i| BeadState {
            position: [14.0 + 6.0 * i as f64 + 0.01 * n as f64, 20.0, 0.0],
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.01 + v, 0.002 * i as f64, 0.0],
            angular_velocity: [0.0, 0.0, 0.001],
        })
        .collect()
}

/// Run `steps` coupled-like steps from `from`; return the bits of the velocity and of every
/// impulse and diagnostic.
pub fn run(c: &mut FluidComponent, x: &mut InProcessExchange, from: u64, steps: u64) -> Vec<u64> {
    let mut bits = Vec::new();
    for n in from..from + steps {
        let (imp, rep) = bead_step(c, x, n, &fibre_states(n, 0.0), &fibre_states(n, 1e-3));
        for j in imp {
            bits.extend(
                j.impulse
                    .iter()
                    .chain(&j.angular_impulse)
                    .map(|v| v.to_bits()),
            );
        }
        bits.extend(rep.diagnostics.iter().map(|(_, v)| v.to_bits()));
    }
    for comp in c.velocity() {
        bits.extend(comp.iter().map(|v| v.to_bits()));
    }
    bits
}

/// 30 coupled FPD steps of a 3-bead chain of touching beads of radius `a`, moved by the
/// velocities the lattice gives it, in a 64 x 640 channel between walls at -+0.01 (nu 0.1):
/// the final positions and velocities. At a = 4 the beads' boxes are computed one after the
/// other, at a = 8 in parallel (`fpd::PARALLEL_BOX_NODES`).
pub fn fpd_chain_run(a: f64) -> ([[f64; 2]; 3], [[f64; 2]; 3]) {
    use fluid_node::fpd::{FpdConfig, FpdCoupling};
    use fluid_node::mrt_d2q9::{MrtConfig, MrtD2q9, YBoundary};
    let walls = YBoundary::Walls {
        bottom: -0.01,
        top: 0.01,
    };
    let mut lat = MrtD2q9::new(MrtConfig::new(64, 640, walls, 0.1)).unwrap();
    let mut c = FpdCoupling::new(FpdConfig::new(a, 0.1), &mut lat, 3).unwrap();
    let mut pos = [
        [10.0, 100.0],
        [10.0 + 2.0 * a, 100.5],
        [10.0 + 4.0 * a, 101.0],
    ];
    let forces = [[1e-4, 0.0], [0.0, 0.0], [-1e-4, 0.0]];
    let mut v = [[0.0; 2]; 3];
    for _ in 0..30 {
        c.apply(&mut lat, &pos, &forces).unwrap();
        lat.step();
        c.bead_velocities(&lat, &mut v).unwrap();
        for (p, w) in pos.iter_mut().zip(&v) {
            p[0] += 50.0 * w[0];
            p[1] += 50.0 * w[1];
        }
    }
    (pos, v)
}
