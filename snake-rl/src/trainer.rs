//! The training loop: SB3's `OnPolicyAlgorithm.learn` for PPO, with the run directory around it.
//!
//! Each iteration collects `n_steps` steps of every env (actions sampled from the policy, clipped
//! to [-1, 1] for the env, stored unclipped; a truncated episode's last reward gains `gamma` times
//! the value of its final observation), computes GAE, and runs one PPO update. Evaluations and
//! checkpoints follow the first update at or past each multiple of their frequency, so that the row
//! or checkpoint labelled T holds a policy trained on exactly T timesteps (SB3's callbacks evaluate
//! inside the rollout instead, before its update). Stopping on request saves the state of the last
//! complete update; resuming starts the next rollout there. Everything runs on one thread pool of `threads` threads: the envs step in parallel, and each
//! minibatch's gradient is split across the threads. A seed and a thread count give one run, bit for
//! bit.
//!
//! A run with an `init` table first imitates its controller ([`crate::imitate`]): the fitted policy
//! is evaluated at 0 timesteps, and PPO starts from it. A run stopped during the initialisation
//! starts it over on resume; its checkpoints afterwards hold the fitted policy.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha12Rng;
use serde_json::{json, Map, Value};
use snake_core::controllers::JointsSine;
use snake_core::{AssistedEnv, EnvConfig, StepBuffers, VecSnakeEnv};

use crate::buffer::RolloutBuffer;
use crate::config::{RunConfig, TrainerKind};
use crate::evaluate::{run_episodes, summarize, EvalError};
use crate::imitate;
use crate::lock::WriterLock;
use crate::model::{self, Checkpoint, EnvSpec, SavedPolicy};
use crate::nn::{init_params, ActorCritic, Workspace};
use crate::normalize::Normalizer;
use crate::policy::Policy;
use crate::ppo::{act, Learner, LossScratch, LossSettings, UpdateSettings, UpdateStats};
use crate::rundir::{check_empty, lock_run_dir, EvaluationRow, RunDir, MODEL_FILE};
use crate::tensorboard::EventWriter;

/// Why training stopped with an error. Every message is one line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TrainError {
    /// The configuration or the run directory cannot be used.
    #[error("{0}")]
    Setup(String),
    /// Writing the run's files failed.
    #[error("{0}")]
    Io(String),
    /// An env failed (the simulation blew up or refused a value).
    #[error("env: {0}")]
    Env(#[from] snake_core::Error),
    /// A loss or gradient became NaN or infinite; the last good state was saved.
    #[error("{0}")]
    NonFinite(String),
}

impl From<crate::rundir::RunDirError> for TrainError {
    fn from(e: crate::rundir::RunDirError) -> Self {
        TrainError::Io(e.0)
    }
}

/// How a training session ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// The run reached its timesteps.
    Finished(Summary),
    /// Stopped on request (Ctrl-C); a checkpoint was saved.
    Interrupted(Summary, PathBuf),
}

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

/// Progress after each update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Timesteps so far.
    pub timesteps: u64,
    /// The run's total.
    pub total: u64,
    /// Timesteps per second of this session, evaluations and the initialisation excluded.
    pub timesteps_per_second: f64,
    /// Mean return of the last 100 training episodes.
    pub ep_rew_mean: Option<f64>,
    /// Success rate of the last 100 training episodes.
    pub ep_success_rate: Option<f64>,
    /// The update's statistics.
    pub update: UpdateStats,
    /// Seconds of the last rollout and update.
    pub rollout_seconds: f64,
    /// See `rollout_seconds`.
    pub update_seconds: f64,
}

/// Progress of a run's `init` (initialisation by imitation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitProgress {
    /// Env steps of the controller so far (all envs).
    pub steps: u64,
    /// Of `init.steps` (rounded up to whole steps of every env).
    pub total_steps: u64,
    /// Epochs of the fit done.
    pub epoch: usize,
    /// Of `init.epochs`.
    pub epochs: usize,
    /// The last epoch's behaviour-cloning loss (mean squared error to the controller's actions).
    pub bc_loss: Option<f64>,
    /// The last epoch's critic loss, when the critic is fitted.
    pub critic_loss: Option<f64>,
}

