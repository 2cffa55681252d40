//! Time of one step of the MRT D2Q9 solver (fused stream, bounce-back and collision) on
//! 256 x 256 and 512 x 512 lattices between two sliding walls, with an FPD-like viscosity
//! field (tanh discs of viscosity ratio 50, S2023 eqs. 1–2) and a body force inside the
//! discs, on 1 and 2 rayon threads (REFERENCE.md section 7 quotes Ludwig's D2Q9 at 256^2).
//!
//! Throughput is per lattice node, so criterion's Melem/s are million lattice updates per
//! second (MLUPS).
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use fluid_node::mrt_d2q9::{MrtConfig, MrtD2q9, YBoundary};
use std::time::Duration;

fn solver(n: usize) -> MrtD2q9 {
    let walls = YBoundary::Walls {
        bottom: -0.02,
        top: 0.02,
    };
    let (nu_f, nu_s) = (0.02, 1.0);
    let mut s = MrtD2q9::new(MrtConfig::new(n, n, walls, nu_f)).unwrap();
    // Sixteen discs of radius n/25 on a 4 x 4 pattern, interface width xi = 2 (S2023 eq. 2).
    let (pitch, radius) = (n as f64 / 4.0, n as f64 / 25.0);
    let phi: Vec<f64> = (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f64, (k / n) as f64);
            (0..16)
                .map(|d| {
                    let cx = pitch * (0.5 + (d % 4) as f64);
                    let cy = pitch * (0.5 + (d / 4) as f64);
                    let r = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
                    0.5 * (((radius - r) / 2.0).tanh() + 1.0)
                })
                .sum::<f64>()
                .min(1.0)
        })
        .collect();
    s.set_viscosity_from_fraction(&phi, nu_f, nu_s).unwrap();
    let (fx, fy) = s.force_mut();
    for (k, p) in phi.iter().enumerate() {
        fx[k] = 1e-6 * p;
        fy[k] = -5e-7 * p;
    }
    s
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("lbm_step");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    for n in [256, 512] {
        group.throughput(Throughput::Elements((n * n) as u64));
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut s = solver(n);
            group.bench_function(format!("mrt_d2q9_{n}x{n}_{threads}_threads"), |b| {
                pool.install(|| b.iter(|| s.step()))
            });
            assert!(s.max_mach().is_finite());
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
