//! The parallel grain, chosen at run time by timing steps.
//!
//! Whether sharing a small grid's loops between threads pays depends on the machine and on
//! what else runs on it at the moment: on one 2-core machine a grain of 4 096 cells made a
//! scene 30 % faster in one hour and 31 % slower in the next (docs/performance.md). So the
//! fluid node measures instead of guessing: it runs a few steps with each candidate grain,
//! keeps the fastest for a while, and measures again. The grain decides only how rows are
//! shared among threads, never a result: reductions go through per-row partial results
//! (`parallel.rs`) and each FFT line is transformed whole, so every run gives the same bits
//! whatever grain it chose.
use crate::parallel::GRAIN;

/// Grains tried, in elements per rayon task: the default first.
pub const CANDIDATES: [usize; 3] = [GRAIN, 4_096, 1_024];

/// Steps timed with each candidate; the median decides, so a step disturbed by another
/// process does not.
pub const TRIAL_STEPS: usize = 7;

/// Steps run with the chosen grain before the next trial, per step of a trial: the trials'
/// losers then cost at most about 1/40 of the run.
pub const STEPS_PER_TRIAL_STEP: usize = 40;

#[derive(Debug, Clone, Copy, PartialEq)]
enum State {
    /// One candidate only (one thread, or a grid large enough that all split alike).
    Fixed,
    /// Timing candidate `k`.
    Trial { k: usize },
    /// Running the chosen grain; the next trial in `left` steps.
    Chosen { left: usize },
}

/// Chooses the grain for a grid from the time of its steps; its owner passes
/// [`GrainTuner::grain`] on to `parallel::set_grain`. Allocates only when built.
#[derive(Debug, Clone)]
pub struct GrainTuner {
    /// Candidates that split the grid differently, in [`CANDIDATES`]'s order.
    candidates: Vec<usize>,
    /// Step times of the candidate on trial (s).
    samples: Vec<f64>,
    /// Median step time of each candidate at the last trial (s).
    medians: Vec<f64>,
    state: State,
    /// The grain to run the next step with.
    grain: usize,
}

impl GrainTuner {
    /// A tuner for a grid of `rows` rows of `row_len` elements, on rayon's current pool.
    pub fn new(rows: usize, row_len: usize) -> Self {
        let threads = rayon::current_num_threads().max(1);
        // Rows per task each candidate gives a whole-grid loop (parallel::min_len).
        let split = |g: usize| {
            (rows / (8 * threads))
                .max(g.div_ceil(row_len.max(1)))
                .max(1)
        };
        let mut candidates: Vec<usize> = Vec::with_capacity(CANDIDATES.len());
        if threads > 1 {
            for g in CANDIDATES {
                // One that splits a whole-grid loop into as many tasks as an earlier
                // candidate adds nothing to try.
                let tasks = rows.div_ceil(split(g));
                let same = candidates.iter().any(|&c| rows.div_ceil(split(c)) == tasks);
                if !same {
                    candidates.push(g);
                }
            }
        }
        let state = if candidates.len() > 1 {
            State::Trial { k: 0 }
        } else {
            State::Fixed
        };
        Self {
            grain: candidates.first().copied().unwrap_or(GRAIN),
            medians: vec![f64::INFINITY; candidates.len()],
            candidates,
            samples: Vec::with_capacity(TRIAL_STEPS),
            state,
        }
    }

    /// The grains this tuner chooses among (one or none: it never changes the grain).
    pub fn candidates(&self) -> &[usize] {
        &self.candidates
    }

    /// The grain to run the next step with.
    pub fn grain(&self) -> usize {
        self.grain
    }

    /// The median step time of each candidate at the last trial (s; infinite before).
    pub fn medians(&self) -> &[f64] {
        &self.medians
    }

    /// Record that a step took `seconds` (of the node's own work); may change [`Self::grain`].
    pub fn end_step(&mut self, seconds: f64) {
        match self.state {
            State::Fixed => {}
            State::Trial { k } => {
                self.samples.push(seconds);
                if self.samples.len() < TRIAL_STEPS {
                    return;
                }
                self.samples.sort_unstable_by(f64::total_cmp);
                self.medians[k] = self.samples[TRIAL_STEPS / 2];
                self.samples.clear();
                if k + 1 < self.candidates.len() {
                    self.grain = self.candidates[k + 1];
                    self.state = State::Trial { k: k + 1 };
                } else {
                    // The first of equals: the default wins ties.
                    let best = (0..self.candidates.len())
                        .min_by(|&a, &b| self.medians[a].total_cmp(&self.medians[b]))
                        .unwrap_or(0);
                    self.grain = self.candidates[best];
                    self.state = State::Chosen {
                        left: STEPS_PER_TRIAL_STEP * TRIAL_STEPS * self.candidates.len(),
                    };
                }
            }
            State::Chosen { left } => {
                if left > 1 {
                    self.state = State::Chosen { left: left - 1 };
                } else {
                    self.grain = self.candidates[0];
                    self.state = State::Trial { k: 0 };
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn on_two_threads<R: Send>(f: impl FnOnce() -> R + Send) -> R {
        rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap()
            .install(f)
    }

    /// On two threads a 100 x 200 lattice splits differently under each candidate, a
    /// 128 x 14 400 one (3D, 128 x 120 x 120) under none, and one thread never tunes.
    #[test]
    fn only_grids_that_split_differently_are_tuned() {
        on_two_threads(|| {
            assert_eq!(GrainTuner::new(200, 100).candidates(), &CANDIDATES);
            assert_eq!(GrainTuner::new(14_400, 128).candidates().len(), 1);
        });
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| assert!(GrainTuner::new(200, 100).candidates().is_empty()));
    }

    /// The fastest candidate by median is chosen after one trial each, a disturbed step does
    /// not move the choice, and the next trial starts after the chosen stretch.
    #[test]
    fn the_fastest_median_wins_and_is_tried_again_later() {
        on_two_threads(|| {
            let mut t = GrainTuner::new(200, 100);
            let n = t.candidates().len();
            // Candidate 1 is fastest; one of its steps is disturbed (10 s).
            let cost = [2.0, 1.0, 3.0];
            for k in 0..n {
                assert_eq!(t.grain(), t.candidates()[k]);
                for s in 0..TRIAL_STEPS {
                    t.end_step(if k == 1 && s == 3 { 10.0 } else { cost[k] });
                }
            }
            assert_eq!(t.medians(), &cost[..n]);
            assert_eq!(t.grain(), t.candidates()[1]);
            let chosen = STEPS_PER_TRIAL_STEP * TRIAL_STEPS * n;
            for _ in 0..chosen - 1 {
                t.end_step(5.0);
                assert_eq!(t.grain(), t.candidates()[1]);
            }
            t.end_step(5.0);
            assert_eq!(t.grain(), t.candidates()[0], "a new trial starts");
        });
    }
}
