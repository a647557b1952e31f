//! PPO's loss on one minibatch and its gradient, as Stable-Baselines3 2.x's `PPO.train` computes it
//! for a diagonal Gaussian policy with a state-independent `log_std`:
//!
//! ```text
//! A      = (A - mean(A)) / (std(A) + 1e-8)          per minibatch (std with Bessel's correction)
//! ratio  = exp(log_prob - old_log_prob)
//! policy = -mean(min(A * ratio, A * clamp(ratio, 1 - clip, 1 + clip)))
//! value  = mean((returns - v)^2),  v = V or old_V + clamp(V - old_V, -clip_vf, clip_vf)
//! entropy_loss = -mean(entropy)
//! loss   = policy + ent_coef * entropy_loss + vf_coef * value
//! ```
//!
//! A run that initialises by imitation may keep an anchor (`init.anchor`, weight `w`):
//! `loss += w * mean((mean_action - anchor_action)^2)` over the minibatch's rows and action
//! dimensions, the anchor actions being the fitted policy's means in the states PPO's policy visited.
//! With `w = 0` nothing of it is computed: SB3's loss, bit for bit.
//!
//! The gradient is written out by hand (no autograd): through the Gaussian's log-probability to the
//! action means and `log_std`, and through the value head; [`ActorCritic::backward`] takes it from
//! there. Every operation is float32, in the order PyTorch evaluates it; ties and bounds follow
//! PyTorch's autograd (`minimum` splits a tie's gradient in halves, `clamp` passes it on at the bounds).

use crate::nn::{ActorCritic, Workspace};

/// log(sqrt(2 pi)), as torch's `Normal.log_prob` subtracts it (a Python float rounded to float32).
pub const LOG_SQRT_2PI: f32 = 0.918_938_5;

/// The loss's hyperparameters for one update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LossSettings {
    /// PPO's clip range of the probability ratio.
    pub clip_range: f32,
    /// Clip range of the value prediction around the rollout's value, if any.
    pub clip_range_vf: Option<f32>,
    /// Weight of the entropy loss.
    pub ent_coef: f32,
    /// Weight of the value loss.
    pub vf_coef: f32,
    /// Normalise advantages per minibatch (SB3's `normalize_advantage`).
    pub normalize_advantage: bool,
    /// Weight of the anchor (0: no anchor, SB3's loss).
    pub anchor_weight: f32,
}

/// Rows of one minibatch (or of one thread's chunk of it), row-major.
#[derive(Debug, Clone, Copy)]
pub struct Minibatch<'a> {
    /// `rows x obs_dim` observations (as the policy saw them: normalised if normalisation is on).
    pub obs: &'a [f32],
    /// `rows x act_dim` actions as sampled (before clipping to the action space).
    pub actions: &'a [f32],
    /// Log-probabilities of the actions under the rollout's policy.
    pub old_log_prob: &'a [f32],
    /// Advantages, already normalised over the whole minibatch when that is asked for
    /// ([`normalize_advantages`]).
    pub advantages: &'a [f32],
    /// Returns (advantages + values).
    pub returns: &'a [f32],
    /// Values under the rollout's policy.
    pub old_values: &'a [f32],
    /// `rows x act_dim` anchor actions (the fitted policy's means) in the same states, or empty
    /// without an anchor.
    pub anchors: &'a [f32],
    /// Number of rows.
    pub rows: usize,
}

impl<'a> Minibatch<'a> {
    /// Rows `start..end`.
    pub fn slice(&self, start: usize, end: usize, obs_dim: usize, act_dim: usize) -> Minibatch<'a> {
        Minibatch {
            obs: &self.obs[start * obs_dim..end * obs_dim],
            actions: &self.actions[start * act_dim..end * act_dim],
            old_log_prob: &self.old_log_prob[start..end],
            advantages: &self.advantages[start..end],
            returns: &self.returns[start..end],
            old_values: &self.old_values[start..end],
            anchors: if self.anchors.is_empty() {
                self.anchors
            } else {
                &self.anchors[start * act_dim..end * act_dim]
            },
            rows: end - start,
        }
    }
}

