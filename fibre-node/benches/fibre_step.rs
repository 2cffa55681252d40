//! Time of one full fibre step (fibre-positions + fibre-velocities, including the bead-state
//! publications on an in-process exchange), 3D, for both models at 10, 100 and 1000 beads.
//! Throughput is reported per bead. Also the full check of the `self_overlap` diagnostic on a
//! coil that overlaps itself (so that no check is skipped), 3D, 1000 and 100 000 beads, with
//! its pair list kept (the coil at rest) and rebuilt at every check (the coil shifted). And
//! one step of a dry suspension of 10-bead fibres, 3D, 100 and 1000 fibres, with and without
//! `fibre.N.fibre_contact` (the `fibre_overlap` diagnostic measured in both). And the step
//! of a 1000- and a 10 000-bead bead-spring fibre with `fibre.N.self_contact`.
use cosim::{Component, InProcessExchange, Phase, PhaseReport};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use fibre_node::quaternion::Vec3;
use fibre_node::self_overlap::SelfOverlap;
use fibre_node::xorshift::Xorshift;
use fibre_node::FibreComponent;

fn scene(model: &str, beads: usize, dt: f64) -> String {
    format!(
        "[time]\ndt = {dt}\n[[fibre]]\nmodel = \"{model}\"\nbeads = {beads}\nbead_radius = 1\n\
         youngs_modulus = 1\nclamp = [0]\nloads = [{{ bead = -1, force = [0, -1e-3, 1e-3], \
         torque = [{}, 0, 0] }}]\n",
        if model == "cohesive-beam" { 1e-3 } else { 0.0 }
    )
}

fn configured(model: &str, beads: usize, extra: &str) -> (FibreComponent, InProcessExchange) {
    let mut c = FibreComponent::new();
    let mut x = InProcessExchange::new();
    let cfg = c
        .configure(&(scene(model, beads, 1e-9) + extra), &mut x)
        .unwrap();
    let limit = cfg.time_step_limits[0].1;
    c.configure(&(scene(model, beads, 0.5 * limit) + extra), &mut x)
        .unwrap();
    (c, x)
}

/// One fibre-node step (both fibre phases) of a component configured alone.
fn one_step(comp: &mut FibreComponent, x: &mut InProcessExchange, n: &mut u64) -> PhaseReport {
    comp.run_phase(*n, Phase::FibrePositions, x).unwrap();
    let r = comp.run_phase(*n, Phase::FibreVelocities, x).unwrap();
    *n += 1;
    std::hint::black_box(r)
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("fibre_step_3d");
    for model in ["cohesive-beam", "bead-spring"] {
        for beads in [10usize, 100, 1000] {
            let (mut comp, mut x) = configured(model, beads, "");
            let mut n = 0u64;
            group.throughput(Throughput::Elements(beads as u64));
            group.bench_with_input(BenchmarkId::new(model, beads), &beads, |b, _| {
                b.iter(|| one_step(&mut comp, &mut x, &mut n))
            });
        }
    }
    group.finish();
}

/// A chain of touching unit beads on a random walk folded into a cube of about one bead
/// volume in 8 of space, so that it crosses itself everywhere (xorshift, fixed seed).
fn dense_coil(beads: usize) -> Vec<Vec3> {
    let side = 2.0 * (beads as f64 * 8.0).cbrt();
    let mut seed = Xorshift(0x2545_F491_4F6C_DD1D);
    let mut uniform = move || seed.uniform() - 0.5;
    let mut pos = vec![Vec3::new(0.5 * side, 0.5 * side, 0.5 * side)];
    let mut dir = Vec3::new(1.0, 0.0, 0.0);
    for _ in 1..beads {
        dir = (dir + Vec3::new(uniform(), uniform(), uniform())).normalize();
        let mut next = pos[pos.len() - 1] + dir * 2.0;
        for a in 0..3 {
            if next[a] < 0.0 || next[a] > side {
                dir[a] = -dir[a];
                next[a] = pos[pos.len() - 1][a] + dir[a] * 2.0;
            }
        }
        pos.push(next);
    }
    pos
}

