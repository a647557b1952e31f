//! The state of one training session ([`Run`]) and SB3's `learn`: rollout, update, log; the
//! evaluations and checkpoints. What a feature adds (imitation init, the anchor, the energy ramp,
//! the steering assist) comes from its part ([`super::parts`]).

use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha12Rng;
use serde_json::{Map, Value};
use snake_core::EnvConfig;

use super::parts::{self, Part, Setup};
use super::{Observer, Outcome, TrainError};
use crate::config::RunConfig;
use crate::evaluate::{run_episodes, summarize, EvalError};
use crate::model::{self, Checkpoint, EnvSpec, SavedPolicy};
use crate::nn::{init_params, ActorCritic};
use crate::normalize::Normalizer;
use crate::policy::Policy;
use crate::ppo::{Learner, LossSettings, UpdateSettings, UpdateStats};
use crate::rundir::{EvaluationRow, RunDir, MODEL_FILE};
use crate::tensorboard::EventWriter;

/// The state of one training session.
pub(crate) struct Run {
    pub(crate) config: RunConfig,
    pub(crate) env_config: EnvConfig,
    /// The env keywords `env_config` was built from.
    pub(crate) env: Map<String, Value>,
    /// The texts of its robot and world files as this session read them ([`model::env_files`]).
    pub(crate) env_files: Option<Value>,
    pub(crate) dir: RunDir,
    pub(crate) threads: usize,
    pub(crate) learner: Learner,
    pub(crate) normalizer: Option<Normalizer>,
    pub(crate) rng: ChaCha12Rng,
    pub(crate) timesteps: u64,
    pub(crate) start_timesteps: u64,
    pub(crate) n_updates: u64,
    pub(crate) wall_offset: f64,
    pub(crate) started: Instant,
    pub(crate) eval_seconds: f64,
    pub(crate) rollout_seconds: f64,
    pub(crate) update_seconds: f64,
    /// Seconds of this session's `init` (its evaluation excluded; 0 without).
    pub(crate) init_seconds: f64,
    pub(crate) tb: EventWriter,
    /// Return, length and success of the last 100 training episodes.
    pub(crate) episodes: VecDeque<(f64, u64, bool)>,
    pub(crate) last_evaluation: Option<EvaluationRow>,
    /// RSS after this session's first update (see [`super::Summary::rss_mib`]).
    pub(crate) rss_first_update: Option<f64>,
    /// The features this run has, in the registry's order ([`parts::build`]).
    pub(crate) parts: Vec<Box<dyn Part>>,
}