/// The loss terms and diagnostics of one minibatch, as SB3 logs them.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LossStats {
    /// The clipped surrogate loss.
    pub policy_loss: f32,
    /// Mean squared error of the (clipped) values against the returns.
    pub value_loss: f32,
    /// Minus the mean entropy.
    pub entropy_loss: f32,
    /// Mean squared distance of the action means to the anchor actions (0 without an anchor).
    pub anchor_loss: f32,
    /// `policy + ent_coef * entropy_loss + vf_coef * value (+ anchor_weight * anchor_loss)`.
    pub loss: f32,
    /// `mean((ratio - 1) - log ratio)`, the KL estimate SB3's `target_kl` tests.
    pub approx_kl: f32,
    /// Fraction of rows whose ratio was clipped.
    pub clip_fraction: f32,
}

/// Sums over the rows of one chunk, merged into [`LossStats`] by [`LossSums::stats`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LossSums {
    /// Sum of min(surrogates).
    pub surrogate: f64,
    /// Sum of squared value errors.
    pub value_error: f64,
    /// Sum of the KL estimate's terms.
    pub kl: f64,
    /// Rows with a clipped ratio.
    pub clipped: usize,
    /// Sum of squared distances to the anchor actions (every action dimension).
    pub anchor_error: f64,
}

impl LossSums {
    /// Adds another chunk's sums.
    pub fn merge(&mut self, other: &LossSums) {
        self.surrogate += other.surrogate;
        self.value_error += other.value_error;
        self.kl += other.kl;
        self.clipped += other.clipped;
        self.anchor_error += other.anchor_error;
    }

    /// The minibatch's loss terms from the sums over all its `rows` of `act_dim` actions, and the
    /// distribution's entropy (the same for every row: the standard deviation does not depend on the
    /// state).
    pub fn stats(
        &self,
        rows: usize,
        act_dim: usize,
        entropy: f32,
        settings: &LossSettings,
    ) -> LossStats {
        let n = rows as f64;
        let policy_loss = -(self.surrogate / n) as f32;
        let value_loss = (self.value_error / n) as f32;
        let entropy_loss = -entropy;
        let anchor_loss = (self.anchor_error / (n * act_dim as f64)) as f32;
        let mut loss =
            policy_loss + settings.ent_coef * entropy_loss + settings.vf_coef * value_loss;
        if settings.anchor_weight > 0.0 {
            loss += settings.anchor_weight * anchor_loss;
        }
        LossStats {
            policy_loss,
            value_loss,
            entropy_loss,
            anchor_loss,
            loss,
            approx_kl: (self.kl / n) as f32,
            clip_fraction: (self.clipped as f64 / n) as f32,
        }
    }
}

/// Per-row scratch of the loss, reused between minibatches.
#[derive(Debug, Clone, Default)]
pub struct LossScratch {
    /// Log-probabilities of the chunk's actions under the current policy.
    pub log_prob: Vec<f32>,
    /// dL/d(log_std) of the chunk (without the entropy's share, which [`add_entropy_gradient`]
    /// adds once per minibatch).
    pub d_log_std: Vec<f32>,
    d_log_prob: Vec<f32>,
    std: Vec<f32>,
    var: Vec<f32>,
    log_scale: Vec<f32>,
}

/// Mean of float32 values (accumulated in double: within an ulp of torch's pairwise sums).
fn mean(values: &[f32]) -> f32 {
    (values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64) as f32
}

/// `(A - mean(A)) / (std(A) + 1e-8)` in place, std with Bessel's correction (torch's `std()`); a single
/// row is left as it is, as SB3 does.
pub fn normalize_advantages(advantages: &mut [f32]) {
    let rows = advantages.len();
    if rows < 2 {
        return;
    }
    let m = mean(advantages);
    let var = advantages
        .iter()
        .map(|&a| {
            let d = f64::from(a) - f64::from(m);
            d * d
        })
        .sum::<f64>()
        / (rows - 1) as f64;
    let std = var.sqrt() as f32;
    for a in advantages {
        *a = (*a - m) / (std + 1e-8);
    }
}

