//! Acting with the policy: SB3's `policy(obs)` during rollouts (a Gaussian sample around the mean,
//! its log-probability and the value) and `predict(obs, deterministic=True)` for evaluation.

use rand::Rng;
use rand_distr::StandardNormal;

use super::loss::{gaussian_log_prob, LossScratch};
use crate::nn::{ActorCritic, Workspace};

/// Samples an action for each of `rows` observations: `mean + exp(log_std) * N(0, 1)`, unclipped,
/// with its log-probability and the observation's value.
#[allow(clippy::too_many_arguments)]
pub fn sample<R: Rng>(
    net: &ActorCritic,
    params: &[f32],
    obs: &[f32],
    rows: usize,
    rng: &mut R,
    ws: &mut Workspace,
    scratch: &mut LossScratch,
    actions: &mut [f32],
    values: &mut [f32],
    log_probs: &mut [f32],
) {
    let n = net.act_dim();
    net.forward(params, obs, rows, ws);
    let log_std = &params[net.log_std_offset()..net.log_std_offset() + n];
    for (r, row) in actions[..rows * n].chunks_exact_mut(n).enumerate() {
        for (j, a) in row.iter_mut().enumerate() {
            let eps: f32 = rng.sample(StandardNormal);
            *a = ws.mean[r * n + j] + log_std[j].exp() * eps;
        }
    }
    gaussian_log_prob(&ws.mean, log_std, &actions[..rows * n], rows, scratch);
    log_probs[..rows].copy_from_slice(&scratch.log_prob);
    values[..rows].copy_from_slice(&ws.value[..rows]);
}

/// The deterministic actions of `rows` observations: the means, clipped to the action space [-1, 1]
/// as SB3's `predict` clips them.
pub fn deterministic(
    net: &ActorCritic,
    params: &[f32],
    obs: &[f32],
    rows: usize,
    ws: &mut Workspace,
    actions: &mut [f32],
) {
    net.forward(params, obs, rows, ws);
    let n = net.act_dim();
    for (a, m) in actions[..rows * n].iter_mut().zip(&ws.mean) {
        *a = m.clamp(-1.0, 1.0);
    }
}

/// Clips sampled actions to the action space [-1, 1] (what the env is stepped with; the buffer keeps
/// the unclipped sample, as SB3 does).
pub fn clip_to_action_space(actions: &[f32], out: &mut [f32]) {
    for (o, a) in out.iter_mut().zip(actions) {
        *o = a.clamp(-1.0, 1.0);
    }
}