impl Run {
    pub(super) fn new(
        config: RunConfig,
        dir: RunDir,
        threads: usize,
        checkpoint: Option<(Checkpoint, Option<Map<String, Value>>)>,
    ) -> Result<Self, TrainError> {
        // The env keywords: the configuration's, or a resumed checkpoint's where it records files
        // that changed since (see `ResumePoint::notes`).
        let (checkpoint, env) = match checkpoint {
            Some((c, Some(env))) => (Some(c), env),
            other => (other.map(|(c, _)| c), config.env.clone()),
        };
        let env_config = crate::config::env_config(config.joints, config.preset, &env, "env")
            .map_err(|e| TrainError::Setup(e.0))?;
        // The robot and world files as read now, recorded in every model and checkpoint this session
        // writes, even if a file is edited while it trains.
        let env_files = model::env_files(&env_config);
        // A checkpoint written during the initialisation holds nothing to keep but its time: the
        // run starts over, initialisation included.
        let (checkpoint, restart_wall) = match checkpoint {
            Some(c) if c.init_pending => (None, c.wall_time),
            other => (other, 0.0),
        };
        let parts = parts::build(&Setup {
            config: &config,
            env_config: &env_config,
            dir: &dir,
            resumed: checkpoint.is_some(),
        })?;
        let (obs_dim, act_dim) = (env_config.observation_dim(), env_config.action_dim());
        let net = ActorCritic::new(config.arch.clone(), obs_dim, act_dim);
        let tb = EventWriter::create(&dir.tensorboard_dir()).map_err(|e| {
            TrainError::Io(format!(
                "cannot write TensorBoard logs in {}: {e}",
                dir.path().display()
            ))
        })?;
        let (learner, normalizer, rng, timesteps, n_updates, wall_offset) = match checkpoint {
            Some(c) => {
                if c.policy.net != net {
                    return Err(TrainError::Setup(format!(
                        "the checkpoint's network ({} for {} observations and {} actions) does not fit the run's",
                        c.policy.net.arch(),
                        c.policy.net.obs_dim(),
                        c.policy.net.act_dim()
                    )));
                }
                let mut learner = Learner::new(net, c.policy.params, threads);
                learner.adam = c.adam;
                let normalizer = c.normalizer.map(|mut n| {
                    n.reset_returns(config.n_envs);
                    n
                });
                (
                    learner,
                    normalizer,
                    c.rng,
                    c.policy.timesteps,
                    c.n_updates,
                    c.wall_time,
                )
            }
            None => {
                let mut rng = ChaCha12Rng::seed_from_u64(config.seed);
                let mut params = init_params(&net, &mut rng);
                let o = net.log_std_offset();
                params[o..o + act_dim].fill(config.log_std_init as f32);
                let normalizer = config
                    .normalize
                    .then(|| Normalizer::new(obs_dim, config.n_envs, config.ppo.gamma));
                (
                    Learner::new(net, params, threads),
                    normalizer,
                    rng,
                    0,
                    0,
                    restart_wall,
                )
            }
        };
        Ok(Run {
            env_config,
            env,
            env_files,
            dir,
            threads,
            learner,
            normalizer,
            rng,
            start_timesteps: timesteps,
            timesteps,
            n_updates,
            wall_offset,
            started: Instant::now(),
            eval_seconds: 0.0,
            rollout_seconds: 0.0,
            update_seconds: 0.0,
            init_seconds: 0.0,
            tb,
            episodes: VecDeque::with_capacity(100),
            last_evaluation: None,
            rss_first_update: None,
            parts,
            config,
        })
    }

    pub(crate) fn wall_time(&self) -> f64 {
        self.wall_offset + self.started.elapsed().as_secs_f64()
    }

    /// The policy as a model file holds it, with what each part records.
    pub(crate) fn saved_policy(&self) -> SavedPolicy {
        let mut policy = SavedPolicy {
            net: self.learner.net().clone(),
            params: self.learner.params.clone(),
            obs_rms: self.normalizer.as_ref().map(|n| n.obs_rms.clone()),
            env: EnvSpec {
                joints: self.config.joints,
                preset: self.config.preset,
                env: self.recorded_env(),
            },
            steer_assist: None,
            timesteps: self.timesteps,
        };
        for part in &self.parts {
            part.saved_policy(&mut policy);
        }
        policy
    }

    /// The env keywords a saved model gets: the session's, with the record in place of a robot or
    /// world file edited since the session read it (the model then records what it trained on, not
    /// the edit; `apply_env_files` on the session's own record cannot fail but is kept quiet if so).
    fn recorded_env(&self) -> Map<String, Value> {
        let mut env = self.env.clone();
        if let Some(records) = &self.env_files {
            let _ = model::apply_env_files(&mut env, records);
        }
        env
    }

    pub(crate) fn save_checkpoint(&self, reason: &str) -> Result<PathBuf, TrainError> {
        let path = self.dir.checkpoint_path(self.timesteps);
        let mut c = Checkpoint {
            policy: self.saved_policy(),
            adam: self.learner.adam.clone(),
            normalizer: self.normalizer.clone(),
            rng: self.rng.clone(),
            n_updates: self.n_updates,
            wall_time: self.wall_time(),
            reason: reason.into(),
            init_pending: false,
        };
        for part in &self.parts {
            part.checkpoint(&mut c);
        }
        model::save_checkpoint(&path, &c).map_err(|e| {
            TrainError::Io(format!("cannot write checkpoint {}: {e}", path.display()))
        })?;
        self.dir
            .write_checkpoint_note(self.timesteps, c.wall_time, reason)?;
        Ok(path)
    }

