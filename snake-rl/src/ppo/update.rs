//! One PPO update over a full rollout, as SB3 2.x's `PPO.train`: `n_epochs` passes over the rollout in
//! shuffled minibatches, each a gradient step of the clipped loss, with gradient-norm clipping and
//! Adam; early stop on `target_kl`.
//!
//! Each minibatch's rows are split into one contiguous chunk per thread; the threads compute their
//! chunks' losses and gradients at once and the gradients are summed in a fixed order. One thread
//! count therefore always gives the same bits, and one thread is exactly the sequential computation.

use rand::Rng;
use rayon::prelude::*;

use super::loss::{self, LossScratch, LossSettings, LossStats, LossSums, Minibatch};
use crate::buffer::{MinibatchData, RolloutBuffer};
use crate::nn::{ActorCritic, Workspace};
use crate::optim::{clip_grad_norm, Adam};

/// The hyperparameters of one update (schedules already evaluated).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UpdateSettings {
    /// Passes over the rollout.
    pub n_epochs: usize,
    /// Rows per minibatch.
    pub batch_size: usize,
    /// The loss's settings.
    pub loss: LossSettings,
    /// Gradient norm clip.
    pub max_grad_norm: f64,
    /// Early-stop threshold (stop once approx_kl > 1.5 x target_kl).
    pub target_kl: Option<f64>,
    /// This update's learning rate.
    pub learning_rate: f64,
}

/// What SB3 logs after an update (`train/*`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct UpdateStats {
    /// Mean entropy loss over the minibatches.
    pub entropy_loss: f64,
    /// Mean clipped surrogate loss.
    pub policy_gradient_loss: f64,
    /// Mean value loss.
    pub value_loss: f64,
    /// Mean KL estimate over the last epoch's minibatches.
    pub approx_kl: f64,
    /// Mean fraction of clipped ratios.
    pub clip_fraction: f64,
    /// The last minibatch's total loss.
    pub loss: f64,
    /// Explained variance of the rollout's values.
    pub explained_variance: f64,
    /// Mean standard deviation of the policy after the update.
    pub std: f64,
    /// Epochs run (fewer than `n_epochs` after an early stop).
    pub epochs: usize,
    /// Gradient steps taken.
    pub gradient_steps: usize,
    /// The update stopped early on `target_kl`.
    pub stopped_early: bool,
}

/// A non-finite loss or gradient: where it happened. The parameters are those before that minibatch.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("non-finite {what} in epoch {epoch}, minibatch {minibatch} of the update")]
pub struct NonFinite {
    /// `loss` or `gradient`.
    pub what: &'static str,
    /// Epoch (from 1).
    pub epoch: usize,
    /// Minibatch within the epoch (from 1).
    pub minibatch: usize,
}

/// One thread's buffers.
#[derive(Debug, Clone, Default)]
struct Worker {
    ws: Workspace,
    scratch: LossScratch,
    grads: Vec<f32>,
    sums: LossSums,
    rows: usize,
}

/// The learning state: the network's parameters, Adam, and the update's scratch.
#[derive(Debug)]
pub struct Learner {
    net: ActorCritic,
    /// The flat parameter buffer (layout: [`ActorCritic::tensors`]).
    pub params: Vec<f32>,
    /// Adam's state.
    pub adam: Adam,
    workers: Vec<Worker>,
    grads: Vec<f32>,
    tensors: Vec<(usize, usize)>,
    minibatch: MinibatchData,
}

impl Learner {
    /// A learner for `net` starting from `params`, computing each minibatch on `threads` threads.
    pub fn new(net: ActorCritic, params: Vec<f32>, threads: usize) -> Self {
        assert_eq!(params.len(), net.len(), "parameters do not fit the network");
        let tensors = net.tensors().iter().map(|t| (t.offset, t.len())).collect();
        let workers = (0..threads.max(1))
            .map(|_| Worker {
                grads: vec![0.0; net.len()],
                ..Worker::default()
            })
            .collect();
        Learner {
            adam: Adam::new(net.len()),
            grads: vec![0.0; net.len()],
            net,
            params,
            workers,
            tensors,
            minibatch: MinibatchData::default(),
        }
    }

    /// The network.
    pub fn net(&self) -> &ActorCritic {
        &self.net
    }

    /// The gradient of the last gradient step, after clipping (what Adam was given).
    pub fn last_gradient(&self) -> &[f32] {
        &self.grads
    }

    /// The policy's standard deviations, `exp(log_std)`.
    pub fn std(&self) -> Vec<f32> {
        let o = self.net.log_std_offset();
        self.params[o..o + self.net.act_dim()]
            .iter()
            .map(|l| l.exp())
            .collect()
    }

