//! Pipelined steps: each node receives all its phases of a step in one request and runs them
//! in schedule order, waiting before a phase for the publication of the other node it reads.
//!
//! The schedule and its order are the coordinator's, as in a lock-step run; what changes is
//! who hands over. Lock-step, every phase goes out from the coordinator and its reply comes
//! back: ten hand-overs between processes in a five-phase SPM step. Pipelined, the node that
//! publishes an output wakes the node that reads it, and the coordinator hears back once per
//! node and step: four hand-overs on the step's critical path. Each node runs the same phases
//! on the same inputs, so the results are the same bits.
//!
//! Inputs a phase reads from an earlier step need no wait: a step starts only when every node
//! has answered the one before it. The one input from an earlier step that a later phase of
//! the other node overwrites, the bead states `fluid-phase-field` reads, the fluid node holds
//! already from the penalty of the step before; it reads them only on the first step of a run,
//! which is therefore run lock-step.
//!
//! The exception to "a step starts when the one before has ended": every node gets its next
//! batch together with the current one ([`Batches::run_step`] with `send_next`) and queues
//! it, so the nodes go on from step to step handing over to each other directly while the
//! coordinator collects the reports and reads the bead states of the step behind. This is
//! safe because every input a batch reads from the other node in its step is awaited by step
//! number, and the inputs from the step before (the bead states a lattice step reads) are
//! published by a phase that comes before one it awaits and overwritten only after it
//! (FPD: `fibre-advance` of n before `fibre-forces` of n + 1, the next states only after the
//! lattice step). The coordinator reads the states of step n by step
//! ([`cosim::Exchange::read_states_of_step`]), so the fibre node may already have published
//! those of n + 1. The runner allows it only where nothing happens between the steps that
//! would see a node's state move on: not before the last step, a checkpoint, a possible stop
//! at rest, or after Ctrl-C.
//!
//! Where the coordinator needs nothing between steps, a batch holds several steps
//! ([`Batches::run_steps`], sized by `runner::batch_steps`): step `n + j` of it awaits each
//! input `j` steps later than step `n`, and the node answers once for all of them. On a
//! 2-core machine the coordinator's request and reply per node and step (a few system calls
//! and wake-ups each) took a core from the fluid's threads: at 256 x 200 (plain SPM) the three
//! processes cost 7.4 % a step with one step per batch and 2.7-3.5 % with several
//! (docs/performance.md).
use crate::links::LinkFailure;
use crate::runner::{fail, node_failed, Node, RunError};
use cosim::{Awaited, Command, FullReports, Phase, PhaseOrder, PhaseReport, Port, Reply};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// How long the coordinator blocks on the node that finishes a step before it looks whether
/// another node has failed meanwhile (then the first would wait for it for ever).
const CHECK_OTHERS: Duration = Duration::from_millis(50);

/// One phase of a node's batch: the phase, the port whose publication it awaits, the node to
/// wake after it.
type Entry = (Phase, Option<Port>, Option<String>);

/// The batches of one schedule: for each node, its phases in order, with what each awaits.
pub(crate) struct Batches {
    /// Node index and its phases.
    per_node: Vec<(usize, Vec<Entry>)>,
    /// Which node runs each phase of the schedule, in schedule order.
    owner: Vec<usize>,
    schedule: Vec<Phase>,
    /// The nodes whose batches go out a step early (see [`Batches::can_go_early`]).
    early: Vec<usize>,
    /// The step whose batch went out early.
    sent_early: Option<u64>,
}

