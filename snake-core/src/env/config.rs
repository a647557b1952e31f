//! Configuration of [`SnakeEnv`](super::SnakeEnv): the snake, the task and the observation.

use serde::{Deserialize, Serialize};

use super::action::{ActionConfig, ActionMode};
use super::height_map::HeightMap;
use super::randomize::Randomize;
use super::reward::RewardConfig;
use super::terrain::{PegField, RoughGround, TerrainDistribution};
use crate::config::{Preset, SnakeConfig};
use crate::error::{invalid, invalid_at, Result};
use crate::limits::{
    check_key_position, check_key_range, MAX_ACTION_SCALE, MAX_EPISODE_STEPS,
    MAX_PHYSICS_STEPS_PER_ENV_STEP, MAX_POSITION, MAX_REWARD_WEIGHT, MAX_START_HEIGHT, MAX_YAW,
};
use crate::robot::RobotRef;
use crate::world_file::WorldRef;

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
    /// A URDF robot instead of the built-in snake (`None`): the path of a `.urdf` or robot file,
    /// loaded when the configuration is made. With a robot, `snake` still gives the time step and
    /// gravity, the robot file gives the body, its friction and its motors, an action holds one value
    /// per movable joint (pybullet's joint order) and the observation's joint pairs are the movable
    /// joints'; the start distribution places the root link's frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robot: Option<RobotRef>,
    /// A world file (ground, friction, obstacles; docs/worlds.md) instead of the flat plane (`None`):
    /// its path, loaded when the configuration is made, built at every reset before the robot. The
    /// start distribution is kept as given: on raised ground, raise `start`'s z to match.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub world: Option<WorldRef>,
    /// Goal position (x, y) on the plane, metres ((0, -10)); used when `goal_distribution` is `None`.
    pub goal: (f64, f64),
    /// Draw each episode's goal relative to its start pose instead of using `goal` (`None`).
    pub goal_distribution: Option<GoalDistribution>,
    /// Random terrain laid out anew at each reset from the episode's stream, after the goal: a peg
    /// field between start and goal, rough ground, or both, added to `world` (`None`: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub terrain: Option<TerrainDistribution>,
    /// The episode terminates (successfully) when the distance to the goal is below this (1.0 m).
    pub goal_radius: f64,
    /// Env steps after which an episode is truncated (5000, gym's `TimeLimit` of `Snake-v0`).
    pub max_episode_steps: u64,
    /// Physics steps of [`SnakeConfig::dt`] per env step, with the same targets (1).
    pub physics_steps_per_env_step: u32,
    /// Distribution of the start pose drawn at each reset.
    pub start: StartDistribution,
    /// Joint targets are `clip(action, -1, 1) * action_scale` radians (1.0), in the `joints` action
    /// mode.
    pub action_scale: f64,
    /// What an action sets: joint targets (the paper's), a steered wave, or a wave plus corrections.
    pub action: ActionConfig,
    /// What the observation holds.
    pub observation: ObservationLayout,
    /// The terrain observation's height map: its grid's points per side and their spacing (5 and
    /// 0.75 m). Left out of written configurations while it is the default.
    #[serde(skip_serializing_if = "HeightMap::is_default")]
    pub height_map: HeightMap,
    /// Optional reward terms and the success reward.
    pub reward: RewardConfig,
    /// Physics drawn anew at every reset from the env's physics stream ([`Randomize`]: ground
    /// friction, masses, motors, latency, observation noise, skin friction); `None` (the default):
    /// the nominal physics every episode. Left out of written configurations while `None`, so a
    /// configuration recorded before it existed resolves as it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub randomize: Option<Randomize>,
}

impl Default for EnvConfig {
    fn default() -> Self {
        EnvConfig {
            snake: SnakeConfig::default(),
            robot: None,
            world: None,
            goal: (0.0, -10.0),
            goal_distribution: None,
            terrain: None,
            goal_radius: 1.0,
            max_episode_steps: 5000,
            physics_steps_per_env_step: 1,
            start: StartDistribution::default(),
            action_scale: 1.0,
            action: ActionConfig::default(),
            observation: ObservationLayout::Paper,
            height_map: HeightMap::default(),
            reward: RewardConfig::default(),
            randomize: None,
        }
    }
}

