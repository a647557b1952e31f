//! Initialisation by imitation (a run's `init` table, [`InitConfig`]): the paper's closing proposal,
//! "teaching the action network to use a simple sine function at initialisation, after which it can
//! be trained to finetune this movement".
//!
//! Before PPO, the training envs are driven by a controller in their own action space
//! ([`Demonstrator`]: a joint-target wave or a gait-action hand controller) and every (observation, action) pair is kept ([`collect`]); the actor's mean is
//! then fitted to the actions by behaviour cloning ([`fit`]: mean squared error, Adam, shuffled
//! minibatches), optionally with the value network fitted to the controller's discounted returns, on
//! the same network code and optimiser as PPO's update. The trainer then sets the action noise and
//! trains PPO as usual.

use rand::seq::SliceRandom;
use rand::Rng;
use snake_core::imitation::Demonstrator;
use snake_core::{StepBuffers, VecSnakeEnv};

use crate::config::InitConfig;
use crate::nn::{ActorCritic, Workspace};
use crate::normalize::Normalizer;
use crate::optim::Adam;

/// The controller's steps: observations as the policy will see them (normalised with the run's
/// statistics after the collection, when it normalises), its actions, and the discounted returns.
#[derive(Debug, Clone, Default)]
pub struct Demonstrations {
    /// `rows x obs_dim`.
    pub obs: Vec<f32>,
    /// `rows x act_dim`, in [-1, 1].
    pub actions: Vec<f32>,
    /// The discounted return of each row (rewards as PPO stores them: normalised with `normalize`),
    /// each env's data ending in a return of 0 after its last step.
    pub returns: Vec<f32>,
    /// Rows.
    pub rows: usize,
    /// Return of each episode that ended during the collection (the env's raw reward).
    pub episode_returns: Vec<f64>,
    /// Whether each of them reached the goal.
    pub episode_successes: Vec<bool>,
}

impl Demonstrations {
    /// Mean return of the finished episodes.
    pub fn mean_return(&self) -> Option<f64> {
        let n = self.episode_returns.len();
        (n > 0).then(|| self.episode_returns.iter().sum::<f64>() / n as f64)
    }

    /// Share of the finished episodes that reached the goal.
    pub fn success_rate(&self) -> Option<f64> {
        let n = self.episode_successes.len();
        (n > 0).then(|| self.episode_successes.iter().filter(|s| **s).count() as f64 / n as f64)
    }
}

/// Drives `envs` (already reset, their observations in `out.obs`) with `controller` for at least
/// `steps` env steps in all (whole steps of every env: `ceil(steps / envs)` of each), updating
/// `normalizer` from the observations and rewards as a rollout does. `stop` is asked between steps;
/// `Ok(None)` when it said stop.
#[allow(clippy::too_many_arguments)]
pub fn collect(
    controller: &mut Demonstrator,
    envs: &mut VecSnakeEnv,
    out: &mut StepBuffers,
    steps: u64,
    gamma: f64,
    mut normalizer: Option<&mut Normalizer>,
    stop: &mut dyn FnMut(u64) -> bool,
) -> Result<Option<Demonstrations>, snake_core::Error> {
    let m = envs.num_envs();
    let (d, n) = (envs.observation_dim(), envs.action_dim());
    let rounds = steps.div_ceil(m as u64) as usize;
    let rows = rounds * m;
    let mut data = Demonstrations {
        obs: Vec::with_capacity(rows * d),
        actions: vec![0.0; rows * n],
        rows,
        ..Demonstrations::default()
    };
    let mut rewards = vec![0.0f32; rows];
    let mut dones = vec![false; rows];
    let mut step_rewards = vec![0.0f32; m];
    let mut step_dones = vec![false; m];
    if let Some(norm) = normalizer.as_deref_mut() {
        norm.obs_rms.update(&out.obs, m);
        norm.reset_returns(m);
    }
    for round in 0..rounds {
        if stop((round * m) as u64) {
            return Ok(None);
        }
        data.obs.extend_from_slice(&out.obs);
        let actions = &mut data.actions[round * m * n..(round + 1) * m * n];
        controller.act(&out.obs, actions);
        let finals = envs.step_into(actions, out)?;
        for f in finals.iter() {
            controller.reset(f.env);
            data.episode_returns.push(f.info.episode_return);
            data.episode_successes.push(f.info.success);
        }
        for i in 0..m {
            step_rewards[i] = out.rewards[i] as f32;
            step_dones[i] = out.done(i);
        }
        if let Some(norm) = normalizer.as_deref_mut() {
            norm.obs_rms.update(&out.obs, m);
            norm.normalize_rewards(&mut step_rewards, &step_dones);
        }
        rewards[round * m..(round + 1) * m].copy_from_slice(&step_rewards);
        dones[round * m..(round + 1) * m].copy_from_slice(&step_dones);
    }
    if let Some(norm) = normalizer.as_deref() {
        norm.normalize_obs(&mut data.obs);
    }
    // Discounted returns, each env backwards; an episode's end cuts the sum.
    data.returns = vec![0.0; rows];
    let gamma = gamma as f32;
    for env in 0..m {
        let mut g = 0.0f32;
        for round in (0..rounds).rev() {
            let k = round * m + env;
            if dones[k] {
                g = 0.0;
            }
            g = rewards[k] + gamma * g;
            data.returns[k] = g;
        }
    }
    Ok(Some(data))
}

