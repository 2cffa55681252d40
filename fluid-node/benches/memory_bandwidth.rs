//! The machine's sustainable memory bandwidth, for the share of it the lattice kernel reaches
//! (docs/performance.md): the STREAM triad a = b + s c on three arrays of 2^23 doubles
//! (64 MiB each, far beyond the caches), split into rows over rayon threads like the
//! lattice step, on 1 and 2 threads.
//!
//! Throughput counts 24 bytes per element (two reads, one write), STREAM's convention; a
//! write-allocating cache also reads `a`, so the bus moves up to 32 bytes per element.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use rayon::prelude::*;
use std::time::Duration;

const N: usize = 1 << 23;
const CHUNK: usize = 1 << 14;

fn triad(a: &mut [f64], b: &[f64], c: &[f64], s: f64) {
    a.par_chunks_mut(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .zip(c.par_chunks(CHUNK))
        .for_each(|((a, b), c)| {
            for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                *a = b + s * c;
            }
        });
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("memory_bandwidth");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Bytes((24 * N) as u64));
    let (mut a, b, cc) = (vec![0.0; N], vec![1.0; N], vec![2.0; N]);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        group.bench_function(format!("stream_triad_{threads}_threads"), |bch| {
            pool.install(|| bch.iter(|| triad(&mut a, &b, &cc, 3.0)))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
