//! The hand controllers of the gait-action tasks (`baseline:gait`, `baseline:steer`) and the
//! steering assist that lets `baseline:steer` share an agent's actions, written once.
//!
//! Both sit outside the env: a controller maps an observation to an action, the assist maps an
//! observation and an agent's action to the action the env is given. The env never knows either
//! (it steps whatever gait action it gets); Python reaches them through `snakesim._core`
//! (`snakesim.agents.baselines`, `snakesim.wrappers.SteerAssist`), and snake-rl applies a run's
//! assist between its policy and its envs, records it in the model and applies it again when the
//! model is loaded.

use serde::{Deserialize, Serialize};

use crate::env::{ActionMode, EnvConfig, ObservationPart};
use crate::error::{invalid, invalid_at, Result};

/// With [`SteerAssist::residual`], the agent's steering action's weight in the sum
/// `clip(steer + STEER_RESIDUAL_GAIN * a, -1, 1)`: 2, so that whatever `baseline:steer` asks (at
/// most 1 either way), the agent can still reach any steering.
pub const STEER_RESIDUAL_GAIN: f64 = 2.0;
/// Largest [`SteerAssist::near_goal`], metres: the tasks draw their goals 4-15 m away, so a
/// hand-over from further off would have steer drive most episodes from their start.
pub const MAX_ASSIST_NEAR_GOAL: f64 = 10.0;
/// The length of a gait action (steering, amplitude, frequency), the only one the controllers set.
pub const GAIT_ACTION_LEN: usize = 3;

/// A hand-made controller of the gait-action tasks, by its `baseline:NAME`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HandController {
    /// The wave at the middle of its amplitude and frequency ranges, never steered: the paper's
    /// "sine wave" start, which goes wherever its drift takes it.
    Gait,
    /// The same wave steered towards the goal: steering action `clip(-bearing, -1, 1)`, the goal's
    /// bearing in radians (0 ahead, positive to the left), read from the observation's goal vector.
    Steer,
}

impl HandController {
    /// Every controller, in the order they are listed.
    pub const ALL: [HandController; 2] = [HandController::Gait, HandController::Steer];

    /// The name after `baseline:`.
    pub fn name(self) -> &'static str {
        match self {
            HandController::Gait => "gait",
            HandController::Steer => "steer",
        }
    }

    /// The controller called `name`; the error lists the names.
    pub fn from_name(name: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|c| c.name() == name)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|c| c.name()).collect();
                // `invalid` caps the message, so a hostile name cannot flood it.
                invalid(format!(
                    "unknown baseline '{name}' (expected one of: {})",
                    names.join(", ")
                ))
            })
    }

    /// Writes the actions for `rows` observations of `on`'s env (`obs`: `rows x observation_dim`)
    /// into `actions` (`rows x 3`).
    pub fn act(self, on: &ControlledEnv, obs: &[f32], rows: usize, actions: &mut [f64]) {
        for (row, action) in on
            .rows(obs, rows)
            .zip(actions.chunks_exact_mut(GAIT_ACTION_LEN))
        {
            action.fill(0.0);
            if self == HandController::Steer {
                action[0] = steer_towards(on.goal_vector(row));
            }
        }
    }
}

/// `baseline:steer`'s steering action for the goal vector (gx, gy) in the head frame (its -y ahead,
/// +x to the left): `clip(-atan2(gx, -gy), -1, 1)`, in float32 as the observation holds the vector.
pub fn steer_towards((gx, gy): (f32, f32)) -> f64 {
    f64::from((-gx.atan2(-gy)).clamp(-1.0, 1.0))
}

/// An env the controllers can drive (gait actions, an observation with the goal vector), with where
/// its observation holds the goal vector.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ControlledEnv {
    observation_dim: usize,
    goal_at: usize,
}

impl ControlledEnv {
    /// `config`'s env, or an error saying what it lacks (`what` names who asks, e.g. `the
    /// baselines` or `steer_assist`).
    pub fn of(config: &EnvConfig, what: &str) -> Result<Self> {
        let goal_at = config
            .observation_structure()
            .offset(ObservationPart::GoalVector);
        match goal_at {
            Some(goal_at) if config.action.mode == ActionMode::Gait => Ok(ControlledEnv {
                observation_dim: config.observation_dim(),
                goal_at,
            }),
            _ => Err(invalid(format!(
                "{what} need action mode 'gait' and observation 'extended' or 'terrain' (baseline:steer reads the goal vector), got '{}' and '{}'",
                config.action.mode.name(),
                config.observation.name()
            ))),
        }
    }

    /// The length of its observations.
    pub fn observation_dim(&self) -> usize {
        self.observation_dim
    }

