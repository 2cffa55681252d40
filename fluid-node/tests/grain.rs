//! The parallel grain (elements per rayon task, `fluid_node::parallel::grain`) decides only
//! how rows are shared among threads: runs with a coarse and a fine grain give the same bits.
//! The fluid node chooses the grain at run time from the time of its steps
//! (`fluid_node::grain_tuner`), so a result must not depend on it.
//!
//! One test in its own binary: the grain is process-wide, and another test running beside
//! this one would change it.
mod common;
use common::*;
use cosim::BeadState;
use fluid_node::fpd::{FpdConfig, FpdCoupling};
use fluid_node::mrt_d2q9::{MrtConfig, MrtD2q9, YBoundary};
use fluid_node::parallel::set_grain;

/// A 2D SPM scene with walls and a 3-bead fibre, 64 x 48.
const SPM_SCENE: &str = r#"
dimensions = 2
[time]
dt = 0.5
steps = 10
[fluid]
method = "spm"
grid = [64, 48]
viscosity = 1.0
[walls]
velocity = [-0.02, 0.02]
[[fibre]]
model = "cohesive-beam"
beads = 3
bead_radius = 3
youngs_modulus = 100
"#;

fn states(n: u64, v: f64) -> Vec<BeadState> {
    (0..3)
        .map(|i| BeadState {
            position: [20.0 + 6.0 * i as f64 + 0.01 * n as f64, 24.0, 0.0],
            orientation: [1.0, 0.0, 0.0, 0.0],
            velocity: [0.01 + v, 0.002 * i as f64, 0.0],
            angular_velocity: [0.0, 0.0, 0.001],
        })
        .collect()
}

/// Bits of 20 SPM steps (impulses, diagnostics, final velocity) with the grain fixed.
fn spm_bits(grain: usize) -> Vec<u64> {
    let (mut c, mut x, _) = configure(SPM_SCENE);
    c.fix_grain(grain);
    let mut bits = Vec::new();
    for n in 0..20 {
        let (imp, rep) = bead_step(&mut c, &mut x, n, &states(n, 0.0), &states(n, 1e-3));
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

/// Bits of 30 coupled FPD steps on a 64 x 640 channel with a moving 3-bead chain.
fn fpd_bits(grain: usize) -> Vec<u64> {
    set_grain(grain);
    let mut lat = MrtD2q9::new(MrtConfig::new(
        64,
        640,
        YBoundary::Walls {
            bottom: -0.01,
            top: 0.01,
        },
        0.1,
    ))
    .unwrap();
    let mut c = FpdCoupling::new(FpdConfig::new(4.0, 0.1), &mut lat, 3).unwrap();
    let mut pos = [[10.0, 100.0], [18.0, 100.5], [26.0, 101.0]];
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
    pos.iter()
        .chain(&v)
        .flatten()
        .map(|x| x.to_bits())
        .collect()
}

/// On two threads, the default grain (16 384: one task for the SPM grid, three for the
/// lattice) and a grain of 64 elements (many tasks) give the same bits, for the SPM step
/// (FFT lines, profiles, penalty, reductions) and the FPD lattice step.
#[test]
fn results_do_not_depend_on_the_grain() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.install(|| {
        let coarse = spm_bits(fluid_node::parallel::GRAIN);
        let fine = spm_bits(64);
        assert_eq!(coarse.len(), fine.len());
        assert!(coarse == fine, "SPM: the grain changed the bits");
        let coarse = fpd_bits(fluid_node::parallel::GRAIN);
        let fine = fpd_bits(64);
        assert!(coarse == fine, "FPD: the grain changed the bits");
    });
}
