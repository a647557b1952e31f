//! Configuration of [`SnakeEnv`](super::SnakeEnv): the snake, the task and the observation.

use serde::{Deserialize, Serialize};

use super::reward::RewardConfig;
use crate::config::{Preset, SnakeConfig};
use crate::error::{invalid, Result};

/// Everything that defines a [`SnakeEnv`](super::SnakeEnv); the defaults are the paper's env
/// (`Snake-v0` of snakebot-gym) except for the snake's masses, which follow the paper's text (see
/// [`EnvConfig::snake`]).
///
/// Serialised configurations reject unknown fields; missing fields take their defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvConfig {
    /// The robot. Default: [`SnakeConfig::default`], the `paper` preset with 5 joints (every cube
    /// 0.06 kg). The paper's published env uses the `snakebot-gym` masses (links 1.0 kg): use
    /// [`EnvConfig::snakebot_gym`] or set `base_mass`/`link_mass`. A partial `snake` table in a
    /// serialised config takes its missing fields from the `paper` preset.
    pub snake: SnakeConfig,
    /// Goal position (x, y) on the plane, metres ((0, -10)).
    pub goal: (f64, f64),
    /// The episode terminates (successfully) when the distance to the goal is below this (1.0 m).
    pub goal_radius: f64,
    /// Env steps after which an episode is truncated (5000, gym's `TimeLimit` of `Snake-v0`).
    pub max_episode_steps: u64,
    /// Physics steps of [`SnakeConfig::dt`] per env step, with the same targets (1).
    pub physics_steps_per_env_step: u32,
    /// Distribution of the start pose drawn at each reset.
    pub start: StartDistribution,
    /// Joint targets are `clip(action, -1, 1) * action_scale` radians (1.0).
    pub action_scale: f64,
    /// What the observation holds.
    pub observation: ObservationLayout,
    /// Optional reward terms and the success reward.
    pub reward: RewardConfig,
}

impl Default for EnvConfig {
    fn default() -> Self {
        EnvConfig {
            snake: SnakeConfig::default(),
            goal: (0.0, -10.0),
            goal_radius: 1.0,
            max_episode_steps: 5000,
            physics_steps_per_env_step: 1,
            start: StartDistribution::default(),
            action_scale: 1.0,
            observation: ObservationLayout::Paper,
            reward: RewardConfig::default(),
        }
    }
}

/// Uniform distribution of the start pose: base at (x, y, z) with heading `yaw`.
///
/// Each of x, y and yaw is `low + (high - low) * u` with `u` uniform in [0, 1), as numpy's `uniform`
/// computes it, drawn in the order x, y, yaw. `low == high` fixes a value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StartDistribution {
    /// Range of the base's x, metres ([-0.5, 0.5]).
    pub x: [f64; 2],
    /// Range of the base's y, metres ([-0.5, 0.5]).
    pub y: [f64; 2],
    /// Height of the base centre, metres (0.5: the snake drops 0.25 m onto the plane).
    pub z: f64,
    /// Range of the heading about z, radians ([-0.2, 0.2]).
    pub yaw: [f64; 2],
}

impl Default for StartDistribution {
    fn default() -> Self {
        StartDistribution {
            x: [-0.5, 0.5],
            y: [-0.5, 0.5],
            z: 0.5,
            yaw: [-0.2, 0.2],
        }
    }
}

impl StartDistribution {
    /// Every draw yields exactly `pose`.
    pub fn fixed(pose: crate::StartPose) -> Self {
        StartDistribution {
            x: [pose.x, pose.x],
            y: [pose.y, pose.y],
            z: pose.z,
            yaw: [pose.yaw, pose.yaw],
        }
    }