    fn rows<'a>(&self, obs: &'a [f32], rows: usize) -> std::slice::ChunksExact<'a, f32> {
        obs[..rows * self.observation_dim].chunks_exact(self.observation_dim)
    }

    /// The goal vector (gx, gy) of one observation, metres in the head frame.
    fn goal_vector(&self, obs: &[f32]) -> (f32, f32) {
        (obs[self.goal_at], obs[self.goal_at + 1])
    }
}

/// `baseline:steer` sharing an agent's gait actions: it corrects the agent's steering
/// (`residual`), takes over near the goal (`near_goal`), or both. Applied between the agent and the
/// env: the env is the plain gait env, the agent's action space is unchanged.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SteerAssist {
    /// The agent's steering action corrects `baseline:steer`'s instead of setting it (residual
    /// policy learning: the agent starts as the hand controller and learns where to depart from
    /// it): the steering is `clip(steer + STEER_RESIDUAL_GAIN * a, -1, 1)`, so actions of 0 drive
    /// exactly `baseline:steer`.
    pub residual: bool,
    /// Metres (0: off): within this distance of the goal (the observation's goal vector)
    /// `baseline:steer` drives whatever the agent's action: steering `clip(-bearing, -1, 1)`,
    /// amplitude and frequency actions 0 (the middle of their ranges). A hand-over: the agent finds
    /// the way, the hand controller makes the last approach. At most [`MAX_ASSIST_NEAR_GOAL`].
    pub near_goal: f64,
}

impl Default for SteerAssist {
    fn default() -> Self {
        SteerAssist {
            residual: false,
            near_goal: 0.0,
        }
    }
}

impl SteerAssist {
    /// Checks the values; errors name the key under `steer_assist`.
    pub fn validate(&self) -> Result<()> {
        let near = self.near_goal;
        if !(near.is_finite() && (0.0..=MAX_ASSIST_NEAR_GOAL).contains(&near)) {
            return Err(invalid_at(
                "steer_assist.near_goal",
                format!("must be in [0, {MAX_ASSIST_NEAR_GOAL}] m, got {near}"),
            ));
        }
        if !self.residual && near == 0.0 {
            return Err(invalid_at(
                "steer_assist",
                "set residual: true, near_goal: METRES or both (as it is, it changes nothing)",
            ));
        }
        Ok(())
    }

    /// The assist bound to `config`'s env, checked against it.
    pub fn bind(self, config: &EnvConfig) -> Result<AssistedEnv> {
        self.validate()?;
        Ok(AssistedEnv {
            assist: self,
            env: ControlledEnv::of(config, "steer_assist: the assisted actions")?,
        })
    }

    /// A one-line description for a model's metadata.
    pub fn describe(&self) -> String {
        let mut parts = Vec::new();
        if self.residual {
            parts.push(format!(
                "the steering corrects baseline:steer's: clip(steer + {STEER_RESIDUAL_GAIN} x action, -1, 1)"
            ));
        }
        if self.near_goal > 0.0 {
            parts.push(format!(
                "within {} m of the goal baseline:steer drives, whatever the action",
                self.near_goal
            ));
        }
        parts.join("; ")
    }
}

/// A [`SteerAssist`] for one env's observations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AssistedEnv {
    assist: SteerAssist,
    env: ControlledEnv,
}

impl AssistedEnv {
    /// The assist.
    pub fn assist(&self) -> SteerAssist {
        self.assist
    }

    /// The length of the observations it reads.
    pub fn observation_dim(&self) -> usize {
        self.env.observation_dim()
    }

