//! Evaluation episodes: the protocol of `snakesim evaluate` and of SB3's `evaluate_policy`.
//!
//! Up to 16 envs run at once, env `i` seeded with `seed + i` (its later episodes continue its random
//! stream), and env `i` contributes `(episodes + i) / m` episodes, so a seed fixes the episodes'
//! starts whatever the policy does.

use std::sync::Arc;

use rand::SeedableRng;
use rand_chacha::ChaCha12Rng;
use snake_core::{EnvConfig, StepBuffers, VecSnakeEnv};

use crate::policy::Policy;

/// Most envs of one evaluation.
pub const MAX_EVAL_ENVS: usize = 16;

/// One finished episode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Episode {
    /// The return.
    pub ret: f64,
    /// Env steps.
    pub steps: u64,
    /// It reached the goal (terminated), rather than running out of time.
    pub success: bool,
    /// Simulated seconds.
    pub seconds: f64,
    /// Head displacement from the start to the end, metres.
    pub distance: f64,
}

impl Episode {
    /// Mean speed, m/s.
    pub fn speed(&self) -> f64 {
        if self.seconds > 0.0 {
            self.distance / self.seconds
        } else {
            0.0
        }
    }
}

/// The summary of an evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Episodes run.
    pub episodes: usize,
    /// Fraction that reached the goal.
    pub success_rate: f64,
    /// Mean return.
    pub mean_return: f64,
    /// Population standard deviation of the returns.
    pub std_return: f64,
    /// Mean steps to the goal of the successful episodes.
    pub mean_steps_to_goal: Option<f64>,
    /// Mean simulated seconds to the goal of the successful episodes.
    pub mean_seconds_to_goal: Option<f64>,
    /// Mean speed over all episodes, m/s.
    pub mean_speed: f64,
    /// Mean episode length, steps.
    pub mean_length: f64,
}

/// The summary of `episodes` (at least one).
pub fn summarize(episodes: &[Episode]) -> Summary {
    let n = episodes.len() as f64;
    let mean = |f: &dyn Fn(&Episode) -> f64, of: &[&Episode]| {
        of.iter().map(|e| f(e)).sum::<f64>() / of.len() as f64
    };
    let all: Vec<&Episode> = episodes.iter().collect();
    let wins: Vec<&Episode> = episodes.iter().filter(|e| e.success).collect();
    let mean_return = mean(&|e| e.ret, &all);
    let std_return = (all
        .iter()
        .map(|e| (e.ret - mean_return).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    Summary {
        episodes: episodes.len(),
        success_rate: wins.len() as f64 / n,
        mean_return,
        std_return,
        mean_steps_to_goal: (!wins.is_empty()).then(|| mean(&|e| e.steps as f64, &wins)),
        mean_seconds_to_goal: (!wins.is_empty()).then(|| mean(&|e| e.seconds, &wins)),
        mean_speed: mean(&|e| e.speed(), &all),
        mean_length: mean(&|e| e.steps as f64, &all),
    }
}

/// Why an evaluation stopped early.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    /// The env failed.
    #[error("evaluation env: {0}")]
    Env(#[from] snake_core::Error),
    /// `stop()` asked to stop.
    #[error("evaluation interrupted")]
    Interrupted,
}

/// Runs `episodes` episodes of `policy` (deterministic or sampled) in `config`'s env, stepping the
/// envs on `pool` (one after the other without one); `stop` is asked between steps.
pub fn run_episodes(
    policy: &mut Policy,
    config: &EnvConfig,
    episodes: usize,
    seed: u64,
    deterministic: bool,
    pool: Option<&Arc<rayon::ThreadPool>>,
    stop: &mut dyn FnMut() -> bool,
) -> Result<Vec<Episode>, EvalError> {
    assert!(episodes >= 1, "an evaluation needs an episode");
    let m = episodes.min(MAX_EVAL_ENVS);
    let targets: Vec<usize> = (0..m).map(|i| (episodes + i) / m).collect();
    let mut counts = vec![0usize; m];
    let n = config.action_dim();
    let mut envs = VecSnakeEnv::new(config.clone(), m)?;
    envs = match pool {
        Some(pool) => envs.with_pool(pool.clone()),
        None => envs.with_threads(1)?,
    };
    let mut out = StepBuffers::for_envs(&envs);
    envs.reset(Some(seed), &mut out.obs)?;
    let step_seconds = config.snake.dt * f64::from(config.physics_steps_per_env_step);
    let mut actions = vec![0.0f32; m * n];
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    let mut done = Vec::with_capacity(episodes);
    while counts != targets {
        if stop() {
            return Err(EvalError::Interrupted);
        }
        policy.act(&out.obs, m, deterministic, &mut rng, &mut actions);
        let finals = envs.step_into(&actions, &mut out)?;
        for f in finals.iter() {
            if counts[f.env] >= targets[f.env] {
                continue;
            }
            let info = f.info;
            // As snakesim's Python evaluation computes it: float32 differences (numpy 2), CPython's hypot.
            let (dx, dy) = (
                f64::from(f.observation[0] - info.start.x as f32),
                f64::from(f.observation[1] - info.start.y as f32),
            );
            done.push(Episode {
                ret: info.episode_return,
                steps: info.episode_step,
                success: info.success,
                seconds: info.episode_step as f64 * step_seconds,
                distance: snake_core::env::python_hypot(dx, dy),
            });
            counts[f.env] += 1;
        }
    }
    Ok(done)
}
