//! # snake-rl
//!
//! PPO for snakesim in Rust: Stable-Baselines3 2.x's algorithm for a `Box` action space, with the
//! whole training loop (env steps, policy inference, updates, evaluations) out of Python.
//!
//! - [`config`]: [`config::RunConfig`], the one definition of a training run: defaults (the paper's
//!   Table 1), limits and checks; YAML and `KEY=VALUE` layers; errors that name the key path.
//! - [`nn`]: the paper's networks (PPO-small, PPO-large) over one flat parameter buffer with SB3's
//!   tensor names, hand-written forward and backward passes, SB3's orthogonal initialisation.
//! - [`ppo`]: the loss and its gradient, acting (sampling and deterministic), the update over a
//!   rollout; [`buffer`]: the rollout buffer and GAE; [`optim`]: gradient clipping and Adam;
//!   [`normalize`]: SB3's `VecNormalize`; [`imitate`]: initialisation by imitation of a controller.
//! - [`trainer`]: the training loop and its run directory ([`rundir`]), models and checkpoints
//!   ([`model`], safetensors), TensorBoard scalars ([`tensorboard`]), evaluation ([`evaluate`]).
//!
//! Every piece of the algorithm is pinned to the library it replaces: `tests/ppo_reference.rs` in the
//! workspace compares the loss terms, every parameter gradient and the parameters after the Adam step
//! with SB3's own `PPO.train()` (PyTorch, float32, within 1e-5 of each tensor's largest magnitude),
//! several Adam steps with `torch.optim.Adam(eps=1e-5)`, GAE with SB3's `RolloutBuffer` (bit for bit)
//! and observation/reward normalisation with SB3's `VecNormalize`.
//!
//! ```no_run
//! use snake_rl::config::RunConfig;
//! use snake_rl::trainer::{self, Outcome, Session, Silent};
//!
//! let config = RunConfig::from_yaml("joints: 5\npreset: snakebot-gym\ntimesteps: 2e6")?;
//! let session = Session {
//!     config,
//!     run_dir: "runs/example".into(),
//!     resume: false,
//!     versions: Default::default(),
//! };
//! if let Outcome::Finished(s) = trainer::train(&session, &mut Silent)? {
//!     println!("{:.0} timesteps/s", s.timesteps_per_second());
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Why hand-written networks
//!
//! The paper's networks are tiny (about 10,000 parameters for PPO-small) and PPO updates them in
//! minibatches of 64: at that size an update is per-operation overhead, not arithmetic. The forward
//! and backward passes here are written out layer by layer over ndarray's matrix product (which calls
//! matrixmultiply's AVX2/FMA kernels; about 70 % of this machine's FMA peak at these shapes), with the
//! elementwise loops (tanh, Adam, clipping) compiled for AVX2 at run time ([`simd`]) and no
//! allocation per minibatch. A tensor crate with autograd was measured against it on the same update
//! (`examples/candle_update_bench.rs`, feature `candle-bench`:
//! `cargo run --release -p snake-rl --example candle_update_bench --features candle-bench`): see the
//! figures in the workspace's `docs/experiments.md`. Measured on the 2-core development machine, one
//! thread each, the same update to within float32 rounding: PPO-small's minibatch update takes 108 us
//! here and 793 us in candle 0.9.2 (7.3x; 7.3x for PPO-large, 363 against 2,647 us). With candle, one
//! update of the paper's settings (10,240 minibatches) would take 8.1 s, longer than the rollout that
//! feeds it (4.5 s at 5 joints); per-operation overhead (allocation, the autograd graph, dispatch),
//! not arithmetic, makes the difference at these sizes.
#![deny(missing_docs)]

/// See [`snake_core::error::one_line`].
pub(crate) use snake_core::error::one_line;

pub mod bench;
pub mod buffer;
pub mod config;
pub mod evaluate;
pub mod flags;
pub mod imitate;
pub mod lock;
pub mod model;
pub mod nn;
pub mod normalize;
pub mod optim;
pub mod policy;
pub mod ppo;
pub mod rundir;
pub mod simd;
pub mod tensorboard;
pub mod trainer;