/// Where each episode's goal lies relative to its start pose: at a distance drawn uniformly from
/// `distance` and a bearing drawn uniformly from `bearing`, measured from the start heading
/// (0: straight ahead, where the head points; positive: to the left, counterclockwise seen from
/// above). Drawn after the start pose, distance first, from the env's random stream.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GoalDistribution {
    /// Range of the distance from the start position, metres ([5, 15]).
    pub distance: [f64; 2],
    /// Range of the bearing, radians ([-pi, pi]: any direction).
    pub bearing: [f64; 2],
}

impl Default for GoalDistribution {
    fn default() -> Self {
        GoalDistribution {
            distance: [5.0, 15.0],
            bearing: [-std::f64::consts::PI, std::f64::consts::PI],
        }
    }
}

/// Largest goal distance the goal distribution may draw, metres.
pub const MAX_GOAL_DISTANCE: f64 = 1000.0;

impl GoalDistribution {
    /// The goal for a start at (x, y) with heading `yaw`, from two uniform numbers in [0, 1).
    pub fn goal(&self, x: f64, y: f64, yaw: f64, u_distance: f64, u_bearing: f64) -> (f64, f64) {
        let [d0, d1] = self.distance;
        let [b0, b1] = self.bearing;
        let distance = d0 + (d1 - d0) * u_distance;
        // The head points along -y at heading 0; rotating that by yaw + bearing about z.
        let angle = yaw + b0 + (b1 - b0) * u_bearing;
        (x + distance * angle.sin(), y - distance * angle.cos())
    }

    /// Checks the ranges; the error names the field.
    pub fn validate(&self) -> Result<()> {
        let [d0, d1] = self.distance;
        if !(d0.is_finite() && d1.is_finite() && 0.0 <= d0 && d0 <= d1 && d1 <= MAX_GOAL_DISTANCE) {
            return Err(invalid_at(
                "goal_distribution.distance",
                format!(
                "must be a range [low, high] with 0 <= low <= high <= {MAX_GOAL_DISTANCE} m, got [{d0}, {d1}]"
            )));
        }
        let [b0, b1] = self.bearing;
        let tau = std::f64::consts::TAU;
        if !(b0.is_finite() && b1.is_finite() && b0 <= b1 && b0 >= -tau && b1 <= tau) {
            return Err(invalid_at(
                "goal_distribution.bearing",
                format!(
                "must be a range [low, high] of radians with -2 pi <= low <= high <= 2 pi, got [{b0}, {b1}]"
            )));
        }
        Ok(())
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

    /// Checks that the ranges are finite, ordered and within [`crate::limits`]; the error names the
    /// field.
    pub fn validate(&self) -> Result<()> {
        for (name, [low, high], bound) in [
            ("start.x", self.x, MAX_POSITION),
            ("start.y", self.y, MAX_POSITION),
            ("start.yaw", self.yaw, MAX_YAW),
        ] {
            if !(low.is_finite() && high.is_finite()) {
                return Err(invalid_at(
                    name,
                    format!("must be finite, got [{low}, {high}]"),
                ));
            }
            if low > high {
                return Err(invalid_at(
                    name,
                    format!("must have low <= high, got [{low}, {high}]"),
                ));
            }
            if low < -bound || high > bound {
                return Err(invalid_at(
                    name,
                    format!("must lie within [-{bound}, {bound}], got [{low:?}, {high:?}]"),
                ));
            }
        }
        check_key_range("start.z", self.z, 0.0, MAX_START_HEIGHT)
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
    /// The extended layout (with the wave's phase where it has one) followed by the world's up
    /// (its z axis) in the head's frame (3: (0, 0, 1) upright, (0, 0, -1) upside down) and a height
    /// map of the ground around the head ([`HeightMap`](super::HeightMap)): by default 25 heights relative to
    /// the head's z on a 5 x 5 grid, 0.75 m apart (`EnvConfig::height_map`); `2 + 2N + 6 + 3 + 25`
    /// in all. The goal, heading, velocity and map are in the rolled head frame
    /// (`observation::rolled_frame`: the heading of the body's long axis, left mirrored upside
    /// down), which rolling over on hills does not scramble; upright and level it is the extended
    /// layout's frame.
    Terrain,
}

impl ObservationLayout {
    /// Length of the observation for a snake of `joints` joints with a height map of `map_len`
    /// values (the terrain layout's), without the wave's phase: the sum of its
    /// [`structure`](Self::structure)'s sizes.
    pub fn dim(self, joints: usize, map_len: usize) -> usize {
        self.structure(joints, false, map_len).len()
    }

    /// The named parts of the observation, in order, for a snake of `joints` joints, with the
    /// wave's phase (`wave_phase`, which only the extended and terrain layouts hold) and a height
    /// map of `map_len` values (the terrain layout's): the one description that the observation's
    /// length, the code that writes it and every reader derive from.
    pub fn structure(
        self,
        joints: usize,
        wave_phase: bool,
        map_len: usize,
    ) -> ObservationStructure {
        let mut s = ObservationStructure::default();
        s.push(ObservationPart::BasePosition, 2);
        s.push(ObservationPart::JointStates, 2 * joints);
        if self.is_extended() {
            s.push(ObservationPart::GoalVector, 2);
            s.push(ObservationPart::Heading, 2);
            s.push(ObservationPart::BaseVelocity, 2);
            if wave_phase {
                s.push(ObservationPart::WavePhase, 2);
            }
        }
        if self == ObservationLayout::Terrain {
            s.push(ObservationPart::WorldUp, 3);
            s.push(ObservationPart::HeightMap, map_len);
        }
        s
    }

    /// Whether the layout holds the extended layout's six values (goal, heading, velocity).
    pub fn is_extended(self) -> bool {
        self != ObservationLayout::Paper
    }

    /// Every layout, in the order the configuration's error message lists them.
    pub const ALL: [ObservationLayout; 3] = [
        ObservationLayout::Paper,
        ObservationLayout::Extended,
        ObservationLayout::Terrain,
    ];

    /// The configuration name (`paper`, `extended` or `terrain`).
    pub fn name(self) -> &'static str {
        match self {
            ObservationLayout::Paper => "paper",
            ObservationLayout::Extended => "extended",
            ObservationLayout::Terrain => "terrain",
        }
    }
}

impl std::str::FromStr for ObservationLayout {
    type Err = crate::Error;