impl Batches {
    /// `owner[k]`: index of the node that runs `schedule[k]`; `names`: node names by index.
    pub(crate) fn new(schedule: &[Phase], owner: &[usize], names: &[String]) -> Self {
        let mut awaits = vec![None; schedule.len()];
        let mut wakes: Vec<Option<String>> = vec![None; schedule.len()];
        for (k, phase) in schedule.iter().enumerate() {
            let Some((port, _)) = phase.input(0) else {
                continue;
            };
            // The input is the latest publication on `port` before this phase in the step.
            let producer = (0..k).rev().find(|&j| schedule[j].output() == Some(port));
            if let Some(j) = producer.filter(|&j| owner[j] != owner[k]) {
                awaits[k] = Some(port);
                wakes[j] = Some(names[owner[k]].clone());
            }
        }
        let mut per_node: Vec<(usize, Vec<Entry>)> = Vec::new();
        for (k, &phase) in schedule.iter().enumerate() {
            let o = owner[k];
            let entry = (phase, awaits[k], wakes[k].clone());
            match per_node.iter_mut().find(|(n, _)| *n == o) {
                Some((_, list)) => list.push(entry),
                None => per_node.push((o, vec![entry])),
            }
        }
        let mut b = Self {
            per_node,
            owner: owner.to_vec(),
            schedule: schedule.to_vec(),
            early: Vec::new(),
            sent_early: None,
        };
        b.early = b
            .per_node
            .iter()
            .map(|(o, _)| *o)
            .filter(|&o| b.can_go_early(o))
            .collect();
        b
    }

    /// The batch of node `o` for `count` steps from `step`, reporting in full where `full`
    /// says.
    fn batch(&self, o: usize, (step, count): (u64, u64), full: FullReports) -> Command {
        let list = &self
            .per_node
            .iter()
            .find(|(n, _)| *n == o)
            .expect("a node of the plan")
            .1;
        let phases = list
            .iter()
            .map(|(phase, port, wake)| PhaseOrder {
                phase: *phase,
                awaits: port.map(|port| Awaited {
                    port,
                    step: phase.input(step).map_or(step, |(_, s)| s),
                }),
                then_wake: wake.clone(),
            })
            .collect();
        Command::RunPhases {
            step,
            phases,
            steps: count,
            full_reports: full,
        }
    }

    /// Whether node `o`'s batch may go out a step early: every phase of it that reads the other
    /// node's data of its step awaits it (by step number), so that it can never read the
    /// publication of the step before.
    fn can_go_early(&self, o: usize) -> bool {
        let list = &self
            .per_node
            .iter()
            .find(|(n, _)| *n == o)
            .expect("a node of the plan")
            .1;
        list.iter()
            .all(|(phase, awaits, _)| phase.input(0).is_none() || awaits.is_some())
    }

    /// Whether a batch may hold several steps: as for sending a step early, every phase of
    /// every node that reads another node's data awaits it by step number; or a node runs
    /// alone, and nobody else publishes.
    pub(crate) fn can_hold_steps(&self) -> bool {
        self.per_node.len() == 1 || self.early.len() == self.per_node.len()
    }

    /// Whether the batch of `step` went out early to some node.
    pub(crate) fn sent_early(&self, step: u64) -> bool {
        self.sent_early == Some(step)
    }

