//! Evaluation episodes: the protocol of `snakesim evaluate` and of SB3's `evaluate_policy`, the one
//! implementation behind the native trainer's evaluations, `snakesim evaluate`, the SB3 trainer's
//! evaluations and the sweeps (Python calls [`run_episodes_with`] and [`summarize`] through `_core`).
//!
//! Up to 16 envs run at once, env `i` seeded with `seed + i` (its later episodes continue its random
//! stream), and env `i` contributes `(episodes + i) / m` episodes, so a seed fixes the episodes'
//! starts whatever the policy does.

use std::sync::Arc;

use rand::SeedableRng;
use rand_chacha::ChaCha12Rng;
use snake_core::{EnvConfig, Physics, StepBuffers, VecSnakeEnv};

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
    /// Length of the head's path in the plane, metres.
    pub path_length: f64,
    /// Mechanical work of the motors, joules.
    pub work: f64,
    /// The snake's weight m g, newtons.
    pub weight: f64,
    /// The physics the episode's reset drew ([`EnvConfig::randomize`]; empty without it), so that an
    /// evaluation under a distribution can say which draws cost its failures.
    pub physics: Physics,
}

impl Episode {
    /// Mean speed, m/s: straight-line displacement over the episode's time.
    pub fn speed(&self) -> f64 {
        if self.seconds > 0.0 {
            self.distance / self.seconds
        } else {
            0.0
        }
    }

    /// Straight-line displacement / path length (1: a straight line); None without a path.
    pub fn path_efficiency(&self) -> Option<f64> {
        (self.path_length > 0.0).then(|| self.distance / self.path_length)
    }

    /// Mechanical energy / (m g displacement), dimensionless; None without displacement.
    pub fn cost_of_transport(&self) -> Option<f64> {
        (self.distance > 0.0 && self.weight > 0.0)
            .then(|| self.work / (self.weight * self.distance))
    }
}

/// The Wilson score interval of `successes` out of `n` at `z` standard deviations (1.959964: 95 %).
pub fn wilson_interval(successes: usize, n: usize, z: f64) -> (f64, f64) {
    let (k, n) = (successes as f64, n as f64);
    let p = k / n;
    let centre = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let half = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    ((centre - half).max(0.0), (centre + half).min(1.0))
}

