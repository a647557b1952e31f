//! One PPO update over a full rollout, as SB3 2.x's `PPO.train`: `n_epochs` passes over the rollout in
//! shuffled minibatches, each a gradient step of the clipped loss, with gradient-norm clipping and
//! Adam; early stop on `target_kl`.
//!
//! Each minibatch's rows are split into one contiguous chunk per thread; the threads compute their
//! chunks' losses and gradients at once and the gradients are summed in a fixed order. One thread
//! count therefore always gives the same bits, and one thread is exactly the sequential computation.

use rand::Rng;
use rayon::prelude::*;

use super::branches;
use super::loss::{self, LossScratch, LossStats, LossSums, Minibatch};
use super::settings::{NonFinite, UpdateSettings, UpdateStats};
use crate::buffer::{MinibatchData, RolloutBuffer};
use crate::nn::network::BranchWorkspace;
use crate::nn::{ActorCritic, Workspace};
use crate::optim::{clip_grad_norm, Adam};

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
    branch_ws: [BranchWorkspace; 2],
    branch_minibatches: [MinibatchData; 2],
    branch_scratch: LossScratch,
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
            branch_ws: Default::default(),
            branch_minibatches: Default::default(),
            branch_scratch: LossScratch::default(),
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
            anchors: &mb.anchors,
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
        sums.stats(rows, self.net.act_dim(), entropy, &settings.loss)
    }

    /// One full update over `buffer` (returns and advantages computed), drawing minibatches with
    /// `rng`. On a non-finite loss or gradient the update stops before applying it. With a pool of two
    /// threads or more, PPO-small updates its two networks on two threads (one per network); any
    /// other network splits each minibatch's rows across the threads.
    pub fn update<R: Rng>(
        &mut self,
        buffer: &RolloutBuffer,
        settings: &UpdateSettings,
        rng: &mut R,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<UpdateStats, NonFinite> {
        let branch_pool = pool.filter(|p| {
            p.current_num_threads() >= 2
                && self.workers.len() >= 2
                && self.net.branch_split().is_some()
        });
        let (records, stopped) = match branch_pool {
            Some(pool) => self.update_branches(buffer, settings, rng, pool)?,
            None => self.update_chunks(buffer, settings, rng, pool)?,
        };
        let mut stats = UpdateStats {
            gradient_steps: records.len(),
            stopped_early: stopped.is_some(),
            ..UpdateStats::default()
        };
        // SB3 logs the losses of every minibatch, the one that stopped the update included, and the
        // KL estimate of the last epoch's.
        let all: Vec<&(usize, LossStats)> = records.iter().chain(stopped.as_ref()).collect();
        let of = |f: fn(&LossStats) -> f32| {
            mean(&all.iter().map(|(_, s)| f64::from(f(s))).collect::<Vec<_>>())
        };
        stats.entropy_loss = of(|s| s.entropy_loss);
        stats.policy_gradient_loss = of(|s| s.policy_loss);
        stats.value_loss = of(|s| s.value_loss);
        stats.clip_fraction = of(|s| s.clip_fraction);
        stats.anchor_loss = of(|s| s.anchor_loss);
        stats.epochs = all.last().map_or(0, |(e, _)| *e);
        let last_epoch: Vec<f64> = all
            .iter()
            .filter(|(e, _)| *e == stats.epochs)
            .map(|(_, s)| f64::from(s.approx_kl))
            .collect();
        stats.approx_kl = mean(&last_epoch);
        stats.loss = records.last().map_or(0.0, |(_, s)| f64::from(s.loss));
        stats.explained_variance = buffer.explained_variance();
        let std = self.std();
        stats.std = std.iter().map(|&s| f64::from(s)).sum::<f64>() / std.len() as f64;
        Ok(stats)
    }

    /// The update with each minibatch's rows split across the threads: (epoch, stats) of every
    /// gradient step, and of the minibatch that stopped the update on the KL test.
    #[allow(clippy::type_complexity)]
    fn update_chunks<R: Rng>(
        &mut self,
        buffer: &RolloutBuffer,
        settings: &UpdateSettings,
        rng: &mut R,
        pool: Option<&rayon::ThreadPool>,
    ) -> Result<(Vec<(usize, LossStats)>, Option<(usize, LossStats)>), NonFinite> {
        let mut records = Vec::new();
        for epoch in 1..=settings.n_epochs {
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
                if let Some(target) = settings.target_kl {
                    if f64::from(s.approx_kl) > 1.5 * target {
                        return Ok((records, Some((epoch, s))));
                    }
                }
                let norm = clip_grad_norm(&mut self.grads, &self.tensors, settings.max_grad_norm);
                if !norm.is_finite() {
                    return Err(where_("gradient"));
                }
                self.adam
                    .step(&mut self.params, &self.grads, settings.learning_rate);
                records.push((epoch, s));
            }
        }
        Ok((records, None))
    }

    /// PPO-small's update on two threads, one per network ([`super::branches`]).
    #[allow(clippy::type_complexity)]
    fn update_branches<R: Rng>(
        &mut self,
        buffer: &RolloutBuffer,
        settings: &UpdateSettings,
        rng: &mut R,
        pool: &rayon::ThreadPool,
    ) -> Result<(Vec<(usize, LossStats)>, Option<(usize, LossStats)>), NonFinite> {
        // Every epoch's permutation up front (the two threads share them).
        let batches: Vec<Vec<Vec<usize>>> = (0..settings.n_epochs)
            .map(|_| buffer.minibatch_indices(settings.batch_size, rng))
            .collect();
        let parts = branches::Parts {
            net: &self.net,
            params: &mut self.params,
            grads: &mut self.grads,
            adam: &mut self.adam,
            ws: &mut self.branch_ws,
            minibatches: &mut self.branch_minibatches,
            scratch: &mut self.branch_scratch,
        };
        let (policy, value) = branches::run(parts, buffer, &batches, settings, pool);
        if let Some(e) = policy.non_finite.or(value.non_finite) {
            return Err(e);
        }
        let act_dim = self.net.act_dim();
        let records = policy
            .steps
            .iter()
            .zip(&value.steps)
            .map(|(p, v)| (p.epoch, branches::step_stats(p, v, act_dim, &settings.loss)))
            .collect();
        let stopped = policy.stopped.zip(value.stopped).map(|(p, v)| {
            (
                p.epoch,
                branches::step_stats(&p, &v, act_dim, &settings.loss),
            )
        });
        Ok((records, stopped))
    }
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}