    /// The env's actions for `rows` agent actions (`rows x 3`, each value clipped to [-1, 1] first,
    /// as the env clips) answering the observations `obs` (`rows x observation_dim`), into `out`
    /// (`rows x 3`). Computed in float64, so the env must be given `out` as it is.
    pub fn apply<A: Copy + Into<f64>>(
        &self,
        obs: &[f32],
        actions: &[A],
        rows: usize,
        out: &mut [f64],
    ) {
        let agent = actions[..rows * GAIT_ACTION_LEN].chunks_exact(GAIT_ACTION_LEN);
        let env = out[..rows * GAIT_ACTION_LEN].chunks_exact_mut(GAIT_ACTION_LEN);
        for ((row, agent), env) in self.env.rows(obs, rows).zip(agent).zip(env) {
            let goal = self.env.goal_vector(row);
            let steer = steer_towards(goal);
            let near = self.assist.near_goal > 0.0
                && f64::from(goal.0).hypot(f64::from(goal.1)) < self.assist.near_goal;
            let a = |i: usize| agent[i].into().clamp(-1.0, 1.0);
            if near {
                // The hand-over: baseline:steer's action.
                env.copy_from_slice(&[steer, 0.0, 0.0]);
            } else if self.assist.residual {
                env.copy_from_slice(&[
                    (steer + STEER_RESIDUAL_GAIN * a(0)).clamp(-1.0, 1.0),
                    a(1),
                    a(2),
                ]);
            } else {
                env.copy_from_slice(&[a(0), a(1), a(2)]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::ObservationLayout;
    use crate::{Preset, ResetOptions, SnakeEnv};

    fn gait_env(observation: ObservationLayout) -> EnvConfig {
        EnvConfig {
            observation,
            action: crate::ActionConfig {
                mode: ActionMode::Gait,
                ..Default::default()
            },
            ..EnvConfig::goal_task(Preset::Paper, 5)
        }
    }

    #[test]
    fn names_round_trip_and_unknown_ones_are_listed() {
        for c in HandController::ALL {
            assert_eq!(HandController::from_name(c.name()).unwrap(), c);
        }
        let message = HandController::from_name("wiggle").unwrap_err().to_string();
        assert!(
            message.contains("'wiggle'") && message.contains("gait, steer"),
            "{message}"
        );
    }

    #[test]
    fn the_controllers_need_gait_actions_and_the_goal_vector() {
        let paper = EnvConfig::default();
        let message = ControlledEnv::of(&paper, "the baselines")
            .unwrap_err()
            .to_string();
        assert!(message.contains("action mode 'gait'"), "{message}");
        let mut joints = gait_env(ObservationLayout::Extended);
        joints.action.mode = ActionMode::Joints;
        assert!(ControlledEnv::of(&joints, "x").is_err());
        assert!(ControlledEnv::of(&gait_env(ObservationLayout::Paper), "x").is_err());
        for layout in [ObservationLayout::Extended, ObservationLayout::Terrain] {
            assert!(ControlledEnv::of(&gait_env(layout), "x").is_ok());
        }
    }

    #[test]
    fn bad_assists_name_the_key() {
        for (assist, key) in [
            (SteerAssist::default(), "steer_assist:"),
            (
                SteerAssist {
                    near_goal: f64::NAN,
                    ..Default::default()
                },
                "steer_assist.near_goal",
            ),
            (
                SteerAssist {
                    near_goal: -1.0,
                    residual: true,
                },
                "steer_assist.near_goal",
            ),
            (
                SteerAssist {
                    near_goal: 10.5,
                    ..Default::default()
                },
                "steer_assist.near_goal",
            ),
        ] {
            let message = assist.validate().unwrap_err().message();
            assert!(message.starts_with(key), "{message}");
        }
        let paper = EnvConfig::default();
        let residual = SteerAssist {
            residual: true,
            ..Default::default()
        };
        assert!(residual.bind(&paper).is_err());
    }

    /// Zero corrections drive `baseline:steer` exactly, a full correction any steering whatever
    /// steer asks, and near the goal steer's action replaces whatever the agent asks.
    #[test]
    fn the_assist_composes_steer_and_the_agent() {
        let config = gait_env(ObservationLayout::Terrain);
        let on = ControlledEnv::of(&config, "x").unwrap();
        let mut env = SnakeEnv::new(config.clone()).unwrap();
        // The goal about 3 m off, within any hand-over distance.
        let options = ResetOptions {
            goal: Some((2.0, 2.0)),
            ..Default::default()
        };
        let (obs, _) = env.reset(Some(3), options).unwrap();
        let mut steer = [0.0; 3];
        HandController::Steer.act(&on, &obs, 1, &mut steer);
        let goal_at = config
            .observation_structure()
            .offset(ObservationPart::GoalVector)
            .unwrap();
        let (gx, gy) = (obs[goal_at], obs[goal_at + 1]);
        assert_eq!(steer, [steer_towards((gx, gy)), 0.0, 0.0]);
        let mut gait = [1.0; 3];
        HandController::Gait.act(&on, &obs, 1, &mut gait);
        assert_eq!(gait, [0.0; 3]);

        let residual = SteerAssist {
            residual: true,
            ..Default::default()
        }
        .bind(&config)
        .unwrap();
        let mut out = [9.0; 3];
        residual.apply(&obs, &[0.0f32, 0.25, -2.0], 1, &mut out);
        assert_eq!(out, [steer[0], 0.25, -1.0]);
        residual.apply(&obs, &[1.0f32, 0.0, 0.0], 1, &mut out);
        assert_eq!(out[0], 1.0);
        residual.apply(&obs, &[-1.0f32, 0.0, 0.0], 1, &mut out);
        assert_eq!(out[0], -1.0);

        let distance = f64::from(gx).hypot(f64::from(gy));
        for (near_goal, handed) in [(distance * 1.01, true), (distance * 0.99, false)] {
            let near = SteerAssist {
                near_goal,
                residual: false,
            }
            .bind(&config)
            .unwrap();
            near.apply(&obs, &[0.5f64, 0.5, 0.5], 1, &mut out);
            let expected = if handed { steer } else { [0.5; 3] };
            assert_eq!(out, expected, "near_goal {near_goal}, goal at {distance}");
        }
    }
}
