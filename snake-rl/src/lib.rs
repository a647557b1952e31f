//! # snake-rl
//!
//! PPO for snakesim in Rust: Stable-Baselines3 2.x's algorithm for a `Box` action space, without
//! Python in the training loop.
#![deny(missing_docs)]

pub mod bench;
pub mod buffer;
pub mod config;
pub mod evaluate;
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
