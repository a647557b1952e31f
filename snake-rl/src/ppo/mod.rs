//! Proximal Policy Optimization as Stable-Baselines3 2.x runs it.

pub mod act;
mod branches;
pub mod loss;
pub mod settings;
pub mod update;

pub use loss::{LossScratch, LossSettings, LossStats, Minibatch};
pub use settings::{NonFinite, UpdateSettings, UpdateStats};
pub use update::Learner;