/// Entropy of N(mean, exp(log_std)^2), the same for every row: `sum_j 0.5 + 0.5 log(2 pi) + log_std_j`.
pub fn gaussian_entropy(log_std: &[f32]) -> f32 {
    // 0.5 + 0.5 * log(2 pi), in double as Python computes it, then float32.
    let entropy_const = (0.5 + 0.5 * (2.0 * std::f64::consts::PI).ln()) as f32;
    log_std.iter().map(|l| entropy_const + l.exp().ln()).sum()
}

/// Log-probabilities of `actions` under N(mean, exp(log_std)^2), one per row, into `scratch.log_prob`.
pub fn gaussian_log_prob(
    mean_actions: &[f32],
    log_std: &[f32],
    actions: &[f32],
    rows: usize,
    scratch: &mut LossScratch,
) {
    let n = log_std.len();
    // torch: scale = exp(log_std), var = scale^2, log_scale = log(scale).
    scratch.std.clear();
    scratch.std.extend(log_std.iter().map(|l| l.exp()));
    scratch.var.clear();
    scratch.var.extend(scratch.std.iter().map(|s| s * s));
    scratch.log_scale.clear();
    scratch.log_scale.extend(scratch.std.iter().map(|s| s.ln()));
    scratch.log_prob.clear();
    for r in 0..rows {
        let mu = &mean_actions[r * n..(r + 1) * n];
        let a = &actions[r * n..(r + 1) * n];
        let mut lp = 0.0f32;
        for j in 0..n {
            let diff = a[j] - mu[j];
            lp += -(diff * diff) / (2.0 * scratch.var[j]) - scratch.log_scale[j] - LOG_SQRT_2PI;
        }
        scratch.log_prob.push(lp);
    }
}

/// Forward pass and loss terms of a chunk of a minibatch of `total_rows` rows; fills `ws.d_mean`,
/// `ws.d_value` and `scratch.d_log_std` with the chunk's share of the loss's gradient, ready for
/// [`backward`].
pub fn forward(
    net: &ActorCritic,
    params: &[f32],
    chunk: &Minibatch<'_>,
    total_rows: usize,
    settings: &LossSettings,
    ws: &mut Workspace,
    scratch: &mut LossScratch,
) -> LossSums {
    let rows = chunk.rows;
    let n = net.act_dim();
    net.forward(params, chunk.obs, rows, ws);
    let log_std = &params[net.log_std_offset()..net.log_std_offset() + n];
    let mut sums = policy_terms(
        &ws.mean,
        log_std,
        chunk,
        total_rows,
        settings,
        scratch,
        &mut ws.d_mean,
    );
    sums.value_error = value_terms(&ws.value, chunk, total_rows, settings, &mut ws.d_value);
    sums
}

