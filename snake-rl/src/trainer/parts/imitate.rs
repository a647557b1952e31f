//! `init`: before PPO, the run imitates a controller ([`crate::imitate`]): the training envs are
//! driven by it, the policy's mean is fitted to its actions (the critic to its returns with
//! `init.critic`), the action noise set; the fitted policy is evaluated at 0 timesteps and saved as
//! the checkpoint at 0 timesteps, and PPO starts from it. A run stopped during the initialisation
//! starts it over on resume (its checkpoint records `init_pending`).

use std::sync::Arc;
use std::time::Instant;

use snake_core::{StepBuffers, VecSnakeEnv};

use super::{Part, Setup};
use crate::config::InitConfig;
use crate::imitate;
use crate::model::Checkpoint;
use crate::trainer::run::Run;
use crate::trainer::{InitProgress, Observer, TrainError};

/// Offset of the seed of the `init` envs' reset from the run's seed, so that the controller's
/// episodes are not PPO's first ones.
pub const INIT_SEED_OFFSET: u64 = 1 << 40;

struct Imitate {
    init: InitConfig,
    /// The init is still to be done (a new run, or one stopped during it).
    pending: bool,
}

pub(crate) fn build(setup: &Setup<'_>) -> Result<Option<Box<dyn Part>>, TrainError> {
    Ok(setup.config.init.clone().map(|init| {
        Box::new(Imitate {
            init,
            pending: !setup.resumed,
        }) as Box<dyn Part>
    }))
}

impl Part for Imitate {
    fn checkpoint(&self, checkpoint: &mut Checkpoint) {
        checkpoint.init_pending = self.pending;
    }

    /// Drives the envs with the controller, fits the policy to it (the critic too with
    /// `init.critic`), sets the action noise, then evaluates the fitted policy (the row at 0
    /// timesteps). False when stopping was asked for (the initialisation is then done again on
    /// resume). Its time is the run's.
    fn before_training(
        &mut self,
        run: &mut Run,
        pool: &Arc<rayon::ThreadPool>,
        observer: &mut dyn Observer,
    ) -> Result<bool, TrainError> {
        if !self.pending {
            return Ok(true);
        }
        let init = self.init.clone();
        let start = Instant::now();
        let m = run.config.n_envs;
        let mut controller = init
            .demonstrator(&run.env_config, m)
            .map_err(|e| TrainError::Setup(format!("init.imitate: {}", e.message())))?;
        let mut envs = VecSnakeEnv::new(run.env_config.clone(), m)?;
        envs = if run.threads == 1 {
            envs.with_threads(1)?
        } else {
            envs.with_pool(pool.clone())
        };
        let mut out = StepBuffers::for_envs(&envs);
        let seed = run.config.seed.wrapping_add(INIT_SEED_OFFSET);
        envs.reset(Some(seed), &mut out.obs)?;
        let total_steps = init.steps.div_ceil(m as u64) * m as u64;
        let mut progress = InitProgress {
            steps: 0,
            total_steps,
            epoch: 0,
            epochs: init.epochs,
            bc_loss: None,
            critic_loss: None,
        };
        let data = imitate::collect(
            &mut controller,
            &mut envs,
            &mut out,
            init.steps,
            run.config.ppo.gamma,
            run.normalizer.as_mut(),
            &mut |done| {
                progress.steps = done;
                observer.on_init(&progress);
                observer.should_stop()
            },
        )?;
        drop(envs);
        let Some(data) = data else {
            return Ok(false);
        };
        progress.steps = total_steps;
        let collect_seconds = start.elapsed().as_secs_f64();
        let mut scalars = vec![("init/collect_seconds", collect_seconds)];
        if let Some(r) = data.mean_return() {
            scalars.push(("init/controller_ep_rew_mean", r));
        }
        if let Some(r) = data.success_rate() {
            scalars.push(("init/controller_success_rate", r));
        }
        let net = run.learner.net().clone();
        let mut params = run.learner.params.clone();
        let initial_loss = imitate::bc_loss(&net, &params, &data);
        scalars.push(("init/bc_loss", initial_loss));
        run.log_at(0, &scalars)?;
        let tb = &mut run.tb;
        let mut log_error = None;
        let losses = imitate::fit(&net, &mut params, &data, &init, &mut run.rng, &mut |e| {
            let mut values = vec![("init/bc_loss", e.bc_loss)];
            if let Some(c) = e.critic_loss {
                values.push(("init/critic_loss", c));
            }
            if let Err(err) = tb
                .scalars(e.epoch as u64, &values)
                .and_then(|()| tb.flush())
            {
                log_error = Some(err);
                return true;
            }
            progress.epoch = e.epoch;
            progress.bc_loss = Some(e.bc_loss);
            progress.critic_loss = e.critic_loss;
            observer.on_init(&progress);
            observer.should_stop()
        });
        if let Some(e) = log_error {
            return Err(TrainError::Io(format!(
                "cannot write TensorBoard logs: {e}"
            )));
        }
        let Some(losses) = losses else {
            return Ok(false);
        };
        let o = net.log_std_offset();
        params[o..o + net.act_dim()].fill(init.log_std as f32);
        run.learner.params.copy_from_slice(&params);
        self.pending = false;
        let seconds = start.elapsed().as_secs_f64();
        run.init_seconds = seconds;
        run.log_at(init.epochs as u64, &[("init/seconds", seconds)])?;
        let last = losses.last().map_or(initial_loss, |l| l.bc_loss);
        observer.on_note(&format!(
            "init: imitated {} for {} env steps (its episodes: mean return {}, success {}), \
             fitted in {} epochs (mse {initial_loss:.4} -> {last:.4}), {seconds:.1} s",
            init.controller_label(),
            total_steps,
            data.mean_return()
                .map_or("n/a".into(), |r| format!("{r:.1}")),
            data.success_rate()
                .map_or("n/a".into(), |r| format!("{r:.2}")),
            init.epochs,
        ));
        if run.config.eval_freq > 0 && !run.evaluate(pool, observer)? {
            return Ok(false);
        }
        // The fitted policy alone, before any PPO update, as the checkpoint at 0 timesteps: it is
        // evaluated like any model (an experiment's "initialised policy alone"), and a run stopped
        // in its first rollout resumes from it without redoing the init.
        run.save_checkpoint("init")?;
        Ok(true)
    }
}