/// Offset of the seed of the `init` envs' reset from the run's seed, so that the controller's
/// episodes are not PPO's first ones.
pub const INIT_SEED_OFFSET: u64 = 1 << 40;

/// Receives what happens during training; every method has a default that does nothing.
pub trait Observer {
    /// Training starts at `start` of `total` timesteps.
    fn on_start(&mut self, _start: u64, _total: u64) {}
    /// After every env step (of all envs); a cheap place to move a progress bar.
    fn on_step(&mut self, _timesteps: u64) {}
    /// During a run's `init` (initialisation by imitation): after every env step of the controller
    /// and every epoch of the fit.
    fn on_init(&mut self, _progress: &InitProgress) {}
    /// After every update.
    fn on_update(&mut self, _progress: &Progress) {}
    /// After every evaluation.
    fn on_evaluation(&mut self, _row: &EvaluationRow) {}
    /// Something the user should know that is not an error (a skipped checkpoint); one line.
    fn on_note(&mut self, message: &str) {
        eprintln!("note: {message}");
    }
    /// Asked between env steps: true stops training (a checkpoint is saved first).
    fn should_stop(&mut self) -> bool {
        false
    }
}

/// An observer that does nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Observer for Silent {
    fn on_note(&mut self, _message: &str) {}
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

/// The versions a native run records in versions.json (callers add their own, e.g. Python's).
pub fn native_versions() -> Map<String, Value> {
    let mut m = Map::new();
    m.insert("snakesim".into(), json!(env!("CARGO_PKG_VERSION")));
    m.insert("trainer".into(), json!("native"));
    m.insert("snake_rl".into(), json!(env!("CARGO_PKG_VERSION")));
    m.insert(
        "target".into(),
        json!(format!(
            "{}-{}",
            std::env::consts::ARCH,
            std::env::consts::OS
        )),
    );
    m
}

/// How to start: a new run, or resuming one.
#[derive(Debug, Clone)]
pub struct Session {
    /// The configuration (for a resumed run: the saved one with the allowed changes).
    pub config: RunConfig,
    /// The run directory.
    pub run_dir: PathBuf,
    /// Continue the run from its latest checkpoint.
    pub resume: bool,
    /// Versions to record besides [`native_versions`].
    pub versions: Map<String, Value>,
}

/// What a session starts from: the configuration to train with and, when resuming, the checkpoint.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The configuration (for a resumed run: the saved one with the allowed changes), resolved.
    pub config: RunConfig,
    /// The checkpoint a resumed run continues from.
    pub resume: Option<ResumePoint>,
}

/// The newest checkpoint of a run that loads, and the newer ones that did not.
#[derive(Debug, Clone)]
pub struct ResumePoint {
    /// Its timesteps.
    pub timesteps: u64,
    /// Its file.
    pub path: PathBuf,
    /// One line for each newer checkpoint that was skipped: its file and why it cannot be used.
    pub skipped: Vec<String>,
    /// One line for each robot or world file that changed since the checkpoint was written: the run
    /// resumes on the files it records, as a loaded model does (`<checkpoint>: robot R changed since
    /// training (...); the robot recorded in the model is used`).
    pub notes: Vec<String>,
    checkpoint: Checkpoint,
    /// The checkpoint's env keywords hold a record in place of a changed file's path.
    recorded_env: bool,
}

fn check_native(config: &RunConfig) -> Result<(), TrainError> {
    if config.trainer != TrainerKind::Native {
        return Err(TrainError::Setup(format!(
            "trainer {} is not the native trainer (run it with `snakesim train`)",
            config.trainer.name()
        )));
    }
    config.validate().map_err(|e| TrainError::Setup(e.0))
}

