//! The FPD coupling of S2023 (eqs. 1, 2, 4, 5) on the MRT D2Q9 solver: exactness of the
//! force spread and the velocity average, momentum balance, the internal flow of eq. 15, and
//! the hydrodynamic radius of a bead against the Sangani–Acrivos drag of a square array of
//! cylinders (REFERENCE.md section 2). Lattice units throughout (dx = dt = 1).
mod common;
use common::fpd_chain_run;
use fluid_node::fpd::{FpdConfig, FpdCoupling, FpdError};
use fluid_node::mrt_d2q9::{MrtConfig, MrtD2q9, YBoundary};
use std::cell::Cell;
use std::f64::consts::PI;

/// Counts the allocations made by the current thread, to check that per-step calls make none.
struct CountingAlloc;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

unsafe impl std::alloc::GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // try_with: the thread-local may be gone while a thread is torn down.
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { std::alloc::System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { std::alloc::System.realloc(ptr, layout, size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAlloc = CountingAlloc;

fn periodic(n: usize, nu: f64) -> MrtD2q9 {
    MrtD2q9::new(MrtConfig::new(n, n, YBoundary::Periodic, nu)).unwrap()
}

fn channel(nx: usize, ny: usize, nu: f64, bottom: f64, top: f64) -> MrtD2q9 {
    MrtD2q9::new(MrtConfig::new(nx, ny, YBoundary::Walls { bottom, top }, nu)).unwrap()
}

/// Sum of a field in index order.
fn sum(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a, b| a + b)
}

/// Total momentum sum rho u over the lattice (cell volume 1), in index order.
fn momentum(s: &MrtD2q9) -> [f64; 2] {
    let n = s.nx() * s.ny();
    let (mut rho, mut ux, mut uy) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    s.fields(&mut rho, &mut ux, &mut uy);
    let px = (0..n).fold(0.0, |a, k| a + rho[k] * ux[k]);
    let py = (0..n).fold(0.0, |a, k| a + rho[k] * uy[k]);
    [px, py]
}

/// Bad input is an error naming what is wrong, never a panic, and changes nothing.
#[test]
fn bad_input_is_refused() {
    let mut lat = periodic(32, 0.1);
    let bad = |f: fn(&mut FpdConfig)| {
        let mut c = FpdConfig::new(4.0, 0.1);
        f(&mut c);
        c
    };
    for (cfg, name) in [
        (bad(|c| c.viscosity_ratio = 0.5), "viscosity_ratio"),
        (bad(|c| c.viscosity_ratio = f64::NAN), "viscosity_ratio"),
        (bad(|c| c.radius = 0.2), "radius"),
        (bad(|c| c.interface_ratio = 0.0), "interface_ratio"),
        (bad(|c| c.cutoff = -1.0), "cutoff"),
        (bad(|c| c.fluid_viscosity = -0.1), "fluid_viscosity"),
        // nu_s = 1e18 puts s_q at 2 to round-off.
        (bad(|c| c.viscosity_ratio = 1e19), "viscosity_ratio"),
        (
            bad(|c| c.background_force = [0.0, f64::INFINITY]),
            "background_force.y",
        ),
    ] {
        match FpdCoupling::new(cfg, &mut lat, 1) {
            Err(FpdError::Parameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: expected a parameter error, got {other:?}"),
        }
    }
    // A box of 2 (4 + 5) + 1 = 19 nodes does not fit 16 periodic rows.
    let mut small = MrtD2q9::new(MrtConfig::new(32, 16, YBoundary::Periodic, 0.1)).unwrap();
    let e = FpdCoupling::new(FpdConfig::new(4.0, 0.1), &mut small, 1).unwrap_err();
    assert!(
        matches!(e, FpdError::LatticeTooSmall { extent: 19, .. }),
        "{e}"
    );
    // A box too wide to count (its extent once wrapped round to zero, passed, and the run
    // then ran out of memory) is refused as well.
    let mut huge = FpdConfig::new(4.0, 0.1);
    huge.interface_ratio = 1e300;
    let e = FpdCoupling::new(huge, &mut small, 1).unwrap_err();
    assert!(matches!(e, FpdError::LatticeTooSmall { .. }), "{e}");
    // Between walls the box is clipped instead: 16 rows are enough.
    let mut ch = channel(32, 16, 0.1, 0.0, 0.0);
    let mut c = FpdCoupling::new(FpdConfig::new(4.0, 0.1), &mut ch, 2).unwrap();
    let e = c
        .apply(&mut ch, &[[3.0, 3.0], [5.0, 16.0]], &[[0.0; 2]; 2])
        .unwrap_err();
    assert!(matches!(e, FpdError::BeadOutside { bead: 1, .. }), "{e}");
    let e = c.apply(&mut ch, &[[3.0, 3.0]], &[[0.0; 2]]).unwrap_err();
    assert!(matches!(e, FpdError::Count { got: 1, .. }), "{e}");
    let e = c
        .apply(
            &mut ch,
            &[[3.0, 3.0], [5.0, 5.0]],
            &[[0.0; 2], [f64::NAN, 0.0]],
        )
        .unwrap_err();
    assert!(matches!(e, FpdError::NotFinite { bead: 1, .. }), "{e}");
    assert_eq!(c.centre(0), None, "nothing placed after errors");
    let mut v = [[0.0; 2]; 2];
    assert_eq!(c.bead_velocities(&ch, &mut v), Err(FpdError::NotPlaced));
    assert!(matches!(
        c.bead_velocities(&lat, &mut v),
        Err(FpdError::LatticeMismatch { .. })
    ));
    eprintln!("example message: {e}");
}

/// S2023 eq. 4 puts exactly F_i into the fluid: the force field sums to sum_i F_i plus the
/// background on every node, to round-off, for beads that wrap across the periodic x
/// boundary, are cut by a wall, or overlap; and moving the beads restores the background at
/// every node they left (exact equality). Tolerance: the a-priori bound on the round-off of
/// an n-term sum, n eps sum_k |f_k| (Higham), with n the number of nodes.
#[test]
fn spread_force_sums_to_the_bead_forces() {
    let (nx, ny) = (48, 30);
    let mut lat = channel(nx, ny, 0.1, 0.01, -0.02);
    let mut cfg = FpdConfig::new(4.0, 0.1);
    let bg = [3e-7, -2e-7];
    cfg.background_force = bg;
    let mut c = FpdCoupling::new(cfg, &mut lat, 3).unwrap();
    let forces = [[1.3e-3, -0.7e-3], [-2.1e-3, 0.4e-3], [0.5e-3, 1.9e-3]];
    let expected = |k: usize| {
        let f = forces.iter().fold(0.0, |a, f| a + f[k]);
        f + (nx * ny) as f64 * bg[k]
    };
    for (step, positions) in [
        // Across x = 0; cut by the bottom wall; overlapping the first.
        [[0.3, 10.2], [20.7, 0.1], [7.6, 12.9]],
        [[-3.4, 22.5], [30.25, 29.5], [41.0, -0.5]],
        [[47.9, 15.0], [24.0, 15.0], [47.9 + 8.0, 15.0]],
    ]
    .iter()
    .enumerate()
    {
        c.apply(&mut lat, positions, &forces).unwrap();
        let (fx, fy) = lat.force();
        let err = [(sum(fx) - expected(0)).abs(), (sum(fy) - expected(1)).abs()];
        let bound =
            |f: &[f64]| (nx * ny) as f64 * f64::EPSILON * f.iter().map(|v| v.abs()).sum::<f64>();
        let tol = [bound(fx), bound(fy)];
        eprintln!(
            "placement {step}: |sum f - sum F - N bg| = {:.1e}, {:.1e} (bounds {:.1e}, {:.1e}); \
             profile sums {:.4} {:.4} {:.4} (pi a^2 = {:.4})",
            err[0],
            err[1],
            tol[0],
            tol[1],
            c.profile_volume(0),
            c.profile_volume(1),
            c.profile_volume(2),
            PI * 16.0
        );
        assert!(err[0] <= tol[0] && err[1] <= tol[1], "{err:?} > {tol:?}");
        // Nodes no bead reaches hold the background exactly.
        let mut inside = vec![false; nx * ny];
        for b in 0..3 {
            c.for_each_node(b, |x, y, _, _| inside[y * nx + x] = true)
                .unwrap();
        }
        for k in (0..nx * ny).filter(|&k| !inside[k]) {
            assert_eq!((fx[k], fy[k]), (bg[0], bg[1]), "node {k}");
        }
        // The total phi of eq. 1 is clamped to [0, 1] and the viscosity follows it.
        let nu = lat.viscosity();
        for (k, &p) in c.solid_fraction().iter().enumerate() {
            assert!((0.0..=1.0).contains(&p));
            assert_eq!(nu[k], 0.1 + (10.0 - 0.1) * p);
        }
    }
}

/// S2023 eq. 5 on prescribed flows (no step taken). Uniform flow: the weighted mean returns
/// it to round-off (tolerance 1e-15 absolute at |u| = 0.03). Linear shear u_x = g (y - y0),
/// u_y = -g' (x - x0): the mean is the value at the centre when the sampled profile is
/// symmetric about it (centre on a node or half-way between nodes; tolerance 1e-15), and
/// elsewhere differs by the lattice's first-moment error of the profile sum_r phi_i (r - R):
/// the aliasing of the profile by the unit lattice, of relative size exp(-pi^2 xi) = 5e-5
/// for xi = 1 (the Fourier transform of the tanh edge decays as exp(-pi k xi / 2), k = 2 pi
/// the first alias); tolerance 2e-4 of g a. A rigid rotation about a symmetric centre is
/// returned as such by `rigid_motion` (tolerance 1e-13 on omega, round-off on V), with an
/// internal flow eps_v of zero to round-off.
#[test]
fn weighted_mean_of_prescribed_flows() {
    let (nx, ny) = (40, 40);
    let mut lat = channel(nx, ny, 0.1, 0.0, 0.0);
    let a = 4.0;
    let mut c = FpdCoupling::new(FpdConfig::new(a, 0.1), &mut lat, 1).unwrap();
    let mut v = [[0.0; 2]];
    let (u0, v0) = (0.03, -0.02);
    lat.initialize_with(|_, _| (1.0, u0, v0)).unwrap();
    for p in [[0.0, 10.0], [13.37, 20.61], [39.9, 0.0]] {
        c.apply(&mut lat, &[p], &[[0.0; 2]]).unwrap();
        c.bead_velocities(&lat, &mut v).unwrap();
        assert!((v[0][0] - u0).abs() < 1e-15 && (v[0][1] - v0).abs() < 1e-15);
    }
    let (g, h, x0, y0) = (1e-3, 7e-4, 17.0, 19.5);
    lat.initialize_with(|x, y| (1.0, g * (y as f64 - y0), -h * (x as f64 - x0)))
        .unwrap();
    let centre_value = |p: [f64; 2]| [g * (p[1] - y0), -h * (p[0] - x0)];
    let mut worst_off: f64 = 0.0;
    for (p, symmetric) in [
        ([20.0, 20.0], true),
        ([20.5, 20.5], true),
        ([21.0, 19.5], true),
        ([20.3, 20.1], false),
        ([19.77, 21.41], false),
        ([22.5, 18.25], false),
    ] {
        c.apply(&mut lat, &[p], &[[0.0; 2]]).unwrap();
        c.bead_velocities(&lat, &mut v).unwrap();
        let e = centre_value(p);
        let err = (v[0][0] - e[0]).abs().max((v[0][1] - e[1]).abs());
        eprintln!(
            "shear, bead at {p:?}: |V - u(R)| = {err:.2e} ({:.2e} g a)",
            err / (g * a)
        );
        if symmetric {
            assert!(err < 1e-15, "{p:?}: {err:e}");
        } else {
            worst_off = worst_off.max(err / (g * a));
        }
    }
    assert!(worst_off < 2e-4, "off-lattice centre: {worst_off:e} g a");
    // Rigid rotation omega about a half-node centre.
    let (w, cx, cy) = (2e-3, 20.5, 20.0);
    lat.initialize_with(|x, y| (1.0, -w * (y as f64 - cy), w * (x as f64 - cx)))
        .unwrap();
    c.apply(&mut lat, &[[cx, cy]], &[[0.0; 2]]).unwrap();
    let (vel, omega) = c.rigid_motion(&lat, 0).unwrap();
    let eps = c.internal_flow(&lat, 0, vel, omega).unwrap();
    eprintln!(
        "rotation: V = {vel:?}, omega / w - 1 = {:.1e}, eps_v = {eps:.1e}",
        omega / w - 1.0
    );
    assert!(vel[0].abs() < 1e-15 && vel[1].abs() < 1e-15);
    assert!((omega / w - 1.0).abs() < 1e-13);
    assert!(eps < 1e-30);
}

/// Momentum balance in a fully periodic box: Guo's forcing adds F to the momentum of a node
/// per step and streaming only moves it, so the total momentum grows by sum_i F_i per step
/// exactly, however the bead moves (S2023 eq. 5 moves it here). Reference: P(t) - P(0) =
/// F t; tolerance 1e-12 relative (round-off over 400 steps of a 1024-node sum).
#[test]
fn momentum_grows_by_force_times_time() {
    let n = 32;
    let mut lat = periodic(n, 0.1);
    let mut c = FpdCoupling::new(FpdConfig::new(3.0, 0.1), &mut lat, 1).unwrap();
    let f = [2e-4, -1e-4];
    let mut pos = [[10.3, 30.9]];
    let mut v = [[0.0; 2]];
    c.apply(&mut lat, &pos, &[f]).unwrap();
    let p0 = momentum(&lat);
    let steps = 400;
    for _ in 0..steps {
        c.apply(&mut lat, &pos, &[f]).unwrap();
        lat.step();
        c.bead_velocities(&lat, &mut v).unwrap();
        // Exaggerated displacement, to sweep the profile across nodes and the boundary.
        pos[0][0] += 20.0 * v[0][0];
        pos[0][1] += 20.0 * v[0][1];
    }
    let p = momentum(&lat);
    let t = steps as f64;
    let err = [
        (p[0] - p0[0]) / (f[0] * t) - 1.0,
        (p[1] - p0[1]) / (f[1] * t) - 1.0,
    ];
    eprintln!(
        "momentum: P - P0 = {:?}, F t = {:?}, relative error {:.1e} {:.1e}, bead at {:?}",
        [p[0] - p0[0], p[1] - p0[1]],
        [f[0] * t, f[1] * t],
        err[0],
        err[1],
        pos[0]
    );
    assert!(err[0].abs() < 1e-12 && err[1].abs() < 1e-12);
}

/// Sangani–Acrivos drag of a square array of cylinders at area fraction c (REFERENCE.md
/// section 2): F / (mu U).
fn sangani_acrivos(c: f64) -> f64 {
    4.0 * PI / (-0.5 * c.ln() - 0.738 + c - 0.887 * c * c + 2.038 * c.powi(3))
}

/// Radius whose square array of period `l` has drag `k` = F / (mu U), by bisection.
fn radius_for_drag(k: f64, l: f64) -> f64 {
    let (mut lo, mut hi) = (0.05 * l, 0.4 * l);
    for _ in 0..60 {
        let m = 0.5 * (lo + hi);
        if sangani_acrivos(PI * m * m / (l * l)) < k {
            lo = m;
        } else {
            hi = m;
        }
    }
    0.5 * (lo + hi)
}

struct Drag {
    /// F / (mu U).
    k: f64,
    /// S2023 eq. 15 relative to the bead velocity, over U^2.
    eps_over_u2: f64,
    /// |total momentum| / (F t) at the end.
    momentum: f64,
    steps: u64,
}

/// A bead driven by F through a periodic l x l box whose fluid carries the balancing
/// background -F / l^2 (the mean pressure gradient of a periodic array: zero total force),
/// moved by eq. 5 until its velocity changes by less than 5e-5 relative over 1000 steps
/// (the bead moves across the lattice, and its velocity varies with its position relative
/// to the nodes by about 1e-5).
fn driven_bead(l: usize, a: f64, nu: f64, r_eta: f64, r_xi: f64, f: f64) -> Drag {
    let mut lat = periodic(l, nu);
    let mut cfg = FpdConfig::new(a, nu);
    cfg.viscosity_ratio = r_eta;
    cfg.interface_ratio = r_xi;
    cfg.background_force = [-f / (l * l) as f64, 0.0];
    let mut c = FpdCoupling::new(cfg, &mut lat, 1).unwrap();
    let mut pos = [[0.5 * l as f64 + 0.3, 0.5 * l as f64 + 0.1]];
    let mut v = [[0.0; 2]];
    let mut last = f64::INFINITY;
    loop {
        for _ in 0..1000 {
            c.apply(&mut lat, &pos, &[[f, 0.0]]).unwrap();
            lat.step();
            c.bead_velocities(&lat, &mut v).unwrap();
            pos[0][0] += v[0][0];
            pos[0][1] += v[0][1];
        }
        if (v[0][0] / last - 1.0).abs() < 5e-5 {
            break;
        }
        last = v[0][0];
        assert!(lat.time() < 40_000, "no steady velocity: {v:?}");
    }
    let u = v[0][0];
    let eps = c.internal_flow(&lat, 0, v[0], 0.0).unwrap();
    let p = momentum(&lat);
    Drag {
        k: f / (nu * u),
        eps_over_u2: eps / (u * u),
        momentum: p[0].hypot(p[1]) / (f * lat.time() as f64),
        steps: lat.time(),
    }
}

/// The hydrodynamic radius of an FPD bead. A bead driven through a periodic 40 x 40 box
/// (a = 4, nu_f = 1/6, Re = 2 a U / nu_f ~ 0.015) reaches a steady velocity U; the drag
/// F / (mu U) is compared with Sangani–Acrivos (REFERENCE.md section 2) at the nominal
/// radius and inverted for the radius a_eff that gives the measured drag.
///
/// References and tolerances:
/// - momentum: the balanced background keeps the total momentum at zero to round-off
///   (tolerance 1e-12 of F t);
/// - a_eff - a scales with xi: (a_eff - a) / xi is the same for r_xi = 0.125 and 0.0625
///   within 0.1 (it is a property of the diffuse profile, not of the lattice);
/// - a_eff - a grows as (xi / 2) ln r_eta: outside the bead phi ~ exp(-2 s / xi), and the
///   layer behaves as solid out to where eta_s phi ~ eta_f, i.e. s ~ (xi / 2) ln r_eta
///   (a log-resistance estimate). Tolerance: the increase per decade of r_eta within 15 % of
///   (ln 10) / 2 = 1.151 (the estimate ignores the non-radial part of the flow);
/// - eq. 15's internal flow eps_v / U^2 (S2023 Fig. 3d) decreases as r_eta grows.
#[test]
fn driven_bead_drag_gives_the_hydrodynamic_radius() {
    let (l, a, nu, f) = (40usize, 4.0, 1.0 / 6.0, 1e-3);
    let c_nominal = PI * a * a / (l * l) as f64;
    let k_nominal = sangani_acrivos(c_nominal);
    let mut shift = Vec::new();
    let mut eps = Vec::new();
    for (r_eta, r_xi) in [
        (10.0, 0.125),
        (100.0, 0.125),
        (1000.0, 0.125),
        (100.0, 0.0625),
    ] {
        let d = driven_bead(l, a, nu, r_eta, r_xi, f);
        let xi = 2.0 * r_xi * a;
        let a_eff = radius_for_drag(d.k, l as f64);
        eprintln!(
            "r_eta {r_eta:>6}, r_xi {r_xi:.4}: F/(mu U) = {:.4}, Sangani-Acrivos at a: {:.4} \
             (ratio {:.4}); a_eff = {a_eff:.4} = a + {:.3} xi; eps_v / U^2 = {:.3e}; \
             |P| / (F t) = {:.1e}; {} steps",
            d.k,
            k_nominal,
            d.k / k_nominal,
            (a_eff - a) / xi,
            d.eps_over_u2,
            d.momentum,
            d.steps
        );
        assert!(d.momentum < 1e-12, "momentum {:e}", d.momentum);
        shift.push((a_eff - a) / xi);
        eps.push(d.eps_over_u2);
    }
    let half_ln10 = 0.5 * 10f64.ln();
    let slopes = [shift[1] - shift[0], shift[2] - shift[1]];
    eprintln!(
        "(a_eff - a) / xi per decade of r_eta: {:.3}, {:.3} (estimate {half_ln10:.3}); \
         at r_eta 100: {:.3} (r_xi 0.125), {:.3} (r_xi 0.0625)",
        slopes[0], slopes[1], shift[1], shift[3]
    );
    for s in slopes {
        assert!((s / half_ln10 - 1.0).abs() < 0.15, "slope {s}");
    }
    assert!((shift[1] - shift[3]).abs() < 0.1);
    assert!(eps[0] > eps[1] && eps[1] > eps[2], "eps_v {eps:?}");
}

/// Internal flow of a free cylinder at the centre of a Couette channel (walls at +-U,
/// 48 x 40 nodes, a = 4, shear rate 2U/H = 1e-4, Re_p = gamma d^2 / nu ~ 0.04): S2023 eq. 15
/// measured relative to the bead's rigid motion (its velocity and angular velocity from
/// `rigid_motion`, since a free cylinder in shear rotates), normalised by (gamma a)^2. It
/// must decrease as r_eta grows and as r_xi = xi / d shrinks (S2023 section III B, Fig. 3d,e:
/// the FPD bead tends to a rigid body as r_eta -> infinity and r_xi -> 0); the rotation rate
/// is reported against -gamma / 2, the unbounded Stokes value (confinement d/H = 0.2 lowers
/// it slightly).
#[test]
fn internal_flow_of_a_cylinder_in_shear_decreases_with_viscosity_ratio() {
    let (nx, ny, a, nu) = (48, 40, 4.0, 1.0 / 6.0);
    let u = 2e-3;
    let gamma = 2.0 * u / ny as f64;
    let mut results = Vec::new();
    let cases = [
        (10.0, 0.125),
        (100.0, 0.125),
        (1000.0, 0.125),
        (100.0, 0.25),
        (100.0, 0.0625),
    ];
    for (r_eta, r_xi) in cases {
        let mut lat = channel(nx, ny, nu, -u, u);
        lat.initialize_with(|_, y| (1.0, -u + gamma * (y as f64 + 0.5), 0.0))
            .unwrap();
        let mut cfg = FpdConfig::new(a, nu);
        cfg.viscosity_ratio = r_eta;
        cfg.interface_ratio = r_xi;
        let mut c = FpdCoupling::new(cfg, &mut lat, 1).unwrap();
        // Centre of the channel, whose walls lie at y = -1/2 and ny - 1/2.
        let pos = [[24.0, 0.5 * ny as f64 - 0.5]];
        c.apply(&mut lat, &pos, &[[0.0; 2]]).unwrap();
        let mut last = f64::INFINITY;
        let (v, omega) = loop {
            lat.run(1000);
            let (v, omega) = c.rigid_motion(&lat, 0).unwrap();
            if (omega / last - 1.0).abs() < 1e-7 {
                break (v, omega);
            }
            last = omega;
            assert!(lat.time() < 60_000, "no steady rotation");
        };
        let eps = c.internal_flow(&lat, 0, v, omega).unwrap() / (gamma * a).powi(2);
        eprintln!(
            "r_eta {r_eta:>6}, r_xi {r_xi:>6}: omega / gamma = {:.4}, |V| / (gamma a) = {:.1e}, \
             eps_v / (gamma a)^2 = {eps:.3e}, {} steps",
            omega / gamma,
            v[0].hypot(v[1]) / (gamma * a),
            lat.time()
        );
        results.push(eps);
    }
    // Along r_eta at r_xi = 0.125, then along r_xi at r_eta = 100.
    assert!(
        results[0] > results[1] && results[1] > results[2],
        "{results:?}"
    );
    assert!(
        results[3] > results[1] && results[1] > results[4],
        "{results:?}"
    );
}

/// Coupled steps give the same bits with 1 and 3 threads: every FPD sum runs in a fixed
/// order, and the solver's own loops are row-parallel without shared reductions. Beads of
/// radius 4 have their boxes computed one after the other, beads of radius 8 in parallel.
#[test]
fn coupled_steps_do_not_depend_on_threads() {
    for a in [4.0, 8.0] {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| fpd_chain_run(a))
        };
        let (one, three) = (run(1), run(3));
        assert_eq!(one, three, "a = {a}");
    }
}

/// The per-step calls (`apply`, `bead_velocities`, `rigid_motion`, `internal_flow`) allocate
/// nothing after planning. Counted on this thread, inside a one-thread pool so that the
/// solver's parallel viscosity update runs here too.
#[test]
fn per_step_calls_do_not_allocate() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    // Radius 4: the beads' boxes one after the other; radius 8: in parallel.
    for a in [4.0, 8.0] {
        pool.install(|| per_step_calls_allocate_nothing(a));
    }
}

