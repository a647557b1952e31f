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
use crate::gait::{Gait, LateralUndulation};
use crate::keys::by_name;

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
        by_name(&Self::ALL, Self::name, name, "baseline")
    }

    /// Writes the actions for `rows` observations of `on`'s env (`obs`: `rows x observation_dim`)
    /// into `actions` (`rows x 3`).
    pub fn act(self, on: &ControlledEnv, obs: &[f32], rows: usize, actions: &mut [f64]) {
        self.act_holding(on, obs, rows, actions, HeldWave::default());
    }

    /// [`HandController::act`] with the amplitude and frequency actions at `hold`'s values rather
    /// than at the middle of their ranges (a run's `init: {imitate: steer, hold: ...}`).
    pub fn act_holding(
        self,
        on: &ControlledEnv,
        obs: &[f32],
        rows: usize,
        actions: &mut [f64],
        hold: HeldWave,
    ) {
        for (row, action) in on
            .rows(obs, rows)
            .zip(actions.chunks_exact_mut(GAIT_ACTION_LEN))
        {
            action[0] = match self {
                HandController::Gait => 0.0,
                HandController::Steer => steer_towards(on.goal_vector(row)),
            };
            action[1] = hold.amplitude;
            action[2] = hold.frequency;
        }
    }
}

/// The amplitude and frequency actions a gait-action hand controller holds, each in [-1, 1] as the
/// env's actions are: 0 is the middle of the env's range (what `baseline:gait` and `baseline:steer`
/// hold), 1 its top. A fixed wave driven harder than the middle can be the better controller (the
/// sand task's, experiments/sand-patch), and a run can imitate it (`init.hold`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeldWave {
    /// The amplitude action (0).
    #[serde(default)]
    pub amplitude: f64,
    /// The frequency action (0).
    #[serde(default)]
    pub frequency: f64,
}

impl HeldWave {
    /// Both finite and in [-1, 1]; the error names the one that is not (`amplitude: ...`).
    pub fn validate(&self) -> Result<()> {
        for (key, value) in [("amplitude", self.amplitude), ("frequency", self.frequency)] {
            if !(-1.0..=1.0).contains(&value) {
                return Err(invalid_at(
                    key,
                    format!("must be an action in [-1, 1], got {value}"),
                ));
            }
        }
        Ok(())
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

/// A joint-target controller a run can imitate before training (`init: {imitate: NAME}`, snake-rl;
/// the gait-action ones are [`HandController`]s, both named by [`crate::imitation::Imitated`]): it
/// acts in the env's own action space, so that a policy can be fitted to its actions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Imitable {
    /// [`JointsSine`] unsteered: pybullet snake.py's wave as joint targets.
    Sine,
    /// [`JointsSine`] steered back to the line through the goal along the wave's direction of
    /// travel ([`JOINTS_STEER_GAIN`]).
    SteeredSine,
}

impl Imitable {
    /// Every one, in the order they are listed.
    pub const ALL: [Imitable; 2] = [Imitable::Sine, Imitable::SteeredSine];

    /// The configuration name (also `baseline:NAME`'s).
    pub fn name(self) -> &'static str {
        match self {
            Imitable::Sine => "sine",
            Imitable::SteeredSine => "steered_sine",
        }
    }

    /// The one called `name`; the error lists the names.
    pub fn from_name(name: &str) -> Result<Self> {
        by_name(&Self::ALL, Self::name, name, "controller")
    }
}

/// [`Imitable::SteeredSine`]'s steering offset per metre of the base's x off the goal's x, radians
/// (`steering = clip(gain * (x - goal_x), -JOINTS_MAX_STEERING, JOINTS_MAX_STEERING)`). The paper's
/// env observes no heading, only the base position, and its snake travels towards -y with a start
/// yaw within 0.2 rad: a controller of the observation alone steers on the lateral offset.
pub const JOINTS_STEER_GAIN: f64 = 0.15;
/// [`Imitable::SteeredSine`]'s largest steering offset, radians: the wave (0.4 rad) plus the
/// offset stays inside [-1, 1] rad, the joints mode's targets at `action_scale` 1.
pub const JOINTS_MAX_STEERING: f64 = 0.3;

/// pybullet snake.py's wave ([`LateralUndulation`]) as the `joints` action mode's actions: each
/// env's wave advances by `physics_steps_per_env_step` physics steps per env step and restarts with
/// its episode; an action is the wave's target over `action_scale`, clipped to [-1, 1]. Steered
/// ([`Imitable::SteeredSine`]), the wave's steering offset follows the base's lateral offset from
/// the goal ([`JOINTS_STEER_GAIN`]).
#[derive(Debug, Clone)]
pub struct JointsSine {
    kind: Imitable,
    joints: usize,
    observation_dim: usize,
    /// Where the observation holds the base position (the steered controller's input).
    base_at: usize,
    goal_x: f64,
    steer_gain: f64,
    action_scale: f64,
    waves: Vec<LateralUndulation>,
    targets: Vec<f64>,
}

