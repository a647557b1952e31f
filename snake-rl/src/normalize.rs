//! Observation and reward normalisation as Stable-Baselines3's `VecNormalize` does it (the
//! `normalize: true` of a run): running mean and variance of the observations, and of the discounted
//! returns for scaling rewards; observations clipped to +-10 after normalising, rewards too.

use serde::{Deserialize, Serialize};

/// Added to the variance before the square root (SB3's `VecNormalize` epsilon).
pub const EPSILON: f64 = 1e-8;
/// Normalised observations and rewards are clipped to +-this (SB3's defaults).
pub const CLIP: f64 = 10.0;

/// Running mean and (population) variance, merged batch by batch (Chan et al.), in double precision;
/// SB3's `RunningMeanStd` with its initial count of 1e-4.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunningMeanStd {
    /// Mean of every component.
    pub mean: Vec<f64>,
    /// Variance of every component.
    pub var: Vec<f64>,
    /// Samples seen (starts at 1e-4).
    pub count: f64,
}

impl RunningMeanStd {
    /// Mean 0, variance 1, count 1e-4, for `dim` components.
    pub fn new(dim: usize) -> Self {
        RunningMeanStd {
            mean: vec![0.0; dim],
            var: vec![1.0; dim],
            count: 1e-4,
        }
    }

    /// Merges a batch of `rows` float32 rows (`rows x dim`, row-major). The batch's mean and variance
    /// are float32, as numpy's `mean(axis=0)` and `var(axis=0)` of a float32 array are (rows summed in
    /// order); the merge is in double.
    pub fn update(&mut self, batch: &[f32], rows: usize) {
        let dim = self.mean.len();
        debug_assert_eq!(batch.len(), rows * dim);
        if rows == 0 {
            return;
        }
        let n = rows as f64;
        for j in 0..dim {
            let column = || batch[j..].iter().step_by(dim).copied();
            let batch_mean = column().fold(0.0f32, |s, x| s + x) / rows as f32;
            let batch_var = column()
                .map(|x| (x - batch_mean) * (x - batch_mean))
                .fold(0.0f32, |s, x| s + x)
                / rows as f32;
            let (batch_mean, batch_var) = (f64::from(batch_mean), f64::from(batch_var));
            let delta = batch_mean - self.mean[j];
            let total = self.count + n;
            let m2 =
                self.var[j] * self.count + batch_var * n + delta * delta * self.count * n / total;
            self.mean[j] += delta * n / total;
            self.var[j] = m2 / total;
        }
        self.count += n;
    }

    /// `clip((x - mean) / sqrt(var + 1e-8), -10, 10)` of every row of `obs`, in place.
    pub fn normalize(&self, obs: &mut [f32]) {
        let dim = self.mean.len();
        for row in obs.chunks_exact_mut(dim) {
            for ((x, m), v) in row.iter_mut().zip(&self.mean).zip(&self.var) {
                let z = (f64::from(*x) - m) / (v + EPSILON).sqrt();
                *x = z.clamp(-CLIP, CLIP) as f32;
            }
        }
    }

    /// The same for single values (one component).
    pub fn update_scalars(&mut self, values: &[f64]) {
        let n = values.len() as f64;
        if values.is_empty() {
            return;
        }
        let batch_mean = values.iter().sum::<f64>() / n;
        let batch_var = values.iter().map(|x| (x - batch_mean).powi(2)).sum::<f64>() / n;
        let delta = batch_mean - self.mean[0];
        let total = self.count + n;
        let m2 = self.var[0] * self.count + batch_var * n + delta * delta * self.count * n / total;
        self.mean[0] += delta * n / total;
        self.var[0] = m2 / total;
        self.count += n;
    }
}

/// `VecNormalize`'s state: observation statistics, return statistics and the running discounted
/// return of every env.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Normalizer {
    /// Observation statistics.
    pub obs_rms: RunningMeanStd,
    /// Statistics of the discounted returns that scale the rewards.
    pub ret_rms: RunningMeanStd,
    /// Discounted return of each env's current episode.
    #[serde(skip)]
    pub returns: Vec<f64>,
    /// Discount of the returns.
    pub gamma: f64,
    /// Added to the variance before the square root (1e-8).
    pub epsilon: f64,
    /// Normalised observations are clipped to +-this (10).
    pub clip_obs: f64,
    /// Normalised rewards are clipped to +-this (10).
    pub clip_reward: f64,
}

impl Normalizer {
    /// Fresh statistics for `obs_dim` observations of `num_envs` envs, SB3's defaults.
    pub fn new(obs_dim: usize, num_envs: usize, gamma: f64) -> Self {
        Normalizer {
            obs_rms: RunningMeanStd::new(obs_dim),
            ret_rms: RunningMeanStd::new(1),
            returns: vec![0.0; num_envs],
            gamma,
            epsilon: EPSILON,
            clip_obs: CLIP,
            clip_reward: CLIP,
        }
    }

    /// Starts over the running returns of `num_envs` envs (after a reset of all of them).
    pub fn reset_returns(&mut self, num_envs: usize) {
        self.returns = vec![0.0; num_envs];
    }

    /// `clip((obs - mean) / sqrt(var + eps), -clip_obs, clip_obs)` of every row, in place.
    pub fn normalize_obs(&self, obs: &mut [f32]) {
        let dim = self.obs_rms.mean.len();
        for row in obs.chunks_exact_mut(dim) {
            for ((x, m), v) in row
                .iter_mut()
                .zip(&self.obs_rms.mean)
                .zip(&self.obs_rms.var)
            {
                let z = (f64::from(*x) - m) / (v + self.epsilon).sqrt();
                *x = z.clamp(-self.clip_obs, self.clip_obs) as f32;
            }
        }
    }

    /// Updates the return statistics with this step's rewards and scales the rewards in place;
    /// `dones` restart the running returns (after the update, as SB3 does).
    pub fn normalize_rewards(&mut self, rewards: &mut [f32], dones: &[bool]) {
        for (ret, &r) in self.returns.iter_mut().zip(rewards.iter()) {
            *ret = *ret * self.gamma + f64::from(r);
        }
        self.ret_rms.update_scalars(&self.returns);
        let scale = (self.ret_rms.var[0] + self.epsilon).sqrt();
        for r in rewards.iter_mut() {
            *r = (f64::from(*r) / scale).clamp(-self.clip_reward, self.clip_reward) as f32;
        }
        for (ret, &done) in self.returns.iter_mut().zip(dones) {
            if done {
                *ret = 0.0;
            }
        }
    }
}