    /// Run `count` steps from `step`: send every node its batch (unless it went out with the
    /// step before), reporting in full where `full` says, collect the replies. With
    /// `send_next` (one step only), the nodes that can start the next step alone get its
    /// batch now too; the caller must then run that step. Returns the phases' reports in
    /// schedule order, step by step, adds each phase's time inside its node to `seconds` and
    /// the time it waited there for its input to `waiting`. `timeout` is per step. An error
    /// comes with the number of steps known to be done: the step a node failed at, or the
    /// batch's first step if that is all it is known.
    pub(crate) fn run_steps(
        &mut self,
        (step, count, full): (u64, u64, FullReports),
        send_next: bool,
        nodes: &mut [Node],
        (seconds, waiting): (&mut BTreeMap<String, f64>, &mut BTreeMap<String, f64>),
        timeout: Duration,
    ) -> Result<Vec<Vec<PhaseReport>>, (RunError, u64)> {
        let count = count.max(1);
        let timeout = timeout.saturating_mul(u32::try_from(count).unwrap_or(u32::MAX));
        let sent_early = self.sent_early.take() == Some(step);
        for (o, _) in &self.per_node {
            if sent_early && self.early.contains(o) {
                continue;
            }
            let link = &mut nodes[*o].link;
            link.send(&self.batch(*o, (step, count), full))
                .map_err(|e| batch_failed(link.name(), (step, count), e))?;
        }
        // A node that cannot take the next step's batch may have failed in this step already
        // (it got this step's batch a moment ago): its reply or its silence below says so,
        // with this step's number. Only if this step completes is it the next step's failure.
        let mut next_refused = None;
        if send_next && count == 1 && !self.early.is_empty() {
            for &o in &self.early {
                let link = &mut nodes[o].link;
                if let Err(e) = link.send(&self.batch(o, (step + 1, 1), full)) {
                    next_refused = Some(node_failed(link.name(), step + 1, "", e));
                    break;
                }
            }
            self.sent_early = Some(step + 1);
        }
        let mut replies = self.collect_replies((step, count), nodes, timeout)?;
        let mut next = vec![0usize; nodes.len()];
        let mut all = Vec::with_capacity(count as usize);
        for s in step..step + count {
            let mut reports = Vec::with_capacity(self.schedule.len());
            for (&phase, &o) in self.schedule.iter().zip(&self.owner) {
                let r = replies[o]
                    .as_mut()
                    .and_then(|list| list.get_mut(next[o]))
                    .map(std::mem::take)
                    .ok_or_else(|| {
                        let e = fail(format!(
                            "node `{}` answered step {s} without a report for phase {phase}",
                            nodes[o].link.name()
                        ));
                        (e, step)
                    })?;
                next[o] += 1;
                *seconds.entry(phase.name().to_string()).or_default() += r.seconds;
                *waiting.entry(phase.name().to_string()).or_default() += r.waited;
                reports.push(r.report);
            }
            all.push(reports);
        }
        match next_refused {
            Some(e) => Err((e, step + 1)),
            None => Ok(all),
        }
    }

    /// Every node's reply to the batch of `count` steps from `step`, indexed by node.
    ///
    /// The node of the schedule's last phase usually answers last: block on it and look at
    /// the others without blocking. Once it has answered, block on one still silent: its
    /// reply may come later (it publishes its data before it answers, and the last node may
    /// finish in between), and looking without blocking would spin, taking the core the
    /// silent node needs.
    fn collect_replies(
        &self,
        (step, count): (u64, u64),
        nodes: &mut [Node],
        timeout: Duration,
    ) -> Result<Vec<Option<Vec<cosim::TimedReport>>>, (RunError, u64)> {
        let last = *self.owner.last().expect("a schedule has phases");
        let mut replies: Vec<Option<Vec<cosim::TimedReport>>> = vec![None; nodes.len()];
        let started = Instant::now();
        loop {
            let block_on = if replies[last].is_none() {
                last
            } else {
                self.per_node
                    .iter()
                    .map(|(o, _)| *o)
                    .find(|o| replies[*o].is_none())
                    .unwrap_or(last)
            };
            for (o, _) in &self.per_node {
                if replies[*o].is_some() {
                    continue;
                }
                let limit = if *o == block_on {
                    CHECK_OTHERS
                } else {
                    Duration::ZERO
                };
                let link = &mut nodes[*o].link;
                let reply = link
                    .receive_within(limit)
                    .map_err(|e| batch_failed(link.name(), (step, count), e))?;
                match reply {
                    Some(Reply::PhasesDone(r)) => replies[*o] = Some(r),
                    Some(Reply::PhasesFailed { step: at, message }) => {
                        let node = link.name().to_string();
                        let e = LinkFailure::Refused { node, message };
                        return Err((node_failed(link.name(), at, "", e), at));
                    }
                    Some(other) => {
                        let e = LinkFailure::Setup(format!("unexpected reply {other:?}"));
                        return Err(batch_failed(link.name(), (step, count), e));
                    }
                    None => {}
                }
            }
            if self.per_node.iter().all(|(o, _)| replies[*o].is_some()) {
                return Ok(replies);
            }
            if started.elapsed() > timeout {
                return Err((self.silence(&replies, (step, count), nodes, timeout), step));
            }
        }
    }

