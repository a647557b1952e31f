//! Throughput measurements for benchmarks: the batched env's own speed, the ceiling a trainer
//! approaches (its learning overhead is what it adds: policy inference and updates).

use std::sync::Arc;
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use snake_core::{EnvConfig, StepBuffers, VecSnakeEnv};

use crate::config::limits;

/// Env steps per second of `n_envs` envs of `config` stepped with uniform random actions in
/// [-1, 1], on `threads` threads arranged as the trainer arranges them, for at least `seconds`
/// (whole steps of all envs; episodes reset as in training).
pub fn env_throughput(
    config: &EnvConfig,
    n_envs: usize,
    threads: usize,
    seconds: f64,
    seed: u64,
) -> Result<f64, snake_core::Error> {
    let (max_envs, max_threads) = (limits::MAX_ENVS as usize, limits::MAX_THREADS as usize);
    let seconds_ok = seconds > 0.0 && seconds <= limits::MAX_BENCH_SECONDS;
    if !((1..=max_envs).contains(&n_envs) && (1..=max_threads).contains(&threads) && seconds_ok) {
        return Err(snake_core::Error::InvalidArgument(
            snake_core::Invalid::new(format!(
            "n_envs must be in [1, {max_envs}], threads in [1, {max_threads}], seconds in (0, {}]",
            limits::MAX_BENCH_SECONDS
        )),
        ));
    }
    let mut envs = VecSnakeEnv::new(config.clone(), n_envs)?;
    envs = if threads <= 1 {
        envs.with_threads(1)?
    } else {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| {
                snake_core::Error::InvalidArgument(snake_core::Invalid::new(format!(
                    "cannot start {threads} threads: {e}"
                )))
            })?;
        envs.with_pool(Arc::new(pool))
    };
    let n = config.action_dim();
    let mut out = StepBuffers::for_envs(&envs);
    envs.reset(Some(seed), &mut out.obs)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut actions = vec![0.0f32; n_envs * n];
    let start = Instant::now();
    let mut steps = 0u64;
    while start.elapsed().as_secs_f64() < seconds {
        for a in actions.iter_mut() {
            *a = rng.gen_range(-1.0..=1.0);
        }
        envs.step_into(&actions, &mut out)?;
        steps += n_envs as u64;
    }
    Ok(steps as f64 / start.elapsed().as_secs_f64())
}
