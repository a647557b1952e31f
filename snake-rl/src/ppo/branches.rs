//! PPO-small's update on two threads, one per network.
//!
//! PPO-small's policy and value networks share no parameter, and their losses are separate terms:
//! the policy's gradient comes from the surrogate (and the entropy) alone, the value network's from
//! the value loss alone. So one thread runs the policy's forward pass, loss, backward pass and Adam on
//! its parameter range, and the other thread the value network's on its own, both over the same
//! minibatches. Per minibatch they exchange one number, the squared norm of their gradients (global
//! norm clipping needs the total), and two flags (a non-finite value; the KL stop, which the policy
//! decides): a lock-free handshake on atomics, instead of a fork, a join and a sum of gradients. Both
//! threads make the same decisions from the same numbers, so they stop at the same step; one
//! configuration always gives the same bits.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use super::loss::{self, LossScratch, LossSettings, LossStats, LossSums, Minibatch};
use super::settings::{NonFinite, UpdateSettings};
use crate::buffer::{MinibatchData, RolloutBuffer};
use crate::nn::network::{Branch, BranchWorkspace};
use crate::nn::ActorCritic;
use crate::optim::{clip_coefficient, scale, squared_norms, Adam, AdamStep};

const NON_FINITE: u32 = 1;
const KL_STOP: u32 = 2;

/// Each thread's published numbers, double-buffered by step parity: a thread can publish step s + 1
/// while the other still reads step s, and cannot reach s + 2 before the other has published s + 1
/// (so has finished reading s).
#[derive(Debug, Default)]
struct Exchange {
    squared_norm: [[AtomicU64; 2]; 2],
    flags: [[AtomicU32; 2]; 2],
    published: [AtomicU64; 2],
}

impl Exchange {
    /// Publishes `me`'s numbers for `step` and waits for the other thread's; returns them.
    fn swap(&self, me: usize, step: u64, squared_norm: f64, flags: u32) -> (f64, u32) {
        let parity = (step % 2) as usize;
        self.squared_norm[me][parity].store(squared_norm.to_bits(), Ordering::Relaxed);
        self.flags[me][parity].store(flags, Ordering::Relaxed);
        self.published[me].store(step + 1, Ordering::Release);
        let other = 1 - me;
        let mut spins = 0u32;
        while self.published[other].load(Ordering::Acquire) < step + 1 {
            // The other thread is normally microseconds behind; yield if it was descheduled.
            if spins < 4096 {
                spins += 1;
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
        (
            f64::from_bits(self.squared_norm[other][parity].load(Ordering::Relaxed)),
            self.flags[other][parity].load(Ordering::Relaxed),
        )
    }
}

/// One thread's network: its branch, parameters, gradients and Adam moments (its own ranges).
struct Side<'a> {
    branch: Branch,
    params: &'a mut [f32],
    grads: &'a mut [f32],
    exp_avg: &'a mut [f32],
    exp_avg_sq: &'a mut [f32],
    /// Its tensors as (offset, length) within its range.
    tensors: Vec<(usize, usize)>,
    ws: &'a mut BranchWorkspace,
    minibatch: &'a mut MinibatchData,
}

/// What one thread records per gradient step (or for the minibatch that stopped the update).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SideStep {
    /// Policy: sum of surrogates; value: sum of squared errors.
    pub sum: f64,
    /// Policy: KL sum and clipped rows.
    pub kl: f64,
    /// Rows with a clipped ratio.
    pub clipped: usize,
    /// Policy: sum of squared distances to the anchoring controller's actions.
    pub anchor_error: f64,
    /// Rows of the minibatch.
    pub rows: usize,
    /// Policy: the distribution's entropy before the step.
    pub entropy: f32,
    /// The epoch.
    pub epoch: usize,
}

/// How the two threads' run ended.
#[derive(Debug, Default)]
pub(crate) struct SideOutcome {
    pub steps: Vec<SideStep>,
    /// The minibatch that stopped the update on the KL test (recorded, no step taken).
    pub stopped: Option<SideStep>,
    pub non_finite: Option<NonFinite>,
}