    fn from_str(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|layout| layout.name() == s)
            .ok_or_else(|| {
                let names: Vec<_> = Self::ALL.iter().map(|l| l.name()).collect();
                invalid(format!(
                    "unknown observation layout '{s}' (expected one of: {})",
                    names.join(", ")
                ))
            })
    }
}

/// A named part of the observation vector (Gymnasium's `observation_structure`, as in Swimmer-v5:
/// name -> size, in order).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ObservationPart {
    /// x and y of the base (head cube) centre in the world, m.
    BasePosition,
    /// Per joint from the head (joint 0) to the tail, its angle (rad) and angular velocity (rad/s),
    /// interleaved: `angle_0, velocity_0, angle_1, ...` (2N values).
    JointStates,
    /// The goal minus the base position in the head frame (x, y), m.
    GoalVector,
    /// Sine and cosine of the head frame's heading (its rotation about world z).
    Heading,
    /// The base's planar linear velocity in the head frame (x, y), m/s.
    BaseVelocity,
    /// Sine and cosine of the wave's phase at the head (a wave action mode's extended or terrain
    /// observation).
    WavePhase,
    /// The world's up (its z axis) in the head's own frame (x, y, z): (0, 0, 1) upright.
    WorldUp,
    /// Ground heights relative to the head's z on the height map's grid, m (row-major, see
    /// [`HeightMap`]).
    HeightMap,
}

impl ObservationPart {
    /// Every part, in the order an observation holds those it has.
    pub const ALL: [ObservationPart; 8] = [
        ObservationPart::BasePosition,
        ObservationPart::JointStates,
        ObservationPart::GoalVector,
        ObservationPart::Heading,
        ObservationPart::BaseVelocity,
        ObservationPart::WavePhase,
        ObservationPart::WorldUp,
        ObservationPart::HeightMap,
    ];

    /// The part's name in `observation_structure`.
    pub fn name(self) -> &'static str {
        match self {
            ObservationPart::BasePosition => "base_position",
            ObservationPart::JointStates => "joint_states",
            ObservationPart::GoalVector => "goal_vector",
            ObservationPart::Heading => "heading",
            ObservationPart::BaseVelocity => "base_velocity",
            ObservationPart::WavePhase => "wave_phase",
            ObservationPart::WorldUp => "world_up",
            ObservationPart::HeightMap => "height_map",
        }
    }

    /// The part named `name`, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// The observation's named parts and their sizes, in order ([`ObservationLayout::structure`]); the
/// observation's length is the sum of the sizes. Fixed-size and `Copy`: reading it allocates nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObservationStructure {
    parts: [(ObservationPart, usize); ObservationPart::ALL.len()],
    count: usize,
}