    /// Checks that the ranges are finite and ordered; the error names the field.
    pub fn validate(&self) -> Result<()> {
        for (name, [low, high]) in [
            ("start.x", self.x),
            ("start.y", self.y),
            ("start.yaw", self.yaw),
        ] {
            if !(low.is_finite() && high.is_finite()) {
                return Err(invalid(format!(
                    "{name} must be finite, got [{low}, {high}]"
                )));
            }
            if low > high {
                return Err(invalid(format!(
                    "{name} must have low <= high, got [{low}, {high}]"
                )));
            }
        }
        if !self.z.is_finite() {
            return Err(invalid(format!("start.z must be finite, got {}", self.z)));
        }
        Ok(())
    }
}

/// The layout of the observation vector (`float32`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObservationLayout {
    /// The paper's `2 + 2N` values: base x, base y, then for each joint its (angle, velocity) pair.
    #[default]
    Paper,
    /// The paper's layout followed by 6 values: the goal vector in the head frame (2), sin and cos of
    /// the heading (2) and the base's planar velocity in the head frame (2); `2 + 2N + 6` in all.
    Extended,
}

impl ObservationLayout {
    /// Length of the observation for a snake of `joints` joints.
    pub fn dim(self, joints: usize) -> usize {
        match self {
            ObservationLayout::Paper => 2 + 2 * joints,
            ObservationLayout::Extended => 2 + 2 * joints + 6,
        }
    }

    /// The configuration name (`paper` or `extended`).
    pub fn name(self) -> &'static str {
        match self {
            ObservationLayout::Paper => "paper",
            ObservationLayout::Extended => "extended",
        }
    }
}

impl std::str::FromStr for ObservationLayout {
    type Err = crate::Error;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "paper" => Ok(ObservationLayout::Paper),
            "extended" => Ok(ObservationLayout::Extended),
            other => Err(invalid(format!(
                "unknown observation layout '{other}' (expected one of: paper, extended)"
            ))),
        }
    }
}

impl EnvConfig {
    /// The paper's env with a `preset` snake of `joints` joints.
    pub fn with_preset(preset: Preset, joints: usize) -> Self {
        EnvConfig {
            snake: preset.config(joints),
            ..EnvConfig::default()
        }
    }

    /// Exactly the paper's published env (`Snake-v0`, snakebot-gym): base 0.06 kg, links 1.0 kg.
    pub fn snakebot_gym(joints: usize) -> Self {
        EnvConfig::with_preset(Preset::SnakebotGym, joints)
    }

    /// Number of joints (the action length).
    pub fn joints(&self) -> usize {
        self.snake.joints
    }

    /// Length of the observation vector.
    pub fn observation_dim(&self) -> usize {
        self.observation.dim(self.snake.joints)
    }

    /// Checks every field; the one-line error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        self.snake.validate().map_err(|e| match e {
            crate::Error::InvalidArgument(m) => invalid(format!("snake.{m}")),
            other => other,
        })?;
        if !(self.goal.0.is_finite() && self.goal.1.is_finite()) {
            return Err(invalid(format!("goal must be finite, got {:?}", self.goal)));
        }
        if !(self.goal_radius.is_finite() && self.goal_radius >= 0.0) {
            return Err(invalid(format!(
                "goal_radius must be finite and >= 0, got {}",
                self.goal_radius
            )));
        }
        if self.max_episode_steps < 1 {
            return Err(invalid("max_episode_steps must be at least 1, got 0"));
        }
        if self.physics_steps_per_env_step < 1 {
            return Err(invalid(
                "physics_steps_per_env_step must be at least 1, got 0",
            ));
        }
        self.start.validate()?;
        if !(self.action_scale.is_finite() && self.action_scale > 0.0) {
            return Err(invalid(format!(
                "action_scale must be positive and finite, got {}",
                self.action_scale
            )));
        }
        let r = &self.reward;
        for (name, w) in [
            ("reward.progress_weight", r.progress_weight),
            ("reward.smoothness_weight", r.smoothness_weight),
            ("reward.energy_weight", r.energy_weight),
            ("reward.success_reward", r.success_reward),
        ] {
            if !w.is_finite() {
                return Err(invalid(format!("{name} must be finite, got {w}")));
            }
        }
        Ok(())
    }
}