/// One epoch's mean losses of [`fit`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpochLoss {
    /// Epoch, from 1.
    pub epoch: usize,
    /// Mean over the epoch's minibatches of the mean squared error between the actor's mean and the
    /// controller's actions (per action component).
    pub bc_loss: f64,
    /// The same for the value and the discounted return, when the critic is fitted.
    pub critic_loss: Option<f64>,
}

/// The mean squared error between the actor's means of `data`'s observations and its actions.
pub fn bc_loss(net: &ActorCritic, params: &[f32], data: &Demonstrations) -> f64 {
    let (d, n) = (net.obs_dim(), net.act_dim());
    let chunk = 4096;
    let mut ws = net.workspace(chunk.min(data.rows.max(1)));
    let mut sum = 0.0f64;
    let mut start = 0;
    while start < data.rows {
        let rows = chunk.min(data.rows - start);
        net.forward(
            params,
            &data.obs[start * d..(start + rows) * d],
            rows,
            &mut ws,
        );
        for (m, a) in ws.mean[..rows * n]
            .iter()
            .zip(&data.actions[start * n..(start + rows) * n])
        {
            sum += f64::from((m - a) * (m - a));
        }
        start += rows;
    }
    sum / (data.rows * n).max(1) as f64
}

/// Behaviour cloning: fits the actor's mean (and with `init.critic` the value) of `params` to
/// `data` by Adam at `init.learning_rate` over `init.epochs` shuffled passes in minibatches of
/// `init.batch_size` (the last one of a pass may be smaller); `log_std` is left alone. `on_epoch`
/// gets each epoch's losses and returns true to stop (`None` then).
pub fn fit<R: Rng>(
    net: &ActorCritic,
    params: &mut [f32],
    data: &Demonstrations,
    init: &InitConfig,
    rng: &mut R,
    on_epoch: &mut dyn FnMut(&EpochLoss) -> bool,
) -> Option<Vec<EpochLoss>> {
    let (d, n) = (net.obs_dim(), net.act_dim());
    let b = init.batch_size.min(data.rows).max(1);
    let mut adam = Adam::new(net.len());
    let mut grads = vec![0.0f32; net.len()];
    let mut ws: Workspace = net.workspace(b);
    let (mut obs, mut actions, mut returns) =
        (vec![0.0f32; b * d], vec![0.0f32; b * n], vec![0.0f32; b]);
    let mut order: Vec<usize> = (0..data.rows).collect();
    let mut losses = Vec::with_capacity(init.epochs);
    for epoch in 1..=init.epochs {
        order.shuffle(rng);
        let (mut bc_sum, mut critic_sum, mut batches) = (0.0f64, 0.0f64, 0usize);
        for batch in order.chunks(b) {
            let rows = batch.len();
            for (k, &i) in batch.iter().enumerate() {
                obs[k * d..(k + 1) * d].copy_from_slice(&data.obs[i * d..(i + 1) * d]);
                actions[k * n..(k + 1) * n].copy_from_slice(&data.actions[i * n..(i + 1) * n]);
                returns[k] = data.returns[i];
            }
            net.forward(params, &obs[..rows * d], rows, &mut ws);
            let scale = 2.0 / (rows * n) as f32;
            let mut bc = 0.0f64;
            let Workspace {
                mean,
                value,
                d_mean,
                d_value,
                ..
            } = &mut ws;
            for ((g, m), a) in d_mean[..rows * n]
                .iter_mut()
                .zip(&mean[..rows * n])
                .zip(&actions[..rows * n])
            {
                let diff = m - a;
                bc += f64::from(diff * diff);
                *g = scale * diff;
            }
            let mut critic = 0.0f64;
            for ((g, v), r) in d_value[..rows]
                .iter_mut()
                .zip(&value[..rows])
                .zip(&returns[..rows])
            {
                if init.critic {
                    let diff = v - r;
                    critic += f64::from(diff * diff);
                    *g = 2.0 / rows as f32 * diff;
                } else {
                    *g = 0.0;
                }
            }
            grads.fill(0.0);
            net.backward(params, &obs[..rows * d], &mut ws, &mut grads);
            adam.step(params, &grads, init.learning_rate);
            bc_sum += bc / (rows * n) as f64;
            critic_sum += critic / rows as f64;
            batches += 1;
        }
        let loss = EpochLoss {
            epoch,
            bc_loss: bc_sum / batches as f64,
            critic_loss: init.critic.then(|| critic_sum / batches as f64),
        };
        losses.push(loss);
        if on_epoch(&loss) {
            return None;
        }
    }
    Some(losses)
}