/// [`per_step_calls_do_not_allocate`] for beads of radius `a`.
fn per_step_calls_allocate_nothing(a: f64) {
    let mut lat = channel(40, 40, 0.1, 0.0, 0.01);
    let mut c = FpdCoupling::new(FpdConfig::new(a, 0.1), &mut lat, 4).unwrap();
    let mut pos = [[1.0, 1.0], [9.0, 1.5], [17.0, 2.0], [39.5, 38.0]];
    let forces = [[1e-4, 2e-4]; 4];
    let mut v = [[0.0; 2]; 4];
    c.apply(&mut lat, &pos, &forces).unwrap();
    let before = ALLOCATIONS.with(|n| n.get());
    for step in 0..50 {
        c.apply(&mut lat, &pos, &forces).unwrap();
        lat.step();
        c.bead_velocities(&lat, &mut v).unwrap();
        let (w, om) = c.rigid_motion(&lat, step % 4).unwrap();
        c.internal_flow(&lat, step % 4, w, om).unwrap();
        for p in pos.iter_mut() {
            p[0] += 0.37;
            p[1] = (p[1] + 0.29).min(39.0);
        }
    }
    let after = ALLOCATIONS.with(|n| n.get());
    assert_eq!(
        after - before,
        0,
        "allocations in per-step calls, radius {a}"
    );
}