    /// Loss and gradient of the minibatch in `self.minibatch` into `self.grads`, and its stats.
    fn compute(
        &mut self,
        settings: &UpdateSettings,
        pool: Option<&rayon::ThreadPool>,
    ) -> LossStats {
        let rows = self.minibatch.rows;
        if settings.loss.normalize_advantage {
            loss::normalize_advantages(&mut self.minibatch.advantages);
        }
        let mb = &self.minibatch;
        let batch = Minibatch {
            obs: &mb.obs,
            actions: &mb.actions,
            old_log_prob: &mb.old_log_prob,
            advantages: &mb.advantages,
            returns: &mb.returns,
            old_values: &mb.old_values,
            rows,
        };
        let (net, params) = (&self.net, &self.params);
        let (obs_dim, act_dim) = (net.obs_dim(), net.act_dim());
        let t = self.workers.len().min(rows).max(1);
        let job = |k: usize, w: &mut Worker| {
            let (start, end) = (k * rows / t, (k + 1) * rows / t);
            w.rows = end - start;
            if w.rows == 0 {
                w.sums = LossSums::default();
                return;
            }
            let chunk = batch.slice(start, end, obs_dim, act_dim);
            w.sums = loss::forward(
                net,
                params,
                &chunk,
                rows,
                &settings.loss,
                &mut w.ws,
                &mut w.scratch,
            );
            loss::backward(net, params, chunk.obs, &mut w.ws, &w.scratch, &mut w.grads);
        };
        let workers = &mut self.workers[..t];
        match pool {
            Some(pool) if t > 1 => pool.install(|| {
                workers
                    .par_iter_mut()
                    .enumerate()
                    .with_max_len(1)
                    .for_each(|(k, w)| job(k, w))
            }),
            _ => workers.iter_mut().enumerate().for_each(|(k, w)| job(k, w)),
        }
        let mut sums = LossSums::default();
        self.grads.copy_from_slice(&workers[0].grads);
        sums.merge(&workers[0].sums);
        for w in &workers[1..] {
            sums.merge(&w.sums);
            if w.rows > 0 {
                for (g, x) in self.grads.iter_mut().zip(&w.grads) {
                    *g += x;
                }
            }
        }
        loss::add_entropy_gradient(&self.net, &settings.loss, &mut self.grads);
        let o = self.net.log_std_offset();
        let entropy = loss::gaussian_entropy(&self.params[o..o + self.net.act_dim()]);
        sums.stats(rows, entropy, &settings.loss)
    }

    /// One full update over `buffer` (returns and advantages computed), drawing minibatches with
    /// `rng`. On a non-finite loss or gradient the update stops before applying it.
    pub fn update<R: Rng>(
        &mut self,
        buffer: &RolloutBuffer,
        settings: &UpdateSettings,
        rng: &mut R,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<UpdateStats, NonFinite> {
        let mut entropy_losses = Vec::new();
        let mut pg_losses = Vec::new();
        let mut value_losses = Vec::new();
        let mut clip_fractions = Vec::new();
        let mut stats = UpdateStats::default();
        let mut last_loss = 0.0;
        'epochs: for epoch in 1..=settings.n_epochs {
            let mut approx_kls = Vec::new();
            for (k, indices) in buffer
                .minibatch_indices(settings.batch_size, rng)
                .iter()
                .enumerate()
            {
                buffer.gather(indices, &mut self.minibatch);
                let s = self.compute(settings, pool);
                let where_ = |what| NonFinite {
                    what,
                    epoch,
                    minibatch: k + 1,
                };
                if !s.loss.is_finite() {
                    return Err(where_("loss"));
                }
                entropy_losses.push(f64::from(s.entropy_loss));
                pg_losses.push(f64::from(s.policy_loss));
                value_losses.push(f64::from(s.value_loss));
                clip_fractions.push(f64::from(s.clip_fraction));
                approx_kls.push(f64::from(s.approx_kl));
                if let Some(target) = settings.target_kl {
                    if f64::from(s.approx_kl) > 1.5 * target {
                        stats.stopped_early = true;
                        stats.approx_kl = mean(&approx_kls);
                        stats.epochs = epoch;
                        break 'epochs;
                    }
                }
                let norm = clip_grad_norm(&mut self.grads, &self.tensors, settings.max_grad_norm);
                if !norm.is_finite() {
                    return Err(where_("gradient"));
                }
                self.adam
                    .step(&mut self.params, &self.grads, settings.learning_rate);
                stats.gradient_steps += 1;
                last_loss = f64::from(s.loss);
            }
            stats.approx_kl = mean(&approx_kls);
            stats.epochs = epoch;
        }
        stats.entropy_loss = mean(&entropy_losses);
        stats.policy_gradient_loss = mean(&pg_losses);
        stats.value_loss = mean(&value_losses);
        stats.clip_fraction = mean(&clip_fractions);
        stats.loss = last_loss;
        stats.explained_variance = buffer.explained_variance();
        let std = self.std();
        stats.std = std.iter().map(|&s| f64::from(s)).sum::<f64>() / std.len() as f64;
        Ok(stats)
    }
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}