/// The state the update borrows from the learner.
pub(crate) struct Parts<'a> {
    pub net: &'a ActorCritic,
    pub params: &'a mut [f32],
    pub grads: &'a mut [f32],
    pub adam: &'a mut Adam,
    pub ws: &'a mut [BranchWorkspace; 2],
    pub minibatches: &'a mut [MinibatchData; 2],
    pub scratch: &'a mut LossScratch,
}

/// Runs the update's gradient steps over `batches` (per epoch, the minibatches' row indices) on
/// `pool` (two threads or more); returns each side's record.
pub(crate) fn run(
    parts: Parts<'_>,
    buffer: &RolloutBuffer,
    batches: &[Vec<Vec<usize>>],
    settings: &UpdateSettings,
    pool: &rayon::ThreadPool,
) -> (SideOutcome, SideOutcome) {
    let Parts {
        net,
        params,
        grads,
        adam,
        ws,
        minibatches,
        scratch,
    } = parts;
    let split = net
        .branch_split()
        .expect("PPO-small has two separate networks");
    let (policy_branch, value_branch) = (
        net.policy_branch().expect("no trunk"),
        net.value_branch().expect("no trunk"),
    );
    let tensors = net.tensors();
    let ranges = |lo: usize, hi: usize| -> Vec<(usize, usize)> {
        tensors
            .iter()
            .filter(|t| t.offset >= lo && t.offset < hi)
            .map(|t| (t.offset - lo, t.len()))
            .collect()
    };
    let (policy_tensors, value_tensors) = (ranges(0, split), ranges(split, net.len()));
    let log_std = net.log_std_offset()..net.log_std_offset() + net.act_dim();
    let first_step = adam.step;
    let hyper = adam.hyper();
    let (p_params, v_params) = params.split_at_mut(split);
    let (p_grads, v_grads) = grads.split_at_mut(split);
    let (p_m, v_m) = adam.exp_avg.split_at_mut(split);
    let (p_v, v_v) = adam.exp_avg_sq.split_at_mut(split);
    let [p_ws, v_ws] = ws;
    let [p_mb, v_mb] = minibatches;
    let mut policy = Side {
        branch: policy_branch,
        params: p_params,
        grads: p_grads,
        exp_avg: p_m,
        exp_avg_sq: p_v,
        tensors: policy_tensors,
        ws: p_ws,
        minibatch: p_mb,
    };
    let mut value = Side {
        branch: value_branch,
        params: v_params,
        grads: v_grads,
        exp_avg: v_m,
        exp_avg_sq: v_v,
        tensors: value_tensors,
        ws: v_ws,
        minibatch: v_mb,
    };
    let exchange = Exchange::default();
    let (mut p_out, mut v_out) = (SideOutcome::default(), SideOutcome::default());
    pool.scope(|s| {
        s.spawn(|_| {
            p_out = side_loop(
                0,
                &mut policy,
                Some((scratch, log_std.clone())),
                (buffer, batches, settings),
                hyper,
                first_step,
                &exchange,
            );
        });
        s.spawn(|_| {
            v_out = side_loop(
                1,
                &mut value,
                None,
                (buffer, batches, settings),
                hyper,
                first_step,
                &exchange,
            );
        });
    });
    adam.step = first_step + p_out.steps.len() as u64;
    (p_out, v_out)
}