/// Takes the run directory's writer lock for a session ([`lock_run_dir`]: one writer per run
/// directory), after checking the configuration, so that a bad one leaves no folder behind.
pub fn lock_run(
    config: &RunConfig,
    run_dir: &Path,
    resume: bool,
) -> Result<WriterLock, TrainError> {
    check_native(config)?;
    lock_run_dir(run_dir, !resume).map_err(|e| TrainError::Setup(e.0))
}

/// Checks a session whose run directory `lock` holds, before anything is written: a new run's
/// directory must be empty; a resumed run must have a checkpoint below its timesteps, and may not
/// change what it learns. A resumed run continues from its newest checkpoint that loads; each newer
/// one that does not is named in [`ResumePoint::skipped`].
pub fn prepare(
    config: &RunConfig,
    lock: &WriterLock,
    resume: bool,
) -> Result<Prepared, TrainError> {
    check_native(config)?;
    let run_dir = lock.folder();
    if !resume {
        check_empty(run_dir).map_err(|e| TrainError::Setup(e.0))?;
        return Ok(Prepared {
            config: config.resolved(),
            resume: None,
        });
    }
    let (dir, saved) = RunDir::open(run_dir).map_err(|e| TrainError::Setup(e.0))?;
    let config = config.resolved();
    if let Some((key, was, now)) = saved.resolved().identity_difference(&config) {
        return Err(TrainError::Setup(format!(
            "cannot change {key} when resuming ({} has {was}, got {now})",
            run_dir.display()
        )));
    }
    let found = dir.checkpoints();
    if found.is_empty() {
        return Err(TrainError::Setup(format!(
            "cannot resume {}: it has no native checkpoints",
            run_dir.display()
        )));
    }
    let mut skipped = Vec::new();
    for (steps, path) in found.into_iter().rev() {
        match model::load_checkpoint_noted(&path) {
            Ok((checkpoint, notes)) if checkpoint.policy.timesteps == steps => {
                if steps >= config.timesteps {
                    return Err(TrainError::Setup(format!(
                        "{} already has {steps} timesteps (>= timesteps {}); pass a larger \
                         --timesteps to train on",
                        run_dir.display(),
                        config.timesteps
                    )));
                }
                return Ok(Prepared {
                    config,
                    resume: Some(ResumePoint {
                        timesteps: steps,
                        path,
                        skipped,
                        recorded_env: !notes.is_empty(),
                        notes: notes.into_iter().map(|n| n.replace('\n', " ")).collect(),
                        checkpoint,
                    }),
                });
            }
            Ok((checkpoint, _)) => skipped.push(format!(
                "skipped a checkpoint: {} holds {} timesteps, not the {steps} its name says",
                path.display(),
                checkpoint.policy.timesteps
            )),
            Err(e) => skipped.push(format!("skipped a checkpoint: {e}")),
        }
    }
    Err(TrainError::Setup(format!(
        "cannot resume {}: none of its checkpoints loads ({})",
        run_dir.display(),
        skipped.join("; ")
    )))
}

/// Trains: the run described by `session`, reporting to `observer`. Holds the run directory's lock
/// for the whole session.
pub fn train(session: &Session, observer: &mut dyn Observer) -> Result<Outcome, TrainError> {
    let lock = lock_run(&session.config, &session.run_dir, session.resume)?;
    let prepared = prepare(&session.config, &lock, session.resume)?;
    train_prepared(session, &lock, prepared, observer)
}

