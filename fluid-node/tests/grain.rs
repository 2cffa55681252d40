//! The parallel grain (elements per rayon task, `fluid_node::parallel::grain`) decides only
//! how rows are shared among threads: runs with a coarse and a fine grain give the same bits.
//! The fluid node chooses the grain at run time from the time of its steps
//! (`fluid_node::grain_tuner`), so a result must not depend on it.
//!
//! One test in its own binary: the grain is process-wide, and another test running beside
//! this one would change it.
mod common;
use common::*;
use fluid_node::parallel::{set_grain, GRAIN};

/// Bits of 20 SPM steps of `FIBRE_SCENE` (impulses, diagnostics, final velocity) with the
/// grain fixed.
fn spm_bits(grain: usize) -> Vec<u64> {
    let (mut c, mut x, _) = configure(FIBRE_SCENE);
    c.fix_grain(grain);
    run(&mut c, &mut x, 0, 20)
}

/// On two threads, the default grain (16 384: one task for the 48 x 40 SPM grid, three for
/// the 64 x 640 lattice) and a grain of 64 elements (many tasks) give the same bits, for the
/// SPM step (FFT lines, profiles, penalty, reductions) and the FPD lattice step.
#[test]
fn results_do_not_depend_on_the_grain() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    pool.install(|| {
        let (coarse, fine) = (spm_bits(GRAIN), spm_bits(64));
        assert_eq!(coarse.len(), fine.len());
        assert!(coarse == fine, "SPM: the grain changed the bits");
        set_grain(GRAIN);
        let coarse = fpd_chain_run(4.0);
        set_grain(64);
        let fine = fpd_chain_run(4.0);
        assert_eq!(coarse, fine, "FPD: the grain changed the bits");
    });
}
