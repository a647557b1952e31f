//! # snake-core
//!
//! The snake robot of "Simulating Snakes" on the Bullet physics engine, built and stepped so that it
//! moves bit for bit as the pybullet 3.2.7 reference does: a chain of `N + 1` cubes joined by `N`
//! position-controlled revolute joints about z, with anisotropic friction against a ground plane.
//!
//! - [`world`]: a Bullet world with pybullet's settings (bodies, dynamics, joint control, state reads).
//! - [`config`]: [`SnakeConfig`], every physical parameter, and the [`Preset`]s `paper` (every cube
//!   0.06 kg) and `snakebot-gym` (the paper's code: links 1.0 kg).
//! - [`snake`]: [`Snake`], the robot on its ground plane.
//! - [`body`]: [`Body`], the simulated body of a run or an episode: the snake or a URDF robot.
//! - [`gait`]: the [`Gait`] trait, [`LateralUndulation`] (pybullet's snake.py wave) and the gait
//!   library ([`Serpenoid`]: lateral undulation, sidewinding, rolling, linear progression, turning).
//! - [`env`](mod@env): [`SnakeEnv`], the paper's reinforcement-learning environment (Gymnasium-style
//!   `reset`/`step`), configured by [`EnvConfig`].
//! - [`world_file`]: [`WorldSpec`], the ground (plane, slope, heightfield) and static obstacles of a
//!   world file.
//! - [`vec_env`]: [`VecSnakeEnv`], many envs stepped together across threads with automatic resets.
//!
//! ```
//! use snake_core::{Gait, LateralUndulation, Preset, Snake, StartPose};
//!
//! let config = Preset::Paper.config(5);
//! let mut snake = Snake::new(&config, StartPose::resting(config.half_extent))?;
//! let mut gait = LateralUndulation::default();
//! let mut targets = vec![0.0; snake.joints()];
//! for _ in 0..240 {
//!     gait.next_targets(&mut targets);
//!     snake.set_targets(&targets)?;
//!     snake.step()?;
//! }
//! let head = snake.base_state()?.pose.position;
//! assert!(head.y < 0.0, "the snake moves head first, towards -y");
//! # Ok::<(), snake_core::Error>(())
//! ```
#![deny(missing_docs)]

pub mod body;
pub mod config;
pub mod controllers;
pub mod drawing;
pub mod env;
pub mod error;
pub mod files;
pub mod gait;
pub mod imitation;
pub mod keys;
pub mod limits;
pub mod math;
pub mod media;
pub mod recorded;
pub mod robot;
pub mod run_targets;
pub mod skin;
pub mod snake;
pub mod tables;
pub mod urdf;
pub mod vec_env;
pub mod world;
pub mod world_file;

pub use body::Body;
pub use config::{Preset, SnakeConfig};
pub use controllers::{AssistedEnv, ControlledEnv, HandController, SteerAssist};
pub use drawing::ShapeDrawing;
pub use env::keywords::{env_from_keywords, env_keyword_defaults};
pub use env::{
    route_distance, ActionConfig, ActionMode, Capsule, Craters, Disc, DistancePrecision, EnvConfig,
    GoalDistribution, Info, Layout, ObservationLayout, ObservationPart, ObservationStructure,
    PegField, Physics, Randomize, ResetOptions, RewardConfig, RewardTerms, Ridges, RoughGround,
    Segment, SnakeEnv, StartDistribution, StepOutcome, StepResult, Task, TerrainDistribution,
    HEIGHT_MAP_LEN, HEIGHT_MAP_SIDE, HEIGHT_MAP_SPACING, NOISE_STREAM, PHYSICS_STREAM,
};
pub use error::{Error, Invalid, Result};
pub use gait::{
    Gait, GaitChoice, GaitKind, JointRole, JointRoles, LateralUndulation, Serpenoid,
    SerpenoidParams,
};
pub use math::{quaternion_from_euler, StartPose};
pub use recorded::RecordedFiles;
pub use robot::{
    Robot, RobotFile, RobotGait, RobotRef, RobotSpec, RobotWave, Simulation, WaveFile,
    DEFAULT_WAVE_STEERING,
};
pub use skin::{SkinAxis, SkinFriction};
pub use snake::Snake;
pub use urdf::{InertiaSource, UrdfRobot};
pub use vec_env::{FinalStep, FinalSteps, StepBuffers, VecSnakeEnv};
pub use world::{
    BaseState, BodyId, BoxChain, BoxLink, Contact, Dynamics, DynamicsInfo, JointControl,
    JointState, LinkVelocity, Pose, StaticShape, World,
};
pub use world_file::{WorldRef, WorldSpec};
