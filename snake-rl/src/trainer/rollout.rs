//! SB3's `collect_rollouts`: the envs, the buffers of one step, and `n_steps` steps of every env
//! into the rollout buffer, with what the parts record beside each step and the actions they give
//! the envs in place of the policy's.

use std::sync::Arc;

use snake_core::{StepBuffers, VecSnakeEnv};

use super::run::Run;
use super::{Observer, TrainError};
use crate::buffer::RolloutBuffer;
use crate::nn::{ActorCritic, Workspace};
use crate::ppo::{act, LossScratch};

/// What collecting rollouts uses besides the run's state, allocated once: the envs, the rollout
/// buffer, the network's workspace, and the buffers of one step.
pub(crate) struct Rollout {
    pub(crate) envs: VecSnakeEnv,
    pub(crate) buffer: RolloutBuffer,
    net: ActorCritic,
    ws: Workspace,
    scratch: LossScratch,
    /// The envs' outputs: raw observations, rewards, terminations and truncations.
    out: StepBuffers,
    /// The policy's observations (normalised with `normalize`).
    obs: Vec<f32>,
    episode_starts: Vec<bool>,
    actions: Vec<f32>,
    clipped: Vec<f32>,
    values: Vec<f32>,
    log_probs: Vec<f32>,
    /// The rewards as stored (float32, normalised with `normalize`, bootstrapped on truncation).
    rewards: Vec<f32>,
    dones: Vec<bool>,
    /// A truncated episode's final observation.
    terminal: Vec<f32>,
}

impl Run {
    /// The envs (on the pool, or one after the other for one thread), reset with a seed that sets a
    /// resumed run's episodes apart from the ones seen before (as SB3 resumes), and the buffers
    /// (each part may widen the rollout buffer).
    pub(super) fn start_rollouts(
        &mut self,
        pool: &Arc<rayon::ThreadPool>,
    ) -> Result<Rollout, TrainError> {
        let c = &self.config;
        let (m, n, d) = (
            c.n_envs,
            self.env_config.action_dim(),
            self.env_config.observation_dim(),
        );
        let mut envs = VecSnakeEnv::new(self.env_config.clone(), m)?;
        envs = if self.threads == 1 {
            envs.with_threads(1)?
        } else {
            envs.with_pool(pool.clone())
        };
        let net = self.learner.net().clone();
        let mut out = StepBuffers::for_envs(&envs);
        envs.reset(Some(c.seed.wrapping_add(self.timesteps)), &mut out.obs)?;
        let mut obs = out.obs.clone();
        if let Some(norm) = &mut self.normalizer {
            norm.obs_rms.update(&out.obs, m);
            norm.reset_returns(m);
            norm.normalize_obs(&mut obs);
        }
        let mut buffer = RolloutBuffer::new(c.ppo.n_steps, m, d, n);
        for part in &mut self.parts {
            buffer = part.start_rollouts(m, buffer);
        }
        Ok(Rollout {
            envs,
            buffer,
            ws: net.workspace(m),
            net,
            scratch: LossScratch::default(),
            out,
            obs,
            episode_starts: vec![true; m],
            actions: vec![0.0; m * n],
            clipped: vec![0.0; m * n],
            values: vec![0.0; m],
            log_probs: vec![0.0; m],
            rewards: vec![0.0; m],
            dones: vec![false; m],
            terminal: vec![0.0; d],
        })
    }

    /// SB3's `collect_rollouts`: `n_steps` steps of every env into the buffer (actions sampled from
    /// the policy, clipped to [-1, 1] for the env, stored unclipped; a truncated episode's last reward
    /// gains `gamma` times the value of its final observation), then the returns and advantages
    /// (GAE). False when stopping was asked for (nothing of this rollout is used).
    pub(super) fn collect_rollout(
        &mut self,
        r: &mut Rollout,
        observer: &mut dyn Observer,
    ) -> Result<bool, TrainError> {
        let m = self.config.n_envs;
        let (n_steps, gamma, gae_lambda) = (
            self.config.ppo.n_steps,
            self.config.ppo.gamma,
            self.config.ppo.gae_lambda,
        );
        let gamma32 = gamma as f32;
        r.buffer.reset();
        for _ in 0..n_steps {
            if observer.should_stop() {
                return Ok(false);
            }
            act::sample(
                &r.net,
                &self.learner.params,
                &r.obs,
                m,
                &mut self.rng,
                &mut r.ws,
                &mut r.scratch,
                &mut r.actions,
                &mut r.values,
                &mut r.log_probs,
            );
            act::clip_to_action_space(&r.actions, &mut r.clipped);
            // The observations the actions answer are the envs' raw ones, still in `out`.
            for part in &mut self.parts {
                part.on_step(&r.out.obs, m, &mut r.buffer);
            }
            let finals = match self
                .parts
                .iter_mut()
                .find_map(|p| p.env_actions(&r.out.obs, &r.clipped, m))
            {
                None => r.envs.step_into(&r.clipped, &mut r.out)?,
                Some(actions) => r.envs.step_into(actions, &mut r.out)?,
            };
            self.timesteps += m as u64;
            for i in 0..m {
                r.rewards[i] = r.out.rewards[i] as f32;
                r.dones[i] = r.out.done(i);
            }
            // The finished episodes: statistics, and the final observations of truncated ones.
            let mut bootstrap: Vec<(usize, Vec<f32>)> = Vec::new();
            for f in finals.iter() {
                if self.episodes.len() == 100 {
                    self.episodes.pop_front();
                }
                self.episodes.push_back((
                    f.info.episode_return,
                    f.info.episode_step,
                    f.info.success,
                ));
                if r.out.truncated[f.env] && !r.out.terminated[f.env] {
                    bootstrap.push((f.env, f.observation.to_vec()));
                }
            }
            let mut next_obs = r.out.obs.clone();
            if let Some(norm) = &mut self.normalizer {
                norm.obs_rms.update(&r.out.obs, m);
                norm.normalize_obs(&mut next_obs);
                norm.normalize_rewards(&mut r.rewards, &r.dones);
            }
            for (env, final_obs) in bootstrap {
                r.terminal.copy_from_slice(&final_obs);
                if let Some(norm) = &self.normalizer {
                    norm.normalize_obs(&mut r.terminal);
                }
                r.net
                    .forward_value(&self.learner.params, &r.terminal, 1, &mut r.ws);
                r.rewards[env] += gamma32 * r.ws.value[0];
            }
            r.buffer.add(
                &r.obs,
                &r.actions,
                &r.rewards,
                &r.episode_starts,
                &r.values,
                &r.log_probs,
            );
            r.obs = next_obs;
            r.episode_starts.copy_from_slice(&r.dones);
            observer.on_step(self.timesteps);
        }
        r.net
            .forward_value(&self.learner.params, &r.obs, m, &mut r.ws);
        let last_values = r.ws.value[..m].to_vec();
        r.buffer
            .compute_returns_and_advantage(&last_values, &r.episode_starts, gamma, gae_lambda);
        Ok(true)
    }
}