/// One thread's pass over all the update's minibatches. `policy` holds the loss scratch and the range
/// of `log_std` for the policy's side; `None` for the value side.
fn side_loop(
    me: usize,
    side: &mut Side<'_>,
    mut policy: Option<(&mut LossScratch, std::ops::Range<usize>)>,
    (buffer, batches, settings): (&RolloutBuffer, &[Vec<Vec<usize>>], &UpdateSettings),
    hyper: (f64, f64, f64),
    first_step: u64,
    exchange: &Exchange,
) -> SideOutcome {
    let mut out = SideOutcome::default();
    let mut step = 0u64;
    for (e, epoch) in batches.iter().enumerate() {
        for (k, indices) in epoch.iter().enumerate() {
            buffer.gather(indices, side.minibatch);
            let mb = &mut *side.minibatch;
            let rows = mb.rows;
            let mut record = SideStep {
                rows,
                epoch: e + 1,
                ..SideStep::default()
            };
            let mut flags = 0;
            side.branch.forward(side.params, &mb.obs, rows, side.ws);
            match policy.as_mut() {
                Some((scratch, log_std)) => {
                    record.entropy = loss::gaussian_entropy(&side.params[log_std.clone()]);
                    if settings.loss.normalize_advantage {
                        loss::normalize_advantages(&mut mb.advantages);
                    }
                    let batch = minibatch(mb);
                    let sums = loss::policy_terms(
                        &side.ws.out,
                        &side.params[log_std.clone()],
                        &batch,
                        rows,
                        &settings.loss,
                        scratch,
                        &mut side.ws.d_out,
                    );
                    record.sum = sums.surrogate;
                    record.kl = sums.kl;
                    record.clipped = sums.clipped;
                    record.anchor_error = sums.anchor_error;
                    if let Some(target) = settings.target_kl {
                        if sums.kl / rows as f64 > 1.5 * target {
                            flags |= KL_STOP;
                        }
                    }
                    side.branch
                        .backward(side.params, &mb.obs, rows, side.ws, side.grads);
                    // log_std's gradient: the surrogate's share, then the entropy's.
                    let g = &mut side.grads[log_std.clone()];
                    g.copy_from_slice(&scratch.d_log_std);
                    for x in g.iter_mut() {
                        *x -= settings.loss.ent_coef;
                    }
                }
                None => {
                    let batch = minibatch(mb);
                    record.sum = loss::value_terms(
                        &side.ws.out,
                        &batch,
                        rows,
                        &settings.loss,
                        &mut side.ws.d_out,
                    );
                    side.branch
                        .backward(side.params, &mb.obs, rows, side.ws, side.grads);
                }
            }
            let squared = squared_norms(side.grads, &side.tensors);
            if !(record.sum.is_finite() && squared.is_finite()) {
                flags |= NON_FINITE;
            }
            let (other, other_flags) = exchange.swap(me, step, squared, flags);
            let all = flags | other_flags;
            if all & NON_FINITE != 0 {
                out.non_finite = Some(NonFinite {
                    what: if record.sum.is_finite() && squared.is_finite() && other.is_finite() {
                        "loss"
                    } else {
                        "gradient"
                    },
                    epoch: e + 1,
                    minibatch: k + 1,
                });
                return out;
            }
            if all & KL_STOP != 0 {
                out.stopped = Some(record);
                return out;
            }
            // Both threads add the two numbers in the same order: the same coefficient.
            let (first, second) = if me == 0 {
                (squared, other)
            } else {
                (other, squared)
            };
            let coef = clip_coefficient((first + second).sqrt() as f32, settings.max_grad_norm);
            scale(side.grads, coef);
            AdamStep::new(hyper, settings.learning_rate, first_step + step + 1).apply(
                side.params,
                side.grads,
                side.exp_avg,
                side.exp_avg_sq,
            );
            out.steps.push(record);
            step += 1;
        }
    }
    out
}

fn minibatch(mb: &MinibatchData) -> Minibatch<'_> {
    Minibatch {
        obs: &mb.obs,
        actions: &mb.actions,
        old_log_prob: &mb.old_log_prob,
        advantages: &mb.advantages,
        returns: &mb.returns,
        old_values: &mb.old_values,
        anchors: &mb.anchors,
        rows: mb.rows,
    }
}

/// The loss terms of one minibatch of `act_dim` actions from both sides' records.
pub(crate) fn step_stats(
    policy: &SideStep,
    value: &SideStep,
    act_dim: usize,
    settings: &LossSettings,
) -> LossStats {
    LossSums {
        surrogate: policy.sum,
        value_error: value.sum,
        kl: policy.kl,
        clipped: policy.clipped,
        anchor_error: policy.anchor_error,
    }
    .stats(policy.rows, act_dim, policy.entropy, settings)
}