/// The summary of an evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Episodes run.
    pub episodes: usize,
    /// Fraction that reached the goal.
    pub success_rate: f64,
    /// The success rate's 95 % Wilson interval.
    pub success_rate_ci95: (f64, f64),
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
    /// Mean path efficiency of the episodes that have one.
    pub mean_path_efficiency: Option<f64>,
    /// Mean cost of transport of the episodes that have one.
    pub mean_cost_of_transport: Option<f64>,
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
    let present = |values: Vec<f64>| {
        (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
    };
    Summary {
        episodes: episodes.len(),
        success_rate: wins.len() as f64 / n,
        success_rate_ci95: wilson_interval(wins.len(), episodes.len(), 1.959964),
        mean_return,
        std_return,
        mean_steps_to_goal: (!wins.is_empty()).then(|| mean(&|e| e.steps as f64, &wins)),
        mean_seconds_to_goal: (!wins.is_empty()).then(|| mean(&|e| e.seconds, &wins)),
        mean_speed: mean(&|e| e.speed(), &all),
        mean_path_efficiency: present(
            episodes
                .iter()
                .filter_map(Episode::path_efficiency)
                .collect(),
        ),
        mean_cost_of_transport: present(
            episodes
                .iter()
                .filter_map(Episode::cost_of_transport)
                .collect(),
        ),
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
    /// The actor failed (e.g. a Python policy raised); the message says why.
    #[error("{0}")]
    Actor(String),
}

/// What acts in an evaluation: given the observations of `m` envs (row-major, `m x obs_dim`), writes
/// their actions (`m x action_dim`; `A` is f64 for the native policy (its env actions) and for Python's actors, whose
/// actions the env takes as they are).
pub type Actor<'a, A> = dyn FnMut(&[f32], usize, &mut [A]) -> Result<(), EvalError> + 'a;

/// Told that env `i`'s episode ended (the env has already reset: its next observation starts a new
/// episode), so that an actor with a state per env, a controller's clock, restarts it.
pub type Restart<'a> = dyn FnMut(usize) -> Result<(), EvalError> + 'a;

/// Runs `episodes` episodes of `policy` (deterministic or sampled) in `config`'s env, stepping the
/// envs on `pool` (one after the other without one); `stop` is asked between steps. A sampling policy
/// draws from a generator seeded with `seed`.
pub fn run_episodes(
    policy: &mut Policy,
    config: &EnvConfig,
    episodes: usize,
    seed: u64,
    deterministic: bool,
    pool: Option<&Arc<rayon::ThreadPool>>,
    stop: &mut dyn FnMut() -> bool,
) -> Result<Vec<Episode>, EvalError> {
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    // float64: the actions the env is given, the policy's own (float32 values) or its assist's.
    let mut act = |obs: &[f32], m: usize, actions: &mut [f64]| {
        policy.env_actions(obs, m, deterministic, &mut rng, actions);
        Ok(())
    };
    run_episodes_with(
        &mut act,
        &mut |_| Ok(()),
        config,
        episodes,
        seed,
        pool,
        stop,
    )
}

/// How many of `episodes` episodes each env of an evaluation runs: `min(episodes, MAX_EVAL_ENVS)`
/// envs, env `i` running `(episodes + i) / m` (an env's episodes beyond its count end uncounted).
pub fn episode_targets(episodes: usize) -> Vec<usize> {
    let m = episodes.min(MAX_EVAL_ENVS);
    (0..m).map(|i| (episodes + i) / m).collect()
}

/// The evaluation protocol for any actor: up to [`MAX_EVAL_ENVS`] envs, env `i` seeded with
/// `seed + i`, env `i` contributing `(episodes + i) / m` episodes, each measured as [`Episode`]
/// says. `episodes` must be at least 1. The episodes come back in their own order (env 0's in
/// turn, then env 1's, ...), not in the order they end, so that the i-th episode of two policies'
/// runs is the same episode (`experiments/ground-or-controller/win_overlap.py` compares them so).
/// `restart` hears of every episode's end, counted or not.
pub fn run_episodes_with<A: Copy + Default + Into<f64> + Sync>(
    act: &mut Actor<'_, A>,
    restart: &mut Restart<'_>,
    config: &EnvConfig,
    episodes: usize,
    seed: u64,
    pool: Option<&Arc<rayon::ThreadPool>>,
    stop: &mut dyn FnMut() -> bool,
) -> Result<Vec<Episode>, EvalError> {
    assert!(episodes >= 1, "an evaluation needs an episode");
    let targets = episode_targets(episodes);
    let m = targets.len();
    let mut counts = vec![0usize; m];
    let n = config.action_dim();
    let mut envs = VecSnakeEnv::new(config.clone(), m)?;
    envs = match pool {
        Some(pool) => envs.with_pool(pool.clone()),
        None => envs.with_threads(1)?,
    };
    let mut out = StepBuffers::for_envs(&envs);
    envs.reset(Some(seed), &mut out.obs)?;
    // The physics of each env's running episode (an env draws its next episode's when it resets).
    let mut physics: Vec<Physics> = envs.envs().map(|e| *e.physics()).collect();
    let mut ended = Vec::with_capacity(m);
    let step_seconds = config.snake.dt * f64::from(config.physics_steps_per_env_step);
    let mut actions = vec![A::default(); m * n];
    // The body's weight m g, for the cost of transport (the robot's links' masses for a robot).
    let weight = config.body_mass() * config.snake.gravity.abs();
    // Each episode keyed by its env and its number there: its identity whatever the policy.
    let mut done = Vec::with_capacity(episodes);
    while counts != targets {
        if stop() {
            return Err(EvalError::Interrupted);
        }
        act(&out.obs, m, &mut actions)?;
        let finals = envs.step_into(&actions, &mut out)?;
        ended.clear();
        for f in finals.iter() {
            ended.push(f.env);
            restart(f.env)?;
            if counts[f.env] >= targets[f.env] {
                continue;
            }
            let info = f.info;
            // As snakesim's Python evaluation computes it: float32 differences (numpy 2), CPython's hypot.
            let (dx, dy) = (
                f64::from(f.observation[0] - info.start.x as f32),
                f64::from(f.observation[1] - info.start.y as f32),
            );
            let key = (f.env, counts[f.env]);
            done.push((
                key,
                Episode {
                    ret: info.episode_return,
                    steps: info.episode_step,
                    success: info.success,
                    seconds: info.episode_step as f64 * step_seconds,
                    distance: snake_core::env::python_hypot(dx, dy),
                    path_length: info.path_length,
                    work: info.work,
                    weight,
                    physics: physics[f.env],
                },
            ));
            counts[f.env] += 1;
        }
        for (i, env) in envs.envs().enumerate() {
            if ended.contains(&i) {
                physics[i] = *env.physics();
            }
        }
    }
    // Episodes end in an order that depends on the policy; returned in the episodes' own order (env
    // 0's first, second, ..., then env 1's), so that two policies' i-th episodes are the same one.
    done.sort_by_key(|(key, _)| *key);
    Ok(done.into_iter().map(|(_, e)| e).collect())
}