/// Trains a session already locked ([`lock_run`]) and prepared ([`prepare`]).
pub fn train_prepared(
    session: &Session,
    lock: &WriterLock,
    prepared: Prepared,
    observer: &mut dyn Observer,
) -> Result<Outcome, TrainError> {
    if lock.folder() != session.run_dir {
        return Err(TrainError::Setup(format!(
            "the lock held is for {}, not the run directory {}",
            lock.folder().display(),
            session.run_dir.display()
        )));
    }
    let Prepared { config, resume } = prepared;
    let threads = config
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let pool = std::sync::Arc::new(
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("snake-rl-{i}"))
            .build()
            .map_err(|e| TrainError::Setup(format!("cannot start {threads} threads: {e}")))?,
    );
    let mut versions = native_versions();
    versions.extend(session.versions.clone());
    let (dir, checkpoint) = if let Some(point) = resume {
        for line in point.skipped.iter().chain(&point.notes) {
            observer.on_note(line);
        }
        let (dir, _) = RunDir::open(&session.run_dir).map_err(|e| TrainError::Setup(e.0))?;
        dir.keep_evaluations_up_to(point.timesteps)?;
        dir.note_resume_versions(point.timesteps, &versions)?;
        // A file changed since the checkpoint: the run goes on with the robot and world it trained
        // on (the checkpoint's env keywords, the record in place of that path).
        let env = point
            .recorded_env
            .then(|| point.checkpoint.policy.env.env.clone());
        (dir, Some((point.checkpoint, env)))
    } else {
        (RunDir::create(lock, &config, &versions)?, None)
    };
    let mut run = Run::new(config, dir, threads, checkpoint)?;
    // The loop itself stays on the caller's thread (a Python caller checks for Ctrl-C there; only the
    // main thread can), the envs and the updates use the pool.
    run.learn(&pool, observer)
}

/// The state of one training session.
struct Run {
    config: RunConfig,
    env_config: EnvConfig,
    /// The env keywords `env_config` was built from.
    env: Map<String, Value>,
    /// The texts of its robot and world files as this session read them ([`model::env_files`]).
    env_files: Option<Value>,
    /// The run's `steer_assist`, bound to its env: between the policy and the envs.
    assist: Option<AssistedEnv>,
    dir: RunDir,
    threads: usize,
    learner: Learner,
    normalizer: Option<Normalizer>,
    rng: ChaCha12Rng,
    timesteps: u64,
    start_timesteps: u64,
    n_updates: u64,
    wall_offset: f64,
    started: Instant,
    eval_seconds: f64,
    rollout_seconds: f64,
    update_seconds: f64,
    tb: EventWriter,
    episodes: std::collections::VecDeque<(f64, u64, bool)>,
    last_evaluation: Option<EvaluationRow>,
    /// RSS after this session's first update (see [`Summary::rss_mib`]).
    rss_first_update: Option<f64>,
    /// The training envs' energy weight in the last rollout, when `energy_ramp` anneals it.
    ramped_energy_weight: Option<f64>,
    /// The run's `init` is still to be done (a new run with one, or one stopped during it).
    init_pending: bool,
    /// Seconds of this session's `init` (its evaluation excluded).
    init_seconds: f64,
    /// With `init.anchor`, once the init is done: the fitted policy (also the checkpoint at 0
    /// timesteps, from which a resumed run reads it).
    anchor: Option<SavedPolicy>,
}