impl JointsSine {
    /// The controller for `envs` envs of `config`, or an error saying why it cannot drive them.
    pub fn new(kind: Imitable, config: &EnvConfig, envs: usize) -> Result<Self> {
        if config.action.mode != ActionMode::Joints {
            return Err(invalid(format!(
                "{} sets joint targets: it needs action mode 'joints', got '{}'",
                kind.name(),
                config.action.mode.name()
            )));
        }
        let base_at = config
            .observation_structure()
            .offset(ObservationPart::BasePosition);
        let base_at = match (kind, base_at) {
            (Imitable::Sine, at) => at.unwrap_or(0),
            (Imitable::SteeredSine, Some(at)) if config.goal_distribution.is_none() => at,
            _ => {
                return Err(invalid(format!(
                    "steered_sine steers on the base position towards the fixed goal: it needs an \
                     observation with the base position ('paper') and no goal_distribution, got '{}'",
                    config.observation.name()
                )))
            }
        };
        let mut wave = LateralUndulation::default();
        wave.dt = config.snake.dt * f64::from(config.physics_steps_per_env_step);
        Ok(JointsSine {
            kind,
            joints: config.joints(),
            observation_dim: config.observation_dim(),
            base_at,
            goal_x: config.goal.0,
            steer_gain: JOINTS_STEER_GAIN,
            action_scale: config.action_scale,
            waves: vec![wave; envs],
            targets: vec![0.0; config.joints()],
        })
    }

    /// The same with another steering gain (radians per metre; [`JOINTS_STEER_GAIN`]).
    pub fn with_steer_gain(mut self, gain: f64) -> Self {
        self.steer_gain = gain;
        self
    }

    /// The number of envs it drives.
    pub fn envs(&self) -> usize {
        self.waves.len()
    }

    /// The length of an observation it reads.
    pub fn observation_dim(&self) -> usize {
        self.observation_dim
    }

    /// The length of an action it writes (the env's joints).
    pub fn action_dim(&self) -> usize {
        self.joints
    }

    /// Restarts env `env`'s wave (its episode ended).
    pub fn reset(&mut self, env: usize) {
        self.waves[env].reset();
    }

    /// Writes every env's action for its observation (`obs`: `envs x observation_dim`) into
    /// `actions` (`envs x joints`) and advances the waves by one env step.
    pub fn act(&mut self, obs: &[f32], actions: &mut [f32]) {
        let rows = obs.chunks_exact(self.observation_dim);
        for ((wave, row), action) in self
            .waves
            .iter_mut()
            .zip(rows)
            .zip(actions.chunks_exact_mut(self.joints))
        {
            wave.steering = match self.kind {
                Imitable::Sine => 0.0,
                Imitable::SteeredSine => (self.steer_gain
                    * (f64::from(row[self.base_at]) - self.goal_x))
                    .clamp(-JOINTS_MAX_STEERING, JOINTS_MAX_STEERING),
            };
            wave.next_targets(&mut self.targets);
            for (a, t) in action.iter_mut().zip(&self.targets) {
                *a = (t / self.action_scale).clamp(-1.0, 1.0) as f32;
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
        // An imitable controller's name is its configuration name (serde's) too.
        for c in Imitable::ALL {
            assert_eq!(Imitable::from_name(c.name()).unwrap(), c);
            let json = serde_json::to_string(&c).unwrap();
            assert_eq!(json, format!("\"{}\"", c.name()));
        }
        let message = Imitable::from_name("wiggle").unwrap_err().to_string();
        assert!(message.contains("sine, steered_sine"), "{message}");
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

    #[test]
    fn joints_sine_is_the_wave_over_the_action_scale() {
        let config = EnvConfig {
            action_scale: 0.5,
            ..EnvConfig::default()
        };
        let mut c = JointsSine::new(Imitable::Sine, &config, 2).unwrap();
        let (n, d) = (config.joints(), config.observation_dim());
        let (mut wave, mut restarted) =
            (LateralUndulation::default(), LateralUndulation::default());
        let obs = vec![0.0f32; 2 * d];
        let mut actions = vec![0.0f32; 2 * n];
        let (mut targets, mut restarted_targets) = (vec![0.0; n], vec![0.0; n]);
        let expected = |t: &[f64]| -> Vec<f32> {
            t.iter()
                .map(|t| (t / 0.5).clamp(-1.0, 1.0) as f32)
                .collect()
        };
        for step in 0..1000 {
            if step == 600 {
                c.reset(1);
                restarted.reset();
            }
            c.act(&obs, &mut actions);
            wave.next_targets(&mut targets);
            restarted.next_targets(&mut restarted_targets);
            assert_eq!(actions[..n], expected(&targets)[..], "step {step}");
            if step >= 600 {
                assert_eq!(
                    actions[n..],
                    expected(&restarted_targets)[..],
                    "step {step}"
                );
            }
        }
        // Steered on the goal's line, it is the plain wave; off it, the steering is bounded.
        let mut steered = JointsSine::new(Imitable::SteeredSine, &config, 1).unwrap();
        let mut plain = JointsSine::new(Imitable::Sine, &config, 1).unwrap();
        let (mut a, mut b) = (vec![0.0f32; n], vec![0.0f32; n]);
        for _ in 0..500 {
            steered.act(&obs[..d], &mut a);
            plain.act(&obs[..d], &mut b);
            assert_eq!(a, b);
        }
        let mut off = obs[..d].to_vec();
        off[0] = 100.0;
        steered.act(&off, &mut a);
        let mut wave = LateralUndulation::default().with_steering(JOINTS_MAX_STEERING);
        for _ in 0..501 {
            wave.next_targets(&mut targets);
        }
        assert_eq!(a, expected(&targets));
    }

    #[test]
    fn joints_sine_needs_the_joints_mode() {
        let message = JointsSine::new(Imitable::Sine, &gait_env(ObservationLayout::Extended), 1)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("needs action mode 'joints', got 'gait'"),
            "{message}"
        );
        let goal = EnvConfig {
            goal_distribution: Some(Default::default()),
            ..EnvConfig::default()
        };
        assert!(JointsSine::new(Imitable::SteeredSine, &goal, 1).is_err());
        assert!(JointsSine::new(Imitable::Sine, &goal, 1).is_ok());
    }
}
