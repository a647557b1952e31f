//! The rollout buffer: `n_steps` steps of `n_envs` envs, and their returns and advantages by GAE,
//! computed as Stable-Baselines3's `RolloutBuffer.compute_returns_and_advantage` does (float32
//! arrays, the same operations in the same order).
//!
//! Rows are stored step-major (`step * n_envs + env`); minibatches draw rows by index, so the layout
//! does not change what is learnt.

use rand::seq::SliceRandom;
use rand::Rng;

/// One rollout's data.
#[derive(Debug, Clone)]
pub struct RolloutBuffer {
    n_steps: usize,
    n_envs: usize,
    obs_dim: usize,
    act_dim: usize,
    len: usize,
    /// Observations the policy acted on (`rows x obs_dim`).
    pub obs: Vec<f32>,
    /// Actions as sampled, before clipping to the action space (`rows x act_dim`).
    pub actions: Vec<f32>,
    /// Rewards, with `gamma * V(terminal observation)` added on truncation.
    pub rewards: Vec<f32>,
    /// 1 where the observation is the first of an episode.
    pub episode_starts: Vec<f32>,
    /// Values of the observations under the rollout's policy.
    pub values: Vec<f32>,
    /// Log-probabilities of the actions under the rollout's policy.
    pub log_probs: Vec<f32>,
    /// GAE advantages (after [`RolloutBuffer::compute_returns_and_advantage`]).
    pub advantages: Vec<f32>,
    /// Advantages plus values.
    pub returns: Vec<f32>,
    /// The anchor actions in the same states (`rows x act_dim`: `init.anchor`'s fitted policy's
    /// means), or empty when the run keeps no anchor ([`RolloutBuffer::with_anchors`]).
    pub anchors: Vec<f32>,
}

impl RolloutBuffer {
    /// An empty buffer for `n_steps` steps of `n_envs` envs.
    pub fn new(n_steps: usize, n_envs: usize, obs_dim: usize, act_dim: usize) -> Self {
        let rows = n_steps * n_envs;
        RolloutBuffer {
            n_steps,
            n_envs,
            obs_dim,
            act_dim,
            len: 0,
            obs: vec![0.0; rows * obs_dim],
            actions: vec![0.0; rows * act_dim],
            rewards: vec![0.0; rows],
            episode_starts: vec![0.0; rows],
            values: vec![0.0; rows],
            log_probs: vec![0.0; rows],
            advantages: vec![0.0; rows],
            returns: vec![0.0; rows],
            anchors: Vec::new(),
        }
    }

    /// The buffer also stores anchor actions per row ([`RolloutBuffer::set_anchors`]).
    pub fn with_anchors(mut self) -> Self {
        self.anchors = vec![0.0; self.rows() * self.act_dim];
        self
    }

    /// The anchor actions for the step [`RolloutBuffer::add`] stores next (`n_envs` rows).
    pub fn set_anchors(&mut self, actions: &[f32]) {
        let width = self.n_envs * self.act_dim;
        let s = self.len;
        self.anchors[s * width..(s + 1) * width].copy_from_slice(actions);
    }

    /// Steps stored so far.
    pub fn steps(&self) -> usize {
        self.len
    }

    /// Whether all `n_steps` steps are stored.
    pub fn is_full(&self) -> bool {
        self.len == self.n_steps
    }

    /// Rows in a full buffer (`n_steps * n_envs`).
    pub fn rows(&self) -> usize {
        self.n_steps * self.n_envs
    }

    /// Forgets the stored steps.
    pub fn reset(&mut self) {
        self.len = 0;
    }