/// The step of `bench` for a bead-spring fibre with `self_contact`: the straight fibre
/// bends without touching itself, so this is the cost of finding that no pair overlaps.
fn bench_self_contact(c: &mut Criterion) {
    let mut group = c.benchmark_group("self_contact_step_3d");
    for beads in [1000usize, 10_000] {
        let (mut comp, mut x) = configured("bead-spring", beads, "self_contact = true\n");
        let mut n = 0u64;
        group.throughput(Throughput::Elements(beads as u64));
        group.bench_with_input(BenchmarkId::new("bead-spring", beads), &beads, |b, _| {
            b.iter(|| one_step(&mut comp, &mut x, &mut n))
        });
    }
    group.finish();
}

fn bench_self_overlap(c: &mut Criterion) {
    let mut group = c.benchmark_group("self_overlap_full_check_3d");
    for beads in [1000usize, 100_000] {
        let pos = dense_coil(beads);
        let mut watch = SelfOverlap::new(beads, 1.0, 2.0, 3);
        assert!(watch.measure(&pos) > 0.0, "the coil must overlap itself");
        group.throughput(Throughput::Elements(beads as u64));
        group.bench_with_input(BenchmarkId::new("list-kept", beads), &beads, |b, _| {
            b.iter(|| std::hint::black_box(watch.measure(&pos)))
        });
        // The coil shifted back and forth by a radius: every check rebuilds the pair list.
        let moved: Vec<Vec3> = pos.iter().map(|p| p + Vec3::new(1.0, 0.0, 0.0)).collect();
        let mut flip = false;
        group.bench_with_input(BenchmarkId::new("list-rebuilt", beads), &beads, |b, _| {
            b.iter(|| {
                flip = !flip;
                std::hint::black_box(watch.measure(if flip { &moved } else { &pos }))
            })
        });
    }
    group.finish();
}

/// `fibres` straight 10-bead bead-spring fibres (unit beads, touching) at random places and
/// directions in a cube filled to a bead volume fraction of about 5 %, lightly damped, no
/// fluid (xorshift, fixed seed). Many start overlapping, so the contact has work to do.
fn suspension(fibres: usize, contact: bool) -> String {
    let beads = 10;
    let side = (fibres as f64 * beads as f64 * 4.19 / 0.05).cbrt();
    let mut seed = Xorshift(0x9E37_79B9_7F4A_7C15);
    let mut uniform = move || seed.uniform();
    let mut s = String::from("dimensions = 3\n[time]\ndt = 0.05\n");
    for _ in 0..fibres {
        let d = Vec3::new(uniform() - 0.5, uniform() - 0.5, uniform() - 0.5).normalize();
        let (x, y, z) = (side * uniform(), side * uniform(), side * uniform());
        s.push_str(&format!(
            "[[fibre]]\nmodel = \"bead-spring\"\nbeads = {beads}\nbead_radius = 1\n\
             youngs_modulus = 1\nstretch_stiffness = 4\nbending_stiffness = 1\n\
             damping = 0.1\nfibre_contact = {contact}\nstart = [{x}, {y}, {z}]\n\
             direction = [{}, {}, {}]\n",
            d.x, d.y, d.z
        ));
    }
    s
}

fn bench_suspension(c: &mut Criterion) {
    let mut group = c.benchmark_group("suspension_step_3d");
    for fibres in [100usize, 1000] {
        for contact in [false, true] {
            let mut comp = FibreComponent::new();
            let mut x = InProcessExchange::new();
            comp.configure(&suspension(fibres, contact), &mut x)
                .unwrap();
            let mut n = 0u64;
            group.throughput(Throughput::Elements(10 * fibres as u64));
            let id = if contact { "contact" } else { "no-contact" };
            group.bench_with_input(BenchmarkId::new(id, fibres), &fibres, |b, _| {
                b.iter(|| one_step(&mut comp, &mut x, &mut n))
            });
        }
    }
    group.finish();
}

criterion_group!(
    benches,
    bench,
    bench_self_contact,
    bench_self_overlap,
    bench_suspension
);
criterion_main!(benches);