    /// The error for nodes that did not answer in time: which phases the silent nodes had;
    /// not which of them they were in.
    fn silence(
        &self,
        replies: &[Option<Vec<cosim::TimedReport>>],
        (step, count): (u64, u64),
        nodes: &[Node],
        timeout: Duration,
    ) -> RunError {
        let silent: Vec<String> = self
            .per_node
            .iter()
            .filter(|(o, _)| replies[*o].is_none())
            .map(|(o, list)| {
                let phases: Vec<&str> = list.iter().map(|(p, _, _)| p.name()).collect();
                let name = nodes[*o].link.name();
                format!("`{name}` (phases {})", phases.join(", "))
            })
            .collect();
        let steps = if count == 1 {
            format!("step {step}")
        } else {
            format!("steps {step} to {}", step + count - 1)
        };
        let other = if self.per_node.len() > 1 {
            " (one may be waiting for the other)"
        } else {
            ""
        };
        fail(format!(
            "{steps}: node {} did not answer within {} s{other}",
            silent.join(" and "),
            timeout.as_secs_f64()
        ))
    }
}

/// A node that fails without saying where failed somewhere in the batch of `count` steps
/// from `step`; the error counts `step` as the steps known to be done.
fn batch_failed(name: &str, (step, count): (u64, u64), e: LinkFailure) -> (RunError, u64) {
    let later = if count == 1 {
        String::new()
    } else {
        format!("or later, up to {} (one batch), ", step + count - 1)
    };
    (node_failed(name, step, &later, e), step)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(phase: Phase, port: Option<Port>, wake: Option<&str>) -> Entry {
        (phase, port, wake.map(String::from))
    }

    /// Each phase awaits the other node's latest publication of what it reads, and the
    /// producer wakes it; phases that read nothing new, or only their own node's output,
    /// wait for nothing.
    #[test]
    fn batches_follow_the_data_between_the_nodes() {
        use Phase::*;
        let names = ["fibre-node".to_string(), "fluid-node".to_string()];
        let spm = [
            FluidPhaseField,
            FibrePositions,
            FluidMomentumExchange,
            FibreVelocities,
            FluidPenalty,
        ];
        let b = Batches::new(&spm, &[1, 0, 1, 0, 1], &names);
        let fluid = Some("fluid-node");
        let fibre = Some("fibre-node");
        assert_eq!(
            b.per_node,
            vec![
                (
                    1,
                    vec![
                        entry(FluidPhaseField, None, None),
                        entry(FluidMomentumExchange, Some(Port::BeadPositions), fibre),
                        entry(FluidPenalty, Some(Port::BeadStates), None),
                    ]
                ),
                (
                    0,
                    vec![
                        entry(FibrePositions, None, fluid),
                        entry(FibreVelocities, Some(Port::BeadImpulses), fluid),
                    ]
                ),
            ]
        );
        // Every phase that reads the other node's data awaits it: both batches go early.
        assert_eq!(b.early, vec![1, 0]);
        assert!(b.can_hold_steps());
        let b = Batches::new(&spm[1..], &[0, 1, 0, 1], &names);
        assert_eq!(b.early, vec![0, 1]);
        let fpd = [FibreForces, FluidLatticeStep, FibreAdvance];
        let b = Batches::new(&fpd, &[0, 1, 0], &names);
        assert_eq!(b.early, vec![0, 1]);
        assert_eq!(
            b.per_node,
            vec![
                (
                    0,
                    vec![
                        entry(FibreForces, None, fluid),
                        entry(FibreAdvance, Some(Port::BeadVelocities), None),
                    ]
                ),
                (
                    1,
                    vec![entry(FluidLatticeStep, Some(Port::BeadForces), fibre)]
                ),
            ]
        );
        // A phase whose input comes from the step before (no producer earlier in the step)
        // awaits nothing, so its node stays in step.
        let b = Batches::new(&[FluidPenalty, FibreVelocities], &[1, 0], &names);
        assert_eq!(b.early, Vec::<usize>::new());
        assert!(!b.can_hold_steps());
        // A fluid alone reads ports nobody publishes: nothing can change under it.
        let b = Batches::new(&[FluidMomentumExchange, FluidPenalty], &[0, 0], &names[1..]);
        assert!(b.can_hold_steps());
    }
}