impl Default for ObservationStructure {
    fn default() -> Self {
        ObservationStructure {
            parts: [(ObservationPart::BasePosition, 0); ObservationPart::ALL.len()],
            count: 0,
        }
    }
}

impl ObservationStructure {
    fn push(&mut self, part: ObservationPart, size: usize) {
        self.parts[self.count] = (part, size);
        self.count += 1;
    }

    /// The parts and their sizes, in order.
    pub fn parts(&self) -> &[(ObservationPart, usize)] {
        &self.parts[..self.count]
    }

    /// The parts' names and sizes, in order (Gymnasium's `observation_structure`).
    pub fn named(&self) -> impl Iterator<Item = (&'static str, usize)> + '_ {
        self.parts().iter().map(|&(p, n)| (p.name(), n))
    }

    /// Length of the observation: the sum of the parts' sizes.
    pub fn len(&self) -> usize {
        self.parts().iter().map(|&(_, n)| n).sum()
    }

    /// Whether the observation has no value (never: the base position is always there).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The indices of `part` in the observation, or `None` where the observation lacks it.
    pub fn range(&self, part: ObservationPart) -> Option<std::ops::Range<usize>> {
        let mut at = 0;
        for &(p, n) in self.parts() {
            if p == part {
                return Some(at..at + n);
            }
            at += n;
        }
        None
    }

    /// The first index of `part`, or `None` where the observation lacks it.
    pub fn offset(&self, part: ObservationPart) -> Option<usize> {
        self.range(part).map(|r| r.start)
    }

    /// The indices of the part named `name`, or `None` where there is no such part here.
    pub fn range_of(&self, name: &str) -> Option<std::ops::Range<usize>> {
        ObservationPart::from_name(name).and_then(|p| self.range(p))
    }
}

/// The task an env's defaults come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Task {
    /// The paper's env (`Snake-v0`): a fixed goal 10 m ahead, joint-target actions, minus the distance
    /// as the reward.
    #[default]
    Paper,
    /// Goal reaching (`SnakeGoal-v0`): see [`EnvConfig::goal_task`].
    Goal,
    /// A goal behind a random peg field (`SnakePegs-v0`): see [`EnvConfig::pegs_task`].
    Pegs,
    /// A goal across random rough ground with hills (`SnakeRough-v0`): see [`EnvConfig::rough_task`].
    Rough,
    /// A goal in water (`SnakeSwim-v0`): see [`EnvConfig::swim_task`].
    Swim,
}

impl Task {
    /// Every task.
    pub const ALL: [Task; 5] = [Task::Paper, Task::Goal, Task::Pegs, Task::Rough, Task::Swim];

    /// The configuration name.
    pub fn name(self) -> &'static str {
        match self {
            Task::Paper => "paper",
            Task::Goal => "goal",
            Task::Pegs => "pegs",
            Task::Rough => "rough",
            Task::Swim => "swim",
        }
    }
}

/// The swimming task's default world, `pool.yaml`: `worlds/pool.yaml`'s still water, 1 m deep over
/// the plane and 20 m x 20 m, written here so that the task builds without the repository's files
/// (a test holds the two to one world). It is recorded in the configuration as its text.
pub const SWIM_POOL: &str =
    "media:\n  - {medium: water, area: [-10, -10, 10, 10], surface: 1.0, depth: 1.0}\n";

/// [`SWIM_POOL`] as a world reference (a record of one file, `pool.yaml`).
pub fn built_in_pool() -> WorldRef {
    let record = crate::recorded::RecordedFiles {
        path: "pool.yaml".into(),
        files: [("pool.yaml".to_owned(), SWIM_POOL.to_owned())].into(),
    };
    WorldRef::from_record(&record).expect("the built-in pool is a valid world file")
}

impl EnvConfig {
    /// The defaults of `task` for a `preset` snake of `joints` joints.
    pub fn for_task(task: Task, preset: Preset, joints: usize) -> Self {
        match task {
            Task::Paper => EnvConfig::with_preset(preset, joints),
            Task::Goal => EnvConfig::goal_task(preset, joints),
            Task::Pegs => EnvConfig::pegs_task(preset, joints),
            Task::Rough => EnvConfig::rough_task(preset, joints),
            Task::Swim => EnvConfig::swim_task(preset, joints),
        }
    }