    /// Stores one step of every env: the slices hold `n_envs` rows each.
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &mut self,
        obs: &[f32],
        actions: &[f32],
        rewards: &[f32],
        episode_starts: &[bool],
        values: &[f32],
        log_probs: &[f32],
    ) {
        assert!(self.len < self.n_steps, "the rollout buffer is full");
        let (m, s) = (self.n_envs, self.len);
        self.obs[s * m * self.obs_dim..(s + 1) * m * self.obs_dim].copy_from_slice(obs);
        self.actions[s * m * self.act_dim..(s + 1) * m * self.act_dim].copy_from_slice(actions);
        self.rewards[s * m..(s + 1) * m].copy_from_slice(rewards);
        for (dst, &start) in self.episode_starts[s * m..(s + 1) * m]
            .iter_mut()
            .zip(episode_starts)
        {
            *dst = if start { 1.0 } else { 0.0 };
        }
        self.values[s * m..(s + 1) * m].copy_from_slice(values);
        self.log_probs[s * m..(s + 1) * m].copy_from_slice(log_probs);
        self.len += 1;
    }

    /// GAE(lambda) advantages and returns, bootstrapping the last step with `last_values` (the values
    /// of the observations after it) unless `dones` says its episode ended:
    ///
    /// ```text
    /// delta_t = r_t + gamma * V_{t+1} * (1 - start_{t+1}) - V_t
    /// A_t     = delta_t + gamma * lambda * (1 - start_{t+1}) * A_{t+1}
    /// R_t     = A_t + V_t
    /// ```
    pub fn compute_returns_and_advantage(
        &mut self,
        last_values: &[f32],
        dones: &[bool],
        gamma: f64,
        gae_lambda: f64,
    ) {
        assert!(self.is_full(), "GAE needs a full rollout");
        let m = self.n_envs;
        // numpy under NEP 50: a Python float times a float32 array is float32, and SB3's
        // `self.gamma * self.gae_lambda` is a product of two Python floats, rounded once.
        let gamma_f32 = gamma as f32;
        let gamma_lambda = (gamma * gae_lambda) as f32;
        let mut last_gae_lam = vec![0.0f32; m];
        for step in (0..self.n_steps).rev() {
            for env in 0..m {
                let (next_non_terminal, next_values) = if step == self.n_steps - 1 {
                    (1.0 - if dones[env] { 1.0 } else { 0.0 }, last_values[env])
                } else {
                    let next = (step + 1) * m + env;
                    (1.0 - self.episode_starts[next], self.values[next])
                };
                let i = step * m + env;
                let delta =
                    self.rewards[i] + gamma_f32 * next_values * next_non_terminal - self.values[i];
                last_gae_lam[env] = delta + gamma_lambda * next_non_terminal * last_gae_lam[env];
                self.advantages[i] = last_gae_lam[env];
            }
        }
        for ((r, a), v) in self
            .returns
            .iter_mut()
            .zip(&self.advantages)
            .zip(&self.values)
        {
            *r = a + v;
        }
    }

    /// A random permutation of the rows, cut into minibatches of `batch_size` (the last one shorter
    /// when `batch_size` does not divide the rows), as SB3's `RolloutBuffer.get` draws them.
    pub fn minibatch_indices<R: Rng>(&self, batch_size: usize, rng: &mut R) -> Vec<Vec<usize>> {
        let mut order: Vec<usize> = (0..self.rows()).collect();
        order.shuffle(rng);
        order.chunks(batch_size).map(<[usize]>::to_vec).collect()
    }

    /// Copies the rows `indices` into `out` (a minibatch's contiguous arrays).
    pub fn gather(&self, indices: &[usize], out: &mut MinibatchData) {
        out.clear();
        for &i in indices {
            out.obs
                .extend_from_slice(&self.obs[i * self.obs_dim..(i + 1) * self.obs_dim]);
            out.actions
                .extend_from_slice(&self.actions[i * self.act_dim..(i + 1) * self.act_dim]);
            out.old_log_prob.push(self.log_probs[i]);
            out.advantages.push(self.advantages[i]);
            out.returns.push(self.returns[i]);
            out.old_values.push(self.values[i]);
            if !self.anchors.is_empty() {
                out.anchors
                    .extend_from_slice(&self.anchors[i * self.act_dim..(i + 1) * self.act_dim]);
            }
        }
        out.rows = indices.len();
    }

    /// `1 - Var(returns - values) / Var(returns)` over the rollout (SB3's explained variance; NaN when
    /// the returns do not vary).
    pub fn explained_variance(&self) -> f64 {
        let variance = |xs: &mut dyn Iterator<Item = f64>| {
            let v: Vec<f64> = xs.collect();
            let mean = v.iter().sum::<f64>() / v.len() as f64;
            v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / v.len() as f64
        };
        let var_y = variance(&mut self.returns.iter().map(|&r| f64::from(r)));
        if var_y == 0.0 {
            return f64::NAN;
        }
        let var_diff = variance(
            &mut self
                .returns
                .iter()
                .zip(&self.values)
                .map(|(&r, &v)| f64::from(r - v)),
        );
        1.0 - var_diff / var_y
    }
}

/// A minibatch's rows, gathered contiguously.
#[derive(Debug, Clone, Default)]
pub struct MinibatchData {
    /// `rows x obs_dim`.
    pub obs: Vec<f32>,
    /// `rows x act_dim`.
    pub actions: Vec<f32>,
    /// Rollout log-probabilities.
    pub old_log_prob: Vec<f32>,
    /// Advantages (normalised in place by the update when asked).
    pub advantages: Vec<f32>,
    /// Returns.
    pub returns: Vec<f32>,
    /// Rollout values.
    pub old_values: Vec<f32>,
    /// The anchor actions (`rows x act_dim`), empty without an anchor.
    pub anchors: Vec<f32>,
    /// Number of rows.
    pub rows: usize,
}

impl MinibatchData {
    fn clear(&mut self) {
        self.obs.clear();
        self.actions.clear();
        self.old_log_prob.clear();
        self.advantages.clear();
        self.returns.clear();
        self.old_values.clear();
        self.anchors.clear();
        self.rows = 0;
    }
}