impl Run {
    fn new(
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
        let assist = match config.steer_assist {
            None => None,
            Some(a) => Some(
                a.bind(&env_config)
                    .map_err(|e| TrainError::Setup(e.message()))?,
            ),
        };
        let (obs_dim, act_dim) = (env_config.observation_dim(), env_config.action_dim());
        let net = ActorCritic::new(config.arch.clone(), obs_dim, act_dim);
        let tb = EventWriter::create(&dir.tensorboard_dir()).map_err(|e| {
            TrainError::Io(format!(
                "cannot write TensorBoard logs in {}: {e}",
                dir.path().display()
            ))
        })?;
        // A checkpoint written during the initialisation holds nothing to keep but its time: the
        // run starts over, initialisation included.
        let (checkpoint, restart_wall) = match checkpoint {
            Some(c) if c.init_pending => (None, c.wall_time),
            other => (other, 0.0),
        };
        let init_pending = config.init.is_some() && checkpoint.is_none();
        let anchored = config.init.as_ref().is_some_and(|i| i.anchor.is_some());
        let anchor = if anchored && !init_pending {
            let path = dir.checkpoint_path(0);
            let policy = model::load_policy(&path).map_err(|e| {
                TrainError::Setup(format!(
                    "init.anchor: the run resumes after its init, whose fitted policy it anchors to: {e}"
                ))
            })?;
            Some(policy)
        } else {
            None
        };
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
            assist,
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
            tb,
            episodes: std::collections::VecDeque::with_capacity(100),
            last_evaluation: None,
            rss_first_update: None,
            ramped_energy_weight: None,
            init_pending,
            init_seconds: 0.0,
            anchor,
            config,
        })
    }

    fn wall_time(&self) -> f64 {
        self.wall_offset + self.started.elapsed().as_secs_f64()
    }

    fn saved_policy(&self) -> SavedPolicy {
        SavedPolicy {
            net: self.learner.net().clone(),
            params: self.learner.params.clone(),
            obs_rms: self.normalizer.as_ref().map(|n| n.obs_rms.clone()),
            env: EnvSpec {
                joints: self.config.joints,
                preset: self.config.preset,
                env: self.recorded_env(),
            },
            steer_assist: self.config.steer_assist,
            timesteps: self.timesteps,
        }
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

    fn save_checkpoint(&self, reason: &str) -> Result<PathBuf, TrainError> {
        let path = self.dir.checkpoint_path(self.timesteps);
        let c = Checkpoint {
            policy: self.saved_policy(),
            adam: self.learner.adam.clone(),
            normalizer: self.normalizer.clone(),
            rng: self.rng.clone(),
            n_updates: self.n_updates,
            wall_time: self.wall_time(),
            reason: reason.into(),
            init_pending: self.init_pending,
        };
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

    fn log(&mut self, values: &[(&str, f64)]) -> Result<(), TrainError> {
        self.log_at(self.timesteps, values)
    }

    fn log_at(&mut self, step: u64, values: &[(&str, f64)]) -> Result<(), TrainError> {
        self.tb
            .scalars(step, values)
            .and_then(|()| self.tb.flush())
            .map_err(|e| TrainError::Io(format!("cannot write TensorBoard logs: {e}")))
    }

    /// Evaluates the current policy on the run's threads; false when interrupted.
    fn evaluate(
        &mut self,
        pool: &Arc<rayon::ThreadPool>,
        observer: &mut dyn Observer,
    ) -> Result<bool, TrainError> {
        let start = Instant::now();
        let mut policy = Policy::new(
            self.learner.net().clone(),
            self.learner.params.clone(),
            self.normalizer.as_ref().map(|n| n.obs_rms.clone()),
        )
        .with_assist(self.assist);
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

    fn summary(&self) -> Summary {
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

    fn interrupted(&mut self, trained: u64) -> Result<Outcome, TrainError> {
        // The partial rollout is dropped: the saved state is that of the last complete update.
        self.timesteps = trained;
        let path = self.save_checkpoint("interrupt")?;
        self.save_final()?;
        Ok(Outcome::Interrupted(self.summary(), path))
    }

    /// SB3's `learn`: collect a rollout, update, log; evaluate and checkpoint after the update that
    /// crosses each multiple of their frequency.
    fn learn(
        &mut self,
        pool: &std::sync::Arc<rayon::ThreadPool>,
        observer: &mut dyn Observer,
    ) -> Result<Outcome, TrainError> {
        let c = self.config.clone();
        if self.init_pending && !self.initialise(pool, observer)? {
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
            if c.energy_ramp.is_some() {
                let configured = self.env_config.reward;
                let weight = c.energy_weight_at(trained, configured.energy_weight);
                rollout.envs.set_reward(snake_core::RewardConfig {
                    energy_weight: weight,
                    ..configured
                })?;
                self.ramped_energy_weight = Some(weight);
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

    /// The run's `init`: drives the envs with the controller, fits the policy to it (the critic too
    /// with `init.critic`), sets the action noise, then evaluates the fitted policy (the row at 0
    /// timesteps). False when stopping was asked for (the initialisation is then done again on
    /// resume). Its time is the run's.
    fn initialise(
        &mut self,
        pool: &Arc<rayon::ThreadPool>,
        observer: &mut dyn Observer,
    ) -> Result<bool, TrainError> {
        let init = self.config.init.clone().expect("a run with an init table");
        let start = Instant::now();
        let m = self.config.n_envs;
        let mut controller = JointsSine::new(init.imitate, &self.env_config, m)
            .map_err(|e| TrainError::Setup(format!("init.imitate: {}", e.message())))?;
        let mut envs = VecSnakeEnv::new(self.env_config.clone(), m)?;
        envs = if self.threads == 1 {
            envs.with_threads(1)?
        } else {
            envs.with_pool(pool.clone())
        };
        let mut out = StepBuffers::for_envs(&envs);
        let seed = self.config.seed.wrapping_add(INIT_SEED_OFFSET);
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
            self.config.ppo.gamma,
            self.normalizer.as_mut(),
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
        let net = self.learner.net().clone();
        let mut params = self.learner.params.clone();
        let initial_loss = imitate::bc_loss(&net, &params, &data);
        scalars.push(("init/bc_loss", initial_loss));
        self.log_at(0, &scalars)?;
        let tb = &mut self.tb;
        let mut log_error = None;
        let losses = imitate::fit(&net, &mut params, &data, &init, &mut self.rng, &mut |e| {
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
        self.learner.params.copy_from_slice(&params);
        self.init_pending = false;
        if init.anchor.is_some() {
            self.anchor = Some(self.saved_policy());
        }
        let seconds = start.elapsed().as_secs_f64();
        self.init_seconds = seconds;
        self.log_at(init.epochs as u64, &[("init/seconds", seconds)])?;
        let last = losses.last().map_or(initial_loss, |l| l.bc_loss);
        observer.on_note(&format!(
            "init: imitated {} for {} env steps (its episodes: mean return {}, success {}), \
             fitted in {} epochs (mse {initial_loss:.4} -> {last:.4}), {seconds:.1} s",
            init.imitate.name(),
            total_steps,
            data.mean_return()
                .map_or("n/a".into(), |r| format!("{r:.1}")),
            data.success_rate()
                .map_or("n/a".into(), |r| format!("{r:.2}")),
            init.epochs,
        ));
        if self.config.eval_freq > 0 && !self.evaluate(pool, observer)? {
            return Ok(false);
        }
        // The fitted policy alone, before any PPO update, as the checkpoint at 0 timesteps: it is
        // evaluated like any model (an experiment's "initialised policy alone"), and a run stopped
        // in its first rollout resumes from it without redoing the init.
        self.save_checkpoint("init")?;
        Ok(true)
    }

    /// The envs (on the pool, or one after the other for one thread), reset with a seed that sets a
    /// resumed run's episodes apart from the ones seen before (as SB3 resumes), and the buffers.
    fn start_rollouts(
        &mut self,
        pool: &std::sync::Arc<rayon::ThreadPool>,
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
        let anchor = match (&self.anchor, c.init.as_ref().and_then(|i| i.anchor)) {
            (Some(policy), Some(_)) => {
                buffer = buffer.with_anchors();
                Some(Anchor {
                    ws: policy.net.workspace(m),
                    obs: vec![0.0; m * d],
                    policy: policy.clone(),
                })
            }
            _ => None,
        };
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
            env_actions: vec![0.0; if self.assist.is_some() { m * n } else { 0 }],
            values: vec![0.0; m],
            log_probs: vec![0.0; m],
            rewards: vec![0.0; m],
            dones: vec![false; m],
            terminal: vec![0.0; d],
            anchor,
        })
    }

    /// SB3's `collect_rollouts`: `n_steps` steps of every env into the buffer (actions sampled from
    /// the policy, clipped to [-1, 1] for the env, stored unclipped; a truncated episode's last reward
    /// gains `gamma` times the value of its final observation), then the returns and advantages
    /// (GAE). False when stopping was asked for (nothing of this rollout is used).
    fn collect_rollout(
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
            if let Some(anchor) = &mut r.anchor {
                // The fitted policy's action means in these states, from the envs' raw
                // observations normalised with its own statistics (as its model file acts).
                anchor.obs.copy_from_slice(&r.out.obs);
                if let Some(rms) = &anchor.policy.obs_rms {
                    rms.normalize(&mut anchor.obs);
                }
                let p = &anchor.policy;
                p.net.forward(&p.params, &anchor.obs, m, &mut anchor.ws);
                r.buffer.set_anchors(&anchor.ws.mean[..m * p.net.act_dim()]);
            }
            let finals = match &self.assist {
                None => r.envs.step_into(&r.clipped, &mut r.out)?,
                Some(assist) => {
                    // The observations the actions answer are the envs' raw ones, still in `out`.
                    assist.apply(&r.out.obs, &r.clipped, m, &mut r.env_actions);
                    r.envs.step_into(&r.env_actions, &mut r.out)?
                }
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

    /// The update's settings at the current progress (schedules of the learning rate and clip range).
    fn update_settings(&self) -> UpdateSettings {
        let (c, ppo) = (&self.config, &self.config.ppo);
        let progress_remaining = 1.0 - self.timesteps as f64 / c.timesteps as f64;
        UpdateSettings {
            n_epochs: ppo.n_epochs,
            batch_size: ppo.batch_size,
            loss: LossSettings {
                clip_range: ppo.clip_range.at(progress_remaining) as f32,
                clip_range_vf: ppo.clip_range_vf.map(|v| v as f32),
                ent_coef: ppo.ent_coef as f32,
                vf_coef: ppo.vf_coef as f32,
                normalize_advantage: ppo.normalize_advantage,
                anchor_weight: c
                    .init
                    .as_ref()
                    .and_then(|i| i.anchor)
                    .map_or(0.0, |a| a.at(progress_remaining) as f32),
            },
            max_grad_norm: ppo.max_grad_norm,
            target_kl: ppo.target_kl,
            learning_rate: ppo.learning_rate.at(progress_remaining),
        }
    }

    /// SB3's `train`: the PPO update over the rollout. A loss or gradient that turns non-finite
    /// restores the state before the update, saves it, and stops training.
    fn update(
        &mut self,
        buffer: &RolloutBuffer,
        settings: &UpdateSettings,
        pool: &std::sync::Arc<rayon::ThreadPool>,
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

    /// After an update: the time split, memory, and SB3's `train/*`, `rollout/*` and `time/*`
    /// scalars to TensorBoard and the observer.
    fn log_update(
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
        if let Some(w) = self.ramped_energy_weight {
            scalars.push(("train/energy_weight", w));
        }
        if self
            .config
            .init
            .as_ref()
            .is_some_and(|i| i.anchor.is_some())
        {
            scalars.push((
                "train/anchor_weight",
                f64::from(settings.loss.anchor_weight),
            ));
            scalars.push(("train/anchor_loss", stats.anchor_loss));
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

/// What collecting rollouts uses besides the run's state, allocated once: the envs, the rollout
/// buffer, the network's workspace, and the buffers of one step.
struct Rollout {
    envs: VecSnakeEnv,
    buffer: RolloutBuffer,
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
    /// With a `steer_assist`, the envs' actions (the assist's composition of `clipped`).
    env_actions: Vec<f64>,
    values: Vec<f32>,
    log_probs: Vec<f32>,
    /// The rewards as stored (float32, normalised with `normalize`, bootstrapped on truncation).
    rewards: Vec<f32>,
    dones: Vec<bool>,
    /// A truncated episode's final observation.
    terminal: Vec<f32>,
    /// With `init.anchor`: the fitted policy the loss keeps PPO's policy near.
    anchor: Option<Anchor>,
}

/// The policy `init.anchor` holds PPO's near (the fitted policy, frozen), and its scratch.
struct Anchor {
    policy: SavedPolicy,
    ws: Workspace,
    /// The step's observations, normalised with the anchor's statistics.
    obs: Vec<f32>,
}

fn mean(values: impl Iterator<Item = f64>) -> Option<f64> {
    let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
    (count > 0).then(|| sum / count as f64)
}