/// The policy's part of the loss for a chunk whose action means are `mean`: the surrogate, KL and
/// clip sums, dL/d(mean) into `d_mean` and dL/d(log_std) (the surrogate's share) into
/// `scratch.d_log_std`.
pub fn policy_terms(
    mean: &[f32],
    log_std: &[f32],
    chunk: &Minibatch<'_>,
    total_rows: usize,
    settings: &LossSettings,
    scratch: &mut LossScratch,
    d_mean: &mut [f32],
) -> LossSums {
    let rows = chunk.rows;
    let n = log_std.len();
    let b = total_rows as f32;
    gaussian_log_prob(mean, log_std, chunk.actions, rows, scratch);

    // The surrogate and its gradient with respect to each row's log-probability.
    let (lo, hi) = (1.0 - settings.clip_range, 1.0 + settings.clip_range);
    let mut sums = LossSums::default();
    scratch.d_log_prob.clear();
    for r in 0..rows {
        let log_ratio = scratch.log_prob[r] - chunk.old_log_prob[r];
        let ratio = log_ratio.exp();
        let adv = chunk.advantages[r];
        let s1 = adv * ratio;
        let s2 = adv * ratio.clamp(lo, hi);
        sums.surrogate += f64::from(s1.min(s2));
        sums.kl += f64::from((ratio - 1.0) - log_ratio);
        sums.clipped += usize::from((ratio - 1.0).abs() > settings.clip_range);
        let inside = if (lo..=hi).contains(&ratio) { 1.0 } else { 0.0 };
        // d min(s1, s2): all to the smaller side, half to each on a tie (torch's `minimum`).
        let weight = if s1 < s2 {
            1.0
        } else if s1 > s2 {
            inside
        } else {
            0.5 + 0.5 * inside
        };
        scratch.d_log_prob.push(-(adv * ratio * weight) / b);
    }

    // Through the Gaussian: d log_prob / d mean = (a - mean) / var,
    // d log_prob / d log_std = (a - mean)^2 / var - 1.
    scratch.d_log_std.clear();
    scratch.d_log_std.resize(n, 0.0);
    for r in 0..rows {
        let g = scratch.d_log_prob[r];
        for j in 0..n {
            let diff = chunk.actions[r * n + j] - mean[r * n + j];
            let var = scratch.var[j];
            d_mean[r * n + j] = g * (diff / var);
            scratch.d_log_std[j] += g * (diff * diff / var - 1.0);
        }
    }
    if settings.anchor_weight > 0.0 && !chunk.anchors.is_empty() {
        // d/d(mean) of w * sum((mean - target)^2) / (b * n).
        let scale = 2.0 * settings.anchor_weight / (b * n as f32);
        for (k, (d, &target)) in d_mean[..rows * n].iter_mut().zip(chunk.anchors).enumerate() {
            let diff = mean[k] - target;
            sums.anchor_error += f64::from(diff * diff);
            *d += scale * diff;
        }
    }
    sums
}

/// The value loss's sum of squared errors for a chunk whose values are `values`, and dL/d(value)
/// into `d_value`.
pub fn value_terms(
    values: &[f32],
    chunk: &Minibatch<'_>,
    total_rows: usize,
    settings: &LossSettings,
    d_value: &mut [f32],
) -> f64 {
    let b = total_rows as f32;
    let mut sum = 0.0f64;
    for r in 0..chunk.rows {
        let v = values[r];
        let (v_pred, pass) = match settings.clip_range_vf {
            None => (v, 1.0),
            Some(c) => {
                let delta = v - chunk.old_values[r];
                let inside = if (-c..=c).contains(&delta) { 1.0 } else { 0.0 };
                (chunk.old_values[r] + delta.clamp(-c, c), inside)
            }
        };
        let err = chunk.returns[r] - v_pred;
        sum += f64::from(err * err);
        d_value[r] = settings.vf_coef * (2.0 * (v_pred - chunk.returns[r]) / b) * pass;
    }
    sum
}

/// The chunk's gradient of the loss of the last [`forward`] with respect to every parameter, into
/// `grads` (`log_std` without the entropy's share: see [`add_entropy_gradient`]).
pub fn backward(
    net: &ActorCritic,
    params: &[f32],
    obs: &[f32],
    ws: &mut Workspace,
    scratch: &LossScratch,
    grads: &mut [f32],
) {
    net.backward(params, obs, ws, grads);
    let o = net.log_std_offset();
    grads[o..o + net.act_dim()].copy_from_slice(&scratch.d_log_std);
}

/// Adds the entropy term's gradient to `log_std`'s: the entropy loss is `-mean(entropy)` and each
/// row's entropy grows by 1 with each `log_std`, so every `log_std` gets `-ent_coef`.
pub fn add_entropy_gradient(net: &ActorCritic, settings: &LossSettings, grads: &mut [f32]) {
    let o = net.log_std_offset();
    for g in &mut grads[o..o + net.act_dim()] {
        *g -= settings.ent_coef;
    }
}
