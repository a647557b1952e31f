//! The networks' math: dense layers, tanh, the actor-critic networks, their initialisation.

pub mod activation;
pub mod dense;
pub mod init;
pub mod network;

pub use dense::Dense;
pub use init::init_params;
pub use network::{ActorCritic, Arch, NetArch, Role, Tensor, Workspace, MAX_LAYERS, MAX_WIDTH};