/// After the first full write, `update_viscosity` touches only the previous and new boxes;
/// the field it leaves must equal eq. 1 evaluated everywhere, bit for bit, as beads move
/// (wrapping in x, overlapping each other).
#[test]
fn sparse_viscosity_update_equals_a_full_rebuild() {
    let (nx, ny) = (48, 40);
    let mut lat = channel(nx, ny, 0.1, 0.0, 0.0);
    let cfg = FpdConfig::new(3.0, 0.1);
    let mut c = FpdCoupling::new(cfg, &mut lat, 3).unwrap();
    let mut full = channel(nx, ny, 0.1, 0.0, 0.0);
    for n in 0..12 {
        let t = n as f64;
        let pos = [
            [5.0 + 3.7 * t, 20.0],
            [9.0 + 3.7 * t, 21.5 - 0.5 * t],
            [46.0 - 2.1 * t, 8.0 + 1.3 * t],
        ];
        c.place(&pos).unwrap();
        c.update_viscosity(&mut lat).unwrap();
        full.set_viscosity_from_fraction(
            c.solid_fraction(),
            cfg.fluid_viscosity,
            cfg.solid_viscosity(),
        )
        .unwrap();
        assert!(
            lat.viscosity() == full.viscosity(),
            "step {n}: the sparse update differs from the full one"
        );
    }
}