    fn save_final(&self) -> Result<PathBuf, TrainError> {
        let path = self.dir.path().join(MODEL_FILE);
        model::save_policy(&path, &self.saved_policy())
            .map_err(|e| TrainError::Io(format!("cannot write {}: {e}", path.display())))?;
        Ok(path)
    }

    /// Evaluates the current policy (as the parts make it act) on the run's threads; false when
    /// interrupted.
    pub(crate) fn evaluate(
        &mut self,
        pool: &Arc<rayon::ThreadPool>,
        observer: &mut dyn Observer,
    ) -> Result<bool, TrainError> {
        let start = Instant::now();
        let mut policy = Policy::new(
            self.learner.net().clone(),
            self.learner.params.clone(),
            self.normalizer.as_ref().map(|n| n.obs_rms.clone()),
        );
        for part in &self.parts {
            policy = part.acting_policy(policy);
        }
        let episodes = match run_episodes(
            &mut policy,
            &self.env_config,
            self.config.eval_episodes,
            self.config.eval_seed(),
            true,
            (self.threads > 1).then_some(pool),
            &mut || observer.should_stop(),
        ) {
            Ok(e) => e,
            Err(EvalError::Interrupted) => return Ok(false),
            Err(EvalError::Env(e)) => return Err(TrainError::Env(e)),
            // The native policy's actor cannot fail; kept total rather than a panic.
            Err(EvalError::Actor(message)) => return Err(TrainError::Setup(message)),
        };
        let s = summarize(&episodes);
        let row = EvaluationRow {
            timesteps: self.timesteps,
            mean_return: s.mean_return,
            std_return: s.std_return,
            success_rate: s.success_rate,
            mean_steps_to_goal: s.mean_steps_to_goal,
            wall_time: (self.wall_time() * 1000.0).round() / 1000.0,
        };
        self.dir.append_evaluation(&row)?;
        let mut values = vec![
            ("eval/mean_reward", s.mean_return),
            ("eval/std_reward", s.std_return),
            ("eval/success_rate", s.success_rate),
            ("eval/mean_ep_length", s.mean_length),
            ("eval/mean_speed", s.mean_speed),
        ];
        if let Some(steps) = s.mean_steps_to_goal {
            values.push(("eval/mean_steps_to_goal", steps));
        }
        self.log(&values)?;
        self.last_evaluation = Some(row);
        observer.on_evaluation(&row);
        self.eval_seconds += start.elapsed().as_secs_f64();
        Ok(true)
    }

    fn interrupted(&mut self, trained: u64) -> Result<Outcome, TrainError> {
        // The partial rollout is dropped: the saved state is that of the last complete update.
        self.timesteps = trained;
        let path = self.save_checkpoint("interrupt")?;
        self.save_final()?;
        Ok(Outcome::Interrupted(self.summary(), path))
    }

