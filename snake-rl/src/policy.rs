//! A policy ready to act: the network, its parameters and, for runs that normalised observations,
//! the observation statistics it applies first.

use rand::Rng;
use snake_core::AssistedEnv;

use crate::model::SavedPolicy;
use crate::nn::{ActorCritic, Workspace};
use crate::normalize::RunningMeanStd;
use crate::ppo::act;
use crate::ppo::LossScratch;

/// A policy with its buffers.
#[derive(Debug, Clone)]
pub struct Policy {
    net: ActorCritic,
    params: Vec<f32>,
    obs_rms: Option<RunningMeanStd>,
    ws: Workspace,
    scratch: LossScratch,
    obs: Vec<f32>,
    values: Vec<f32>,
    log_probs: Vec<f32>,
    /// `baseline:steer`'s share of the env's actions, when the policy was trained with one.
    assist: Option<AssistedEnv>,
    /// The policy's own actions before the assist.
    own_actions: Vec<f32>,
}

impl Policy {
    /// The policy of `net` with `params`, normalising observations with `obs_rms` when given.
    pub fn new(net: ActorCritic, params: Vec<f32>, obs_rms: Option<RunningMeanStd>) -> Self {
        Policy {
            ws: net.workspace(1),
            net,
            params,
            obs_rms,
            scratch: LossScratch::default(),
            obs: Vec::new(),
            values: Vec::new(),
            log_probs: Vec::new(),
            assist: None,
            own_actions: Vec::new(),
        }
    }

    /// The policy with `baseline:steer` sharing the actions its env is given
    /// ([`Policy::env_actions`]).
    pub fn with_assist(mut self, assist: Option<AssistedEnv>) -> Self {
        self.assist = assist;
        self
    }

    /// The policy of a saved model.
    pub fn from_saved(saved: &SavedPolicy) -> Self {
        Policy::new(
            saved.net.clone(),
            saved.params.clone(),
            saved.obs_rms.clone(),
        )
    }

    /// The network.
    pub fn net(&self) -> &ActorCritic {
        &self.net
    }

    /// The parameters.
    pub fn params(&self) -> &[f32] {
        &self.params
    }

    fn prepare(&mut self, obs: &[f32], rows: usize) {
        self.obs.clear();
        self.obs
            .extend_from_slice(&obs[..rows * self.net.obs_dim()]);
        if let Some(rms) = &self.obs_rms {
            rms.normalize(&mut self.obs);
        }
    }

    /// Actions for `rows` raw observations into `actions` (`rows x act_dim`), clipped to [-1, 1]: the
    /// means (`deterministic`) or samples around them.
    pub fn act<R: Rng>(
        &mut self,
        obs: &[f32],
        rows: usize,
        deterministic: bool,
        rng: &mut R,
        actions: &mut [f32],
    ) {
        self.prepare(obs, rows);
        if deterministic {
            act::deterministic(
                &self.net,
                &self.params,
                &self.obs,
                rows,
                &mut self.ws,
                actions,
            );
        } else {
            self.values.resize(rows, 0.0);
            self.log_probs.resize(rows, 0.0);
            act::sample(
                &self.net,
                &self.params,
                &self.obs,
                rows,
                rng,
                &mut self.ws,
                &mut self.scratch,
                actions,
                &mut self.values,
                &mut self.log_probs,
            );
            for a in &mut actions[..rows * self.net.act_dim()] {
                *a = a.clamp(-1.0, 1.0);
            }
        }
    }

    /// The actions the env is given for `rows` raw observations (`rows x act_dim`): the policy's
    /// own ([`Policy::act`]), or with its assist, the assist's composition of them.
    pub fn env_actions<R: Rng>(
        &mut self,
        obs: &[f32],
        rows: usize,
        deterministic: bool,
        rng: &mut R,
        actions: &mut [f64],
    ) {
        let n = rows * self.net.act_dim();
        let mut own = std::mem::take(&mut self.own_actions);
        own.resize(n, 0.0);
        self.act(obs, rows, deterministic, rng, &mut own);
        match &self.assist {
            Some(assist) => assist.apply(obs, &own, rows, actions),
            None => {
                for (a, o) in actions[..n].iter_mut().zip(&own) {
                    *a = f64::from(*o);
                }
            }
        }
        self.own_actions = own;
    }

    /// Values of `rows` raw observations.
    pub fn values(&mut self, obs: &[f32], rows: usize) -> Vec<f32> {
        self.prepare(obs, rows);
        self.net
            .forward_value(&self.params, &self.obs, rows, &mut self.ws);
        self.ws.value[..rows].to_vec()
    }
}
