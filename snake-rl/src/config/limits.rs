//! Limits of a run's sizes: each keeps a typo from asking for an impossible run. The env's own
//! limits are [`snake_core::limits`]'s.

/// Most parallel envs of a run (snake-core's batched env's limit).
pub const MAX_ENVS: u64 = snake_core::limits::MAX_ENVS as u64;
/// Most timesteps of a run (10^12: decades at our speed).
pub const MAX_TIMESTEPS: u64 = 1_000_000_000_000;
/// Most episodes of one evaluation.
pub const MAX_EVAL_EPISODES: u64 = 100_000;
/// Most threads (native trainer) or torch threads (SB3 trainer).
pub const MAX_THREADS: u64 = 256;
/// Most memory the rollout buffer may take, bytes.
pub const MAX_ROLLOUT_BYTES: u64 = 4 << 30;
/// Most optimisation epochs per rollout.
pub const MAX_EPOCHS: u64 = 10_000;
/// Largest seed: SB3 and numpy take seeds below 2^32, so both trainers share that range.
pub const MAX_SEED: u64 = u32::MAX as u64;
/// Longest throughput measurement, seconds.
pub const MAX_BENCH_SECONDS: f64 = 3600.0;
/// Most training seeds of one sweep (`snakesim sweep --seeds`).
pub const MAX_SWEEP_SEEDS: u64 = 1000;
/// Most trials of one sweep or search.
pub const MAX_SWEEP_TRIALS: u64 = 10_000;
/// Most values of one `--grid` key or one search choice.
pub const MAX_GRID_VALUES: u64 = 1000;
/// Most retries of a failed trial (`--max-failures`).
pub const MAX_TRIAL_FAILURES: u64 = 100;
/// Most keys of a search space.
pub const MAX_SEARCH_KEYS: u64 = 100;
/// Longest name of a sweep trial's folder, characters (a config name and its grid point).
pub const MAX_TRIAL_NAME: u64 = 100;
/// Most tanh layers of one part of a network (`arch.shared`, `arch.pi`, `arch.vf`).
pub const MAX_NET_LAYERS: u64 = crate::nn::MAX_LAYERS as u64;
/// Widest tanh layer of a network.
pub const MAX_NET_WIDTH: u64 = crate::nn::MAX_WIDTH as u64;
/// Bounds of `log_std_init`: SB3's own bounds of a learnt log standard deviation (SAC's
/// `LOG_STD_MIN`, `LOG_STD_MAX`), beyond which the noise is 0 or swamps the action.
pub const LOG_STD_INIT: [f64; 2] = [-20.0, 2.0];
/// Most env steps of the controller an `init` imitates (`init.steps`): 2^22, a few minutes of
/// stepping on 2 cores.
pub const MAX_INIT_STEPS: u64 = 1 << 22;
/// Most memory the imitation data may take, bytes.
pub const MAX_INIT_BYTES: u64 = 2 << 30;
/// Most minibatch size of the imitation fit (`init.batch_size`).
pub const MAX_INIT_BATCH: u64 = 1 << 16;
/// Largest weight of the anchor to the fitted policy (`init.anchor`). The surrogate's gradient
/// in the action means grows as 1 / std (about 20 at the init's std of 0.05) while the anchor's
/// is its weight times the distance to the fitted policy (hundredths): weights that balance them
/// are in the thousands, and a million leaves PPO nothing to say.
pub const MAX_ANCHOR_WEIGHT: f64 = 1e6;
/// Most joint counts one `snake-cli bench` measures.
pub const MAX_BENCH_SIZES: usize = 16;
/// Most runs per joint count of `snake-cli bench`.
pub const MAX_BENCH_REPEATS: usize = 100;