    /// Each part's work before the first rollout, in the registry's order; false when stopping was
    /// asked for. A part is out of `self.parts` during its own call (so the run it is given holds
    /// every other part) and back in it afterwards, whatever the call returned.
    fn before_training(
        &mut self,
        pool: &Arc<rayon::ThreadPool>,
        observer: &mut dyn Observer,
    ) -> Result<bool, TrainError> {
        for i in 0..self.parts.len() {
            let mut part = std::mem::replace(&mut self.parts[i], Box::new(parts::Absent));
            let done = part.before_training(self, pool, observer);
            self.parts[i] = part;
            if !done? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// SB3's `learn`: collect a rollout, update, log; evaluate and checkpoint after the update that
    /// crosses each multiple of their frequency.
    pub(super) fn learn(
        &mut self,
        pool: &Arc<rayon::ThreadPool>,
        observer: &mut dyn Observer,
    ) -> Result<Outcome, TrainError> {
        let c = self.config.clone();
        if !self.before_training(pool, observer)? {
            return self.interrupted(self.timesteps);
        }
        let mut rollout = self.start_rollouts(pool)?;
        // The next multiple of `freq` after `t` (never, for 0).
        let every = |freq: u64, t: u64| t.checked_div(freq).map_or(u64::MAX, |k| (k + 1) * freq);
        let mut next_eval = every(c.eval_freq, self.timesteps);
        let mut next_checkpoint = every(c.checkpoint_freq, self.timesteps);
        let mut last_eval_at = None;
        observer.on_start(self.timesteps, c.timesteps);
        while self.timesteps < c.timesteps {
            let rollout_start = Instant::now();
            let trained = self.timesteps;
            for part in &mut self.parts {
                part.before_rollout(trained, &self.env_config, &mut rollout.envs)?;
            }
            if !self.collect_rollout(&mut rollout, observer)? {
                return self.interrupted(trained);
            }
            let rollout_seconds = rollout_start.elapsed().as_secs_f64();
            let update_start = Instant::now();
            let settings = self.update_settings();
            let stats = self.update(&rollout.buffer, &settings, pool)?;
            let update_seconds = update_start.elapsed().as_secs_f64();
            self.log_update(&stats, &settings, rollout_seconds, update_seconds, observer)?;
            // After the update: the evaluation and checkpoint at T hold the policy trained on T.
            if self.timesteps >= next_eval && self.timesteps < c.timesteps {
                if !self.evaluate(pool, observer)? {
                    return self.interrupted(self.timesteps);
                }
                last_eval_at = Some(self.timesteps);
                next_eval = every(c.eval_freq, self.timesteps);
            }
            if self.timesteps >= next_checkpoint && self.timesteps < c.timesteps {
                self.save_checkpoint("periodic")?;
                next_checkpoint = every(c.checkpoint_freq, self.timesteps);
            }
        }
        if last_eval_at != Some(self.timesteps) && !self.evaluate(pool, observer)? {
            return self.interrupted(self.timesteps);
        }
        self.save_checkpoint("final")?;
        self.save_final()?;
        Ok(Outcome::Finished(self.summary()))
    }

    /// The update's settings at the current progress (schedules of the learning rate and clip
    /// range; each part's share of the loss).
    fn update_settings(&self) -> UpdateSettings {
        let (c, ppo) = (&self.config, &self.config.ppo);
        let progress_remaining = 1.0 - self.timesteps as f64 / c.timesteps as f64;
        let mut loss = LossSettings {
            clip_range: ppo.clip_range.at(progress_remaining) as f32,
            clip_range_vf: ppo.clip_range_vf.map(|v| v as f32),
            ent_coef: ppo.ent_coef as f32,
            vf_coef: ppo.vf_coef as f32,
            normalize_advantage: ppo.normalize_advantage,
            anchor_weight: 0.0,
        };
        for part in &self.parts {
            part.loss(progress_remaining, &mut loss);
        }
        UpdateSettings {
            n_epochs: ppo.n_epochs,
            batch_size: ppo.batch_size,
            loss,
            max_grad_norm: ppo.max_grad_norm,
            target_kl: ppo.target_kl,
            learning_rate: ppo.learning_rate.at(progress_remaining),
        }
    }

    /// SB3's `train`: the PPO update over the rollout. A loss or gradient that turns non-finite
    /// restores the state before the update, saves it, and stops training.
    fn update(
        &mut self,
        buffer: &crate::buffer::RolloutBuffer,
        settings: &UpdateSettings,
        pool: &Arc<rayon::ThreadPool>,
    ) -> Result<UpdateStats, TrainError> {
        let before = (
            self.learner.params.clone(),
            self.learner.adam.clone(),
            self.rng.clone(),
        );
        match self
            .learner
            .update(buffer, settings, &mut self.rng, Some(pool))
        {
            Ok(stats) => {
                self.n_updates += stats.epochs as u64;
                Ok(stats)
            }
            Err(e) => {
                // Keep the last good state: the parameters before this update.
                (self.learner.params, self.learner.adam, self.rng) = before;
                let path = self.save_checkpoint("non-finite")?;
                Err(TrainError::NonFinite(format!(
                    "training stopped at update {} ({} timesteps): {e}; saved the state before it to {}",
                    self.n_updates / self.config.ppo.n_epochs.max(1) as u64 + 1,
                    self.timesteps,
                    path.display()
                )))
            }
        }
    }
}