    /// A goal in water (`snakesim/SnakeSwim-v0`, docs/media.md "Swimming to goals"): the goal task's
    /// actions, observation and reward, a goal 3-6 m from the start in any direction in the plane of
    /// the surface (the distance is measured across the water, as on the ground), a start 2 cm under a
    /// surface 1 m up (the body's axis just under water), episodes of at most 900 env steps (30 s), in
    /// the still pool [`SWIM_POOL`]. Another `world` must have water; a current that pushes is the
    /// world's water entry, or drawn at each reset by `randomize`'s `current_speed` and
    /// `current_heading`.
    pub fn swim_task(preset: Preset, joints: usize) -> Self {
        EnvConfig {
            world: Some(built_in_pool()),
            goal_distribution: Some(GoalDistribution {
                distance: [3.0, 6.0],
                ..GoalDistribution::default()
            }),
            start: StartDistribution {
                z: 0.98,
                ..StartDistribution::default()
            },
            max_episode_steps: 900,
            ..EnvConfig::goal_task(preset, joints)
        }
    }

    /// A goal behind a random peg field (`snakesim/SnakePegs-v0`): the goal task's actions,
    /// observation and reward, a goal 4-6 m from the start within 45 degrees of its heading, and a
    /// new [`PegField`] at each reset (its defaults: 3 cm pegs 30 cm high on a 0.3 m grid, 70 % of
    /// the points filled, jittered 8 cm, in a band 3 m wide from 1 m after the start to 1 m before
    /// the goal); episodes of at most 900 env steps (30 s).
    pub fn pegs_task(preset: Preset, joints: usize) -> Self {
        EnvConfig {
            goal_distribution: Some(GoalDistribution {
                distance: [4.0, 6.0],
                bearing: [-std::f64::consts::FRAC_PI_4, std::f64::consts::FRAC_PI_4],
            }),
            terrain: Some(TerrainDistribution {
                pegs: Some(PegField::default()),
                rough: None,
            }),
            max_episode_steps: 900,
            ..EnvConfig::goal_task(preset, joints)
        }
    }

    /// A goal across random rough ground with hills (`snakesim/SnakeRough-v0`): the goal task's
    /// actions, observation and reward, a goal 5-8 m from the start in any direction, and new
    /// [`RoughGround`] at each reset (its defaults: 8 cm bumps 0.5 m apart on 1.2 m hills 3 m apart,
    /// sampled every 0.125 m to 3 m beyond start and goal); the start is raised by the ground's
    /// highest point within 1.5 m of the origin; episodes of at most 900 env steps (30 s), ended
    /// early when the head leaves the ground's square.
    pub fn rough_task(preset: Preset, joints: usize) -> Self {
        EnvConfig {
            goal_distribution: Some(GoalDistribution {
                distance: [5.0, 8.0],
                ..GoalDistribution::default()
            }),
            terrain: Some(TerrainDistribution {
                pegs: None,
                rough: Some(RoughGround::default()),
            }),
            max_episode_steps: 900,
            ..EnvConfig::goal_task(preset, joints)
        }
    }

    /// Goal reaching beyond the paper (`snakesim/SnakeGoal-v0`), with the defaults our experiments
    /// found best (docs/experiments.md, "Beyond the paper"): a goal drawn 5-15 m from the start in any
    /// direction; actions steer a lateral-undulation wave (the `gait` mode: steering, amplitude,
    /// frequency) at 30 Hz (8 physics steps per env step); the extended observation with the wave's
    /// phase; reward: progress towards the goal (1 per metre) and 10 on arrival, no distance term;
    /// episodes of at most 600 env steps (20 s).
    pub fn goal_task(preset: Preset, joints: usize) -> Self {
        EnvConfig {
            snake: preset.config(joints),
            goal_distribution: Some(GoalDistribution::default()),
            max_episode_steps: 600,
            physics_steps_per_env_step: 8,
            action: ActionConfig {
                mode: ActionMode::Gait,
                ..ActionConfig::default()
            },
            observation: ObservationLayout::Extended,
            reward: RewardConfig {
                distance_weight: 0.0,
                progress_weight: 1.0,
                success_reward: 10.0,
                ..RewardConfig::default()
            },
            ..EnvConfig::default()
        }
    }

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

    /// Number of driven joints: the snake's, or the robot's movable joints.
    pub fn joints(&self) -> usize {
        match &self.robot {
            Some(r) => r.spec().urdf.movable_joints().len(),
            None => self.snake.joints,
        }
    }

    /// Mass of the whole body, kg: the built-in snake's cubes, or the robot's links
    /// ([`RobotSpec::masses`](crate::RobotSpec::masses)).
    pub fn body_mass(&self) -> f64 {
        match &self.robot {
            Some(r) => r.spec().masses().iter().sum(),
            None => self.snake.base_mass + self.snake.joints as f64 * self.snake.link_mass,
        }
    }

