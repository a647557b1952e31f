//! What a session reports: the TensorBoard scalars of each update (SB3's `train/*`, `rollout/*`,
//! `time/*`, and each part's), the observer's [`Progress`], and the session's [`Summary`].

use std::path::PathBuf;

use super::run::Run;
use super::{Observer, Progress, TrainError};
use crate::ppo::{UpdateSettings, UpdateStats};
use crate::rundir::EvaluationRow;

/// What a session did.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The run directory.
    pub run_dir: PathBuf,
    /// Timesteps at the start of this session (0, or the checkpoint resumed from).
    pub start_timesteps: u64,
    /// Timesteps at the end.
    pub timesteps: u64,
    /// Wall seconds of this session (evaluations included).
    pub seconds: f64,
    /// Of which evaluating.
    pub eval_seconds: f64,
    /// Of which collecting rollouts (env steps and policy inference).
    pub rollout_seconds: f64,
    /// Of which updating.
    pub update_seconds: f64,
    /// Of which initialising by imitation (`init`; 0 without).
    pub init_seconds: f64,
    /// The last evaluation.
    pub last_evaluation: Option<EvaluationRow>,
    /// Resident memory after the session's first update (worlds, buffers and networks allocated,
    /// so growth from there is what a long run adds) and at its end, MiB.
    pub rss_mib: (f64, f64),
    /// Threads used.
    pub threads: usize,
}

impl Summary {
    /// Timesteps per wall second of this session.
    pub fn timesteps_per_second(&self) -> f64 {
        (self.timesteps - self.start_timesteps) as f64 / self.seconds.max(1e-9)
    }

    /// The same without the evaluations' time and the initialisation's.
    pub fn training_timesteps_per_second(&self) -> f64 {
        (self.timesteps - self.start_timesteps) as f64
            / (self.seconds - self.eval_seconds - self.init_seconds).max(1e-9)
    }
}

/// Resident set size of this process, MiB (0 where /proc is missing).
pub fn rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(0.0, |kib| kib / 1024.0)
}

impl Run {
    /// Scalars to TensorBoard at the current timesteps.
    pub(crate) fn log(&mut self, values: &[(&str, f64)]) -> Result<(), TrainError> {
        self.log_at(self.timesteps, values)
    }

    /// Scalars to TensorBoard at `step`.
    pub(crate) fn log_at(&mut self, step: u64, values: &[(&str, f64)]) -> Result<(), TrainError> {
        self.tb
            .scalars(step, values)
            .and_then(|()| self.tb.flush())
            .map_err(|e| TrainError::Io(format!("cannot write TensorBoard logs: {e}")))
    }

    pub(super) fn summary(&self) -> Summary {
        Summary {
            run_dir: self.dir.path().to_path_buf(),
            start_timesteps: self.start_timesteps,
            timesteps: self.timesteps,
            seconds: self.started.elapsed().as_secs_f64(),
            eval_seconds: self.eval_seconds,
            rollout_seconds: self.rollout_seconds,
            update_seconds: self.update_seconds,
            init_seconds: self.init_seconds,
            last_evaluation: self.last_evaluation,
            rss_mib: {
                let end = rss_mib();
                (self.rss_first_update.unwrap_or(end), end)
            },
            threads: self.threads,
        }
    }

    /// After an update: the time split, memory, and SB3's `train/*`, `rollout/*` and `time/*`
    /// scalars (each part's after `train/*`'s) to TensorBoard and the observer.
    pub(super) fn log_update(
        &mut self,
        stats: &UpdateStats,
        settings: &UpdateSettings,
        rollout_seconds: f64,
        update_seconds: f64,
        observer: &mut dyn Observer,
    ) -> Result<(), TrainError> {
        self.rollout_seconds += rollout_seconds;
        self.update_seconds += update_seconds;
        let rss = rss_mib();
        self.rss_first_update.get_or_insert(rss);
        let busy = self.started.elapsed().as_secs_f64() - self.eval_seconds - self.init_seconds;
        let progress = Progress {
            timesteps: self.timesteps,
            total: self.config.timesteps,
            timesteps_per_second: (self.timesteps - self.start_timesteps) as f64 / busy.max(1e-9),
            ep_rew_mean: mean(self.episodes.iter().map(|e| e.0)),
            ep_success_rate: mean(self.episodes.iter().map(|e| f64::from(u8::from(e.2)))),
            update: *stats,
            rollout_seconds,
            update_seconds,
        };
        let mut scalars = vec![
            ("train/entropy_loss", stats.entropy_loss),
            ("train/policy_gradient_loss", stats.policy_gradient_loss),
            ("train/value_loss", stats.value_loss),
            ("train/approx_kl", stats.approx_kl),
            ("train/clip_fraction", stats.clip_fraction),
            ("train/loss", stats.loss),
            ("train/explained_variance", stats.explained_variance),
            ("train/std", stats.std),
            ("train/clip_range", f64::from(settings.loss.clip_range)),
            ("train/learning_rate", settings.learning_rate),
            ("time/fps", progress.timesteps_per_second),
            ("time/rollout_seconds", rollout_seconds),
            ("time/update_seconds", update_seconds),
            ("time/rss_mib", rss),
        ];
        for part in &self.parts {
            part.log(settings, stats, &mut scalars);
        }
        if let Some(r) = progress.ep_rew_mean {
            scalars.push(("rollout/ep_rew_mean", r));
            scalars.push((
                "rollout/ep_len_mean",
                mean(self.episodes.iter().map(|e| e.1 as f64)).unwrap_or(0.0),
            ));
            scalars.push((
                "rollout/success_rate",
                progress.ep_success_rate.unwrap_or(0.0),
            ));
        }
        self.log(&scalars)?;
        observer.on_update(&progress);
        Ok(())
    }
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
    (count > 0).then(|| sum / count as f64)
}