    /// Length of an action: one value per joint, or the gait mode's three.
    pub fn action_dim(&self) -> usize {
        self.action.dim(self.joints())
    }

    /// Length of the observation vector: the layout's, plus the wave's phase (sin, cos) when the
    /// extended layout meets a wave action mode.
    pub fn observation_dim(&self) -> usize {
        self.observation_structure().len()
    }

    /// The observation's named parts and their sizes, in order
    /// ([`ObservationLayout::structure`] of this configuration's joints, wave phase and height map).
    pub fn observation_structure(&self) -> ObservationStructure {
        self.observation.structure(
            self.joints(),
            self.observes_wave_phase(),
            self.height_map.len(),
        )
    }

    /// Whether the world file has water (a `media` entry `{medium: water}`).
    pub fn has_water(&self) -> bool {
        self.world.as_ref().is_some_and(|w| {
            w.spec()
                .media
                .iter()
                .any(|m| matches!(m, crate::media::Medium::Water(_)))
        })
    }

    /// Whether the observation ends with the sine and cosine of the wave's phase at the head.
    pub fn observes_wave_phase(&self) -> bool {
        self.observation.is_extended() && self.action.mode.uses_wave()
    }

    /// Checks every field; the one-line error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        self.snake.validate().map_err(|e| match e {
            crate::Error::InvalidArgument(m) => crate::Error::InvalidArgument(m.under("snake")),
            other => other,
        })?;
        if let Some(r) = &self.robot {
            if self.joints() == 0 {
                return Err(invalid_at(
                    "robot",
                    format!("{} has no movable joint to act on", r.path().display()),
                ));
            }
        }
        check_key_position("goal", self.goal.0, self.goal.1)?;
        check_key_range("goal_radius", self.goal_radius, 0.0, MAX_POSITION)?;
        if !(1..=MAX_EPISODE_STEPS).contains(&self.max_episode_steps) {
            return Err(invalid_at(
                "max_episode_steps",
                format!(
                    "must be in [1, {MAX_EPISODE_STEPS}], got {}",
                    self.max_episode_steps
                ),
            ));
        }
        if !(1..=MAX_PHYSICS_STEPS_PER_ENV_STEP).contains(&self.physics_steps_per_env_step) {
            return Err(invalid_at(
                "physics_steps_per_env_step",
                format!(
                    "must be in [1, {MAX_PHYSICS_STEPS_PER_ENV_STEP}], got {}",
                    self.physics_steps_per_env_step
                ),
            ));
        }
        self.start.validate()?;
        if let Some(goals) = &self.goal_distribution {
            goals.validate()?;
        }
        if let Some(terrain) = &self.terrain {
            terrain.validate()?;
        }
        self.action.validate()?;
        self.height_map.validate()?;
        if !self.height_map.is_default() && self.observation != ObservationLayout::Terrain {
            return Err(invalid_at(
                "height_map",
                format!(
                    "needs observation 'terrain' (the map is its last values), got '{}'",
                    self.observation.name()
                ),
            ));
        }
        if !(self.action_scale.is_finite()
            && self.action_scale > 0.0
            && self.action_scale <= MAX_ACTION_SCALE)
        {
            return Err(invalid_at(
                "action_scale",
                format!(
                    "must be in (0, {MAX_ACTION_SCALE}], got {}",
                    self.action_scale
                ),
            ));
        }
        if let Some(randomize) = &self.randomize {
            let has_skin = match &self.robot {
                None => self.snake.skin_friction.is_some(),
                Some(r) => r.spec().skin_friction.iter().any(Option::is_some),
            };
            randomize.validate(has_skin, self.has_water())?;
        }
        self.reward.validate()
    }
}

impl RewardConfig {
    /// Checks every weight against [`MAX_REWARD_WEIGHT`]; the error names the key.
    pub fn validate(&self) -> Result<()> {
        for (name, w) in [
            ("reward.distance_weight", self.distance_weight),
            ("reward.progress_weight", self.progress_weight),
            ("reward.smoothness_weight", self.smoothness_weight),
            ("reward.energy_weight", self.energy_weight),
            ("reward.success_reward", self.success_reward),
        ] {
            check_key_range(name, w, -MAX_REWARD_WEIGHT, MAX_REWARD_WEIGHT)?;
        }
        Ok(())
    }
}
