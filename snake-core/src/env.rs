//! The paper's reinforcement-learning environment: [`SnakeEnv`], a Gymnasium-style `reset`/`step`
//! interface over [`Snake`], bit-exact with the paper's pybullet env.

mod action;
mod config;
mod course;
mod height_map;
pub mod keywords;
mod observation;
mod randomize;
mod reward;
mod route;
mod terrain;
#[cfg(test)]
mod tests;
mod trace;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha12Rng;
use serde::{Deserialize, Serialize};

pub use action::{
    ActionConfig, ActionMode, MAX_GAIT_AMPLITUDE, MAX_GAIT_FREQUENCY, MAX_GAIT_STEERING,
    MAX_RESIDUAL_SCALE,
};
pub use config::{
    EnvConfig, GoalDistribution, ObservationLayout, ObservationPart, ObservationStructure,
    StartDistribution, Task, MAX_GOAL_DISTANCE, SWIM_POOL,
};
pub use height_map::{
    HeightMap, HEIGHT_MAP_LEN, HEIGHT_MAP_SIDE, HEIGHT_MAP_SPACING, MAX_HEIGHT_MAP_SIDE,
    MAX_HEIGHT_MAP_SPACING,
};
pub use randomize::{Physics, Randomize, NOISE_STREAM, PHYSICS_STREAM};
pub use reward::{
    paper_distance, python_hypot, DistancePrecision, RewardConfig, RewardInputs, RewardTerms,
};
pub use route::{route_distance, route_distance_around, Capsule, Disc, Footprint, Segment};
pub use terrain::{Craters, Layout, PegField, Ridges, RoughGround, TerrainDistribution};
pub use trace::PhysicsTrace;

use crate::error::{invalid, Result};
use crate::math::StartPose;
use crate::robot::Simulation;
use crate::world_file::WorldSpec;
use crate::{Body, Robot, Snake};
use action::Driver;
use observation::JointScratch;

/// On random rough ground a drawn start is raised by the ground's highest point within this many
/// metres of the origin.
pub const TERRAIN_START_REACH: f64 = 1.5;

/// Per-episode choices for [`SnakeEnv::reset`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ResetOptions {
    /// Place the base exactly here instead of drawing the start (no random numbers are drawn then).
    pub start: Option<StartPose>,
    /// The goal of this episode instead of [`EnvConfig::goal`].
    pub goal: Option<(f64, f64)>,
}

/// What a reset or a step reports besides the observation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Info {
    /// Distance from the base to the goal, metres, computed as the paper's reward computes it (from
    /// the `float32` observation; see [`paper_distance`]).
    pub distance: f64,
    /// Every term of this step's reward (all 0 after a reset).
    pub reward_terms: RewardTerms,
    /// The base is within [`EnvConfig::goal_radius`] of the goal (only ever true on a step, which
    /// then terminates the episode).
    pub success: bool,
    /// Env steps taken in this episode (0 after a reset).
    pub episode_step: u64,
    /// Sum of this episode's rewards so far.
    pub episode_return: f64,
    /// Simulated seconds since the episode's world was built (the reset's own physics step included).
    pub time: f64,
    /// This episode's goal.
    pub goal: (f64, f64),
    /// This episode's start pose.
    pub start: StartPose,
    /// Mechanical work of the motors in this episode so far, joules: the sum over physics steps and
    /// joints of |torque x joint velocity| x dt.
    pub work: f64,
    /// Length of the base's path in the plane in this episode so far, metres (sampled once per env
    /// step).
    pub path_length: f64,
    /// Straight-line planar distance of the base from where it was after the reset, metres.
    pub displacement: f64,
}

/// The result of [`SnakeEnv::step`]: Gymnasium's `(obs, reward, terminated, truncated, info)`.
#[derive(Debug, Clone, PartialEq)]
pub struct StepResult {
    /// The observation after the step.
    pub obs: Vec<f32>,
    /// The step's reward.
    pub reward: f64,
    /// The episode ended in a terminal state (the goal was reached).
    pub terminated: bool,
    /// The episode was cut off by the step limit.
    pub truncated: bool,
    /// Details, including every reward term.
    pub info: Info,
}

/// The result of [`SnakeEnv::step_into`]: a [`StepResult`] whose observation went to the caller's slice.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepOutcome {
    /// The step's reward.
    pub reward: f64,
    /// The episode ended in a terminal state (the goal was reached).
    pub terminated: bool,
    /// The episode was cut off by the step limit.
    pub truncated: bool,
    /// Details, including every reward term.
    pub info: Info,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Phase {
    /// No episode yet, or the last step failed.
    NeedsReset,
    Running,
    /// The last step terminated or truncated the episode.
    Done,
}

/// The snake robot crawling to a goal: the environment of "Simulating Snakes" (snakebot-gym's
/// `Snake-v0`), reproduced bit for bit from its pybullet 3.2.7 implementation.
///
/// ## Description
///
/// A snake of `N` position-controlled revolute joints (`N + 1` cubes of 0.5 m, see
/// [`SnakeConfig`](crate::SnakeConfig)) lies on a plane with anisotropic friction. The policy sets the
/// joint target angles; the snake should crawl to a goal, by default 10 m away in -y, which is where
/// its head points at the start. Each env step is [`EnvConfig::physics_steps_per_env_step`] physics
/// steps of 1/240 s (1: an episode of 5000 steps is 20.8 simulated seconds).
///
/// ## Action Space
///
/// `Box(-1, 1, (N,), float32)`, one value per joint from the head (joint 0, next to the base) to the
/// tail. Actions are clipped to [-1, 1] and multiplied by [`EnvConfig::action_scale`] (1.0): the
/// result is the target angle in radians of pybullet's `POSITION_CONTROL` with the configured motor
/// force (10 N m) and pybullet's default gains (kp 0.1, kd 1.0). `f32` and `f64` actions are accepted;
/// the wrong length or a non-finite value is an [`Error::InvalidArgument`](crate::Error::InvalidArgument).
///
/// ## Observation Space
///
/// `Box(-inf, inf, (D,), float32)`. Every value is the simulator's double cast to `float32`.
/// [`EnvConfig::observation_structure`] names its parts in order ([`ObservationPart`]: name and size,
/// Gymnasium's `observation_structure`); the tables below are its index formulas.
/// [`ObservationLayout::Paper`] (the default), `D = 2 + 2N`:
///
/// | index      | observation                                      | unit    |
/// |------------|--------------------------------------------------|---------|
/// | 0          | x of the base (head cube) centre                 | m       |
/// | 1          | y of the base centre                             | m       |
/// | 2 + 2j     | angle of joint j (j = 0..N-1, head to tail)      | rad     |
/// | 3 + 2j     | angular velocity of joint j                      | rad/s   |
///
/// (The paper's README says all angles first, then all velocities; its code interleaves them, as here.)
/// [`ObservationLayout::Extended`] appends 6 values, `D = 2 + 2N + 6`, in the head frame (the base's
/// frame rotated by its heading only; its y axis runs from head to tail, so "forward" is -y):
///
/// | index      | observation                                      | unit    |
/// |------------|--------------------------------------------------|---------|
/// | 2N + 2     | goal minus base position, head-frame x           | m       |
/// | 2N + 3     | goal minus base position, head-frame y           | m       |
/// | 2N + 4     | sin of the heading (rotation of the base about z) | -       |
/// | 2N + 5     | cos of the heading                               | -       |
/// | 2N + 6     | base linear velocity, head-frame x               | m/s     |
/// | 2N + 7     | base linear velocity, head-frame y               | m/s     |
///
/// ## Rewards
///
/// The paper's reward is `-distance`, where `distance` is computed from the observation exactly as
/// `math.hypot(goal_x - obs[0], goal_y - obs[1])` with numpy `float32` arithmetic (see
/// [`DistancePrecision`] and [`python_hypot`]). On the step that ends with `distance <
/// goal_radius` the reward is [`RewardConfig::success_reward`] (100) instead. A run that never
/// arrives scores about -50,000. Optional shaping terms, off by default (weight 0), are added to it:
/// progress towards the goal, a smoothness penalty on the change of the joint targets and an energy
/// penalty on the motors' mechanical work; [`RewardTerms`] defines each. `info.reward_terms` reports
/// every term of every step.
///
/// ## Starting State
///
/// Every reset builds a fresh world (plane, gravity -9.81 m/s², the snake straight along +y from its
/// base) with the base at `(x, y, z)` and heading `yaw` (`getQuaternionFromEuler((0, 0, yaw))`),
/// where x, y ~ U(-0.5, 0.5), z = 0.5 and yaw ~ U(-0.2, 0.2) ([`StartDistribution`]; the snake drops
/// 0.25 m onto the plane), then takes one physics step before the first observation. The start is
/// drawn from a ChaCha12 generator: `reset(Some(seed))` reseeds it, `reset(None)` continues its
/// stream (the first reset without any seed seeds it from the OS, as Gymnasium does).
/// [`ResetOptions`] can fix the start pose and the goal of one episode.
///
/// ## Episode End
///
/// - Termination: the distance to the goal falls below [`EnvConfig::goal_radius`] (1 m); or,
///   unsuccessfully, with [`EnvConfig::terrain`]'s rough ground, the base leaves its square (beyond
///   it the body falls off the world) or, with `terrain.rough.craters.terminate`, is over a crater's
///   floor.
/// - Truncation: the episode reaches [`EnvConfig::max_episode_steps`] env steps (5000, the
///   `TimeLimit` registered with `Snake-v0`). Both flags are true if both happen on the same step.
///
/// After either, [`SnakeEnv::step`] fails until the next [`SnakeEnv::reset`]. A simulation that
/// blows up ([`Error::NonFinite`](crate::Error::NonFinite)) also ends the episode; reset to go on.
///
/// ## Arguments
///
/// [`EnvConfig`]: the snake ([`SnakeConfig`](crate::SnakeConfig), presets `paper` and `snakebot-gym`;
/// the paper's published env is [`EnvConfig::snakebot_gym`]), `goal`, `goal_radius`,
/// `max_episode_steps`, `physics_steps_per_env_step`, `start`, `action_scale`, `observation` and
/// `reward` (shaping weights, success reward, distance precision).
///
/// ## Differences from the paper's env
///
/// The paper's env also loads a static duck mesh one metre beyond the goal as a marker; it only
/// matters if the snake touches it and is left out. Its action space is not clipped by the env itself
/// (Stable-Baselines3 clips before stepping); here the env clips.
///
/// ```
/// use snake_core::{EnvConfig, ResetOptions, SnakeEnv};
///
/// let mut env = SnakeEnv::new(EnvConfig::snakebot_gym(5))?;
/// let (obs, info) = env.reset(Some(42), ResetOptions::default())?;
/// assert_eq!(obs.len(), 12);
/// assert_eq!(info.episode_step, 0);
/// let step = env.step(&[0.5f32, -0.5, 0.5, -0.5, 0.5])?;
/// assert_eq!(step.reward, -step.info.distance);
/// assert!(!step.terminated && !step.truncated);
/// # Ok::<(), snake_core::Error>(())
/// ```
#[derive(Debug)]
pub struct SnakeEnv {
    config: EnvConfig,
    rng: Option<ChaCha12Rng>,
    snake: Option<Body>,
    phase: Phase,
    goal: (f64, f64),
    start: StartPose,
    episode_step: u64,
    episode_return: f64,
    distance: f64,
    targets: Vec<f64>,
    previous_action: Vec<f64>,
    driver: Driver,
    joints: JointScratch,
    torques: Vec<f64>,
    /// Base position after the reset, and now.
    origin: (f64, f64),
    position: (f64, f64),
    work: f64,
    path_length: f64,
    /// The latest reset's or step's physics steps, when on.
    trace: Option<PhysicsTrace>,
    /// The current episode's world, when [`EnvConfig::terrain`] laid one out.
    episode_world: Option<WorldSpec>,
    /// The current episode's ground, for the terrain observation's height map (the plane otherwise).
    ground: height_map::GroundProbe,
    /// What the progress term measures its way around and where the episode ends, from the
    /// terrain [`EnvConfig::terrain`] laid out (nothing without it).
    course: course::Course,
    /// The distance the progress term measured after the latest step or reset.
    progress_distance: f64,
    /// The observation's parts ([`EnvConfig::observation_structure`]), derived once: every reset and
    /// step writes the observation by it.
    structure: ObservationStructure,
    /// The physics stream ([`Randomize`]; the module `randomize` documents it), when randomizing.
    physics_rng: Option<ChaCha12Rng>,
    /// The observation noise's stream, apart from the physics stream so that the physics of an
    /// episode never depends on how many steps the episodes before it took.
    noise_rng: Option<ChaCha12Rng>,
    /// The physics the latest reset drew (empty without [`EnvConfig::randomize`]).
    physics: Physics,
    /// The delay line of `latency_steps` actions (`action_dim` values each), oldest at `delay_head`.
    delay: Vec<f64>,
    delay_head: usize,
}

impl SnakeEnv {
    /// Changes the reward's weights from the next step on (a trainer annealing a term in); the rest of
    /// the configuration stays. Checked as the configuration's `reward` is.
    pub fn set_reward(&mut self, reward: RewardConfig) -> Result<()> {
        reward.validate()?;
        self.config.reward = reward;
        Ok(())
    }

    /// An environment with the given configuration; call [`SnakeEnv::reset`] before stepping.
    pub fn new(config: EnvConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self::from_valid(config))
    }

    /// [`SnakeEnv::new`] of a configuration that `validate` has accepted already (a vector env checks
    /// its one configuration once, not once per env).
    pub(crate) fn from_valid(config: EnvConfig) -> Self {
        let n = config.joints();
        let driver = Driver::new(&config);
        let structure = config.observation_structure();
        SnakeEnv {
            previous_action: vec![0.0; config.action_dim()],
            driver,
            origin: (0.0, 0.0),
            position: (0.0, 0.0),
            work: 0.0,
            path_length: 0.0,
            goal: config.goal,
            start: StartPose {
                x: 0.0,
                y: 0.0,
                z: config.start.z,
                yaw: 0.0,
            },
            config,
            rng: None,
            snake: None,
            phase: Phase::NeedsReset,
            episode_step: 0,
            episode_return: 0.0,
            distance: 0.0,
            targets: vec![0.0; n],
            joints: JointScratch::new(n),
            torques: vec![0.0; n],
            trace: None,
            episode_world: None,
            ground: height_map::GroundProbe::Plane,
            course: course::Course::default(),
            progress_distance: 0.0,
            structure,
            physics_rng: None,
            noise_rng: None,
            physics: Physics::default(),
            delay: Vec::new(),
            delay_head: 0,
        }
    }

    /// Turns the physics trace on or off (off by default). While on, every reset and step records
    /// the snake's full state after each of its physics steps (cube poses, joint angles, velocities,
    /// motor torques and targets), read back with [`SnakeEnv::physics_trace`]. Recording only reads
    /// the world: observations and rewards are the same bits either way.
    pub fn set_physics_trace(&mut self, on: bool) {
        self.trace = on.then(|| PhysicsTrace::new(self.config.joints()));
    }

    /// The physics steps of the latest reset or step, if the trace is on (see
    /// [`SnakeEnv::set_physics_trace`]): empty before the first reset; after a failed call, the
    /// steps before the failure.
    pub fn physics_trace(&self) -> Option<&PhysicsTrace> {
        self.trace.as_ref()
    }

    /// The physics the latest reset drew from [`EnvConfig::randomize`] (the given keys only; empty
    /// without it).
    pub fn physics(&self) -> &Physics {
        &self.physics
    }

    /// The configuration.
    pub fn config(&self) -> &EnvConfig {
        &self.config
    }

    /// Length of an action: one value per joint, or 3 in the gait action mode.
    pub fn action_dim(&self) -> usize {
        self.config.action_dim()
    }

    /// Length of an observation.
    pub fn observation_dim(&self) -> usize {
        self.config.observation_dim()
    }

    /// Bounds of every action value, (-1, 1).
    pub fn action_bounds(&self) -> (f32, f32) {
        (-1.0, 1.0)
    }

    /// The current episode's goal.
    pub fn goal(&self) -> (f64, f64) {
        self.goal
    }

    /// Env steps taken in the current episode.
    pub fn episode_step(&self) -> u64 {
        self.episode_step
    }

    /// Whether [`SnakeEnv::step`] needs a [`SnakeEnv::reset`] first (no episode yet, or it ended).
    pub fn needs_reset(&self) -> bool {
        self.phase != Phase::Running
    }

    /// The current episode's snake and world (for rendering or extra measurements), if any and if it
    /// is the built-in snake.
    pub fn snake(&self) -> Option<&Snake> {
        self.snake.as_ref().and_then(Body::snake)
    }

    /// The current episode's world when [`EnvConfig::terrain`] laid one out at the latest reset
    /// (`None` otherwise: the world is the configuration's).
    pub fn episode_world(&self) -> Option<&WorldSpec> {
        self.episode_world.as_ref()
    }

    /// The current episode's body (its world, its ground), if any.
    pub fn body(&self) -> Option<&Body> {
        self.snake.as_ref()
    }

    /// The current episode's body, the built-in snake or a robot, if any.
    pub fn simulation(&self) -> Option<&dyn Simulation> {
        self.snake.as_ref().map(Body::sim)
    }

    /// Starts an episode and returns the first observation. See the type's documentation.
    pub fn reset(&mut self, seed: Option<u64>, options: ResetOptions) -> Result<(Vec<f32>, Info)> {
        let mut obs = vec![0.0; self.observation_dim()];
        let info = self.reset_into(seed, options, &mut obs)?;
        Ok((obs, info))
    }

    /// [`SnakeEnv::reset`] writing the observation into `obs` (of length
    /// [`SnakeEnv::observation_dim`]).
    pub fn reset_into(
        &mut self,
        seed: Option<u64>,
        options: ResetOptions,
        obs: &mut [f32],
    ) -> Result<Info> {
        self.check_obs_len(obs)?;
        if let Some(goal) = options.goal {
            crate::limits::check_position("reset goal", goal.0, goal.1)?;
        }
        if let Some(start) = options.start {
            start.validate()?;
        }
        if let Some(seed) = seed {
            self.rng = Some(ChaCha12Rng::seed_from_u64(seed));
            if self.config.randomize.is_some() {
                let mut physics = ChaCha12Rng::seed_from_u64(seed);
                physics.set_stream(PHYSICS_STREAM);
                self.physics_rng = Some(physics);
                let mut noise = ChaCha12Rng::seed_from_u64(seed);
                noise.set_stream(NOISE_STREAM);
                self.noise_rng = Some(noise);
            }
        }
        // The physics stream, never the main one: the start, goal and terrain are the plain env's.
        self.physics = match &self.config.randomize {
            None => Physics::default(),
            Some(r) => r.draw(
                self.physics_rng
                    .get_or_insert_with(ChaCha12Rng::from_entropy),
            ),
        };
        let start = match options.start {
            Some(start) => start,
            None => {
                let rng = self.rng.get_or_insert_with(ChaCha12Rng::from_entropy);
                let d = &self.config.start;
                let mut uniform = |[low, high]: [f64; 2]| low + (high - low) * rng.gen::<f64>();
                let (x, y) = (uniform(d.x), uniform(d.y));
                let yaw = uniform(d.yaw);
                StartPose { x, y, z: d.z, yaw }
            }
        };
        // A drawn goal takes two more numbers, after the start's (none with a fixed goal, so the
        // paper's stream is untouched).
        let goal = match (options.goal, &self.config.goal_distribution) {
            (Some(goal), _) => goal,
            (None, None) => self.config.goal,
            (None, Some(goals)) => {
                let rng = self.rng.get_or_insert_with(ChaCha12Rng::from_entropy);
                let (u_distance, u_bearing) = (rng.gen::<f64>(), rng.gen::<f64>());
                goals.goal(start.x, start.y, start.yaw, u_distance, u_bearing)
            }
        };

        // Drop the old world first: at most one world per env is alive at a time.
        self.snake = None;
        self.phase = Phase::NeedsReset;
        if let Some(trace) = self.trace.as_mut() {
            trace.clear();
        }
        let flat = WorldSpec::default();
        let mut world = self.config.world.as_ref().map_or(&flat, |w| w.spec());
        // Random terrain takes one more number, after the goal's (none without it).
        let mut start = start;
        self.episode_world = None;
        self.course = course::Course::default();
        let laid_out;
        if let Some(terrain) = &self.config.terrain {
            let rng = self.rng.get_or_insert_with(ChaCha12Rng::from_entropy);
            let seed = rng.gen::<u64>();
            let layout = terrain.layout(world, &start, goal, seed)?;
            self.course = course::Course::of(terrain, &self.config.reward, &layout);
            laid_out = layout.world;
            world = &laid_out;
            if terrain.rough.is_some() && options.start.is_none() {
                start.z += world.ground_top(TERRAIN_START_REACH);
            }
        }
        let keep = self.config.terrain.is_some().then(|| world.clone());
        self.ground = if self.config.observation == ObservationLayout::Terrain {
            height_map::GroundProbe::of(world)
        } else {
            height_map::GroundProbe::Plane
        };
        let mut body = match &self.config.robot {
            None => Body::Cubes(Snake::in_world(&self.config.snake, start, world)?),
            Some(robot) => Body::Robot(Robot::in_world(robot.spec(), start, world)?),
        };
        self.physics.apply(&mut body)?;
        let k = self.physics.latency_steps.unwrap_or(0) as usize;
        self.delay.clear();
        self.delay.resize(k * self.config.action_dim(), 0.0);
        self.delay_head = 0;
        let snake = body.sim_mut();
        // The paper steps once before the first observation.
        snake.step()?;
        if let Some(trace) = self.trace.as_mut() {
            trace.record(snake, None)?;
        }
        self.goal = goal;
        self.start = start;
        self.episode_step = 0;
        self.episode_return = 0.0;
        self.previous_action.fill(0.0);
        self.driver.reset();
        let base = observation::write(
            self.config.observation,
            &self.structure,
            snake,
            self.goal,
            self.wave_phase(),
            (&self.ground, &self.config.height_map),
            &mut self.joints,
            obs,
        )?;
        finite_output(obs, 0.0, 0.0)?;
        self.origin = (base.pose.position.x, base.pose.position.y);
        self.position = self.origin;
        self.work = 0.0;
        self.path_length = 0.0;
        self.distance = paper_distance(
            self.goal,
            obs[0],
            obs[1],
            self.config.reward.distance_precision,
        );
        self.progress_distance =
            self.course
                .progress_distance(self.origin, self.goal, self.distance);
        self.snake = Some(body);
        self.episode_world = keep;
        self.phase = Phase::Running;
        self.add_obs_noise(obs);
        Ok(self.info(RewardTerms::default(), false))
    }

    /// One env step with `action` (one value per joint, `f32` or `f64`). See the type's documentation.
    pub fn step<A: Copy + Into<f64>>(&mut self, action: &[A]) -> Result<StepResult> {
        let mut obs = vec![0.0; self.observation_dim()];
        let out = self.step_into(action, &mut obs)?;
        Ok(StepResult {
            obs,
            reward: out.reward,
            terminated: out.terminated,
            truncated: out.truncated,
            info: out.info,
        })
    }

    /// [`SnakeEnv::step`] writing the observation into `obs` (of length
    /// [`SnakeEnv::observation_dim`]); allocation-free.
    pub fn step_into<A: Copy + Into<f64>>(
        &mut self,
        action: &[A],
        obs: &mut [f32],
    ) -> Result<StepOutcome> {
        self.check_step(action, obs)?;
        if self.delay.is_empty() {
            self.driver.set_action(action.iter().map(|&a| a.into()));
        } else {
            // The motors get the action of `latency_steps` steps ago; this one waits in its slot.
            let d = action.len();
            let slot = &mut self.delay[self.delay_head * d..(self.delay_head + 1) * d];
            self.driver.set_action(slot.iter().copied());
            for (s, &a) in slot.iter_mut().zip(action) {
                *s = a.into();
            }
            self.delay_head = (self.delay_head + 1) % (self.delay.len() / d);
        }
        let (base, work) = match self.simulate(obs) {
            Ok(done) => done,
            Err(e) => {
                self.phase = Phase::NeedsReset;
                return Err(e);
            }
        };
        let p = (base.pose.position.x, base.pose.position.y);
        self.path_length += (p.0 - self.position.0).hypot(p.1 - self.position.1);
        self.position = p;
        self.work += work;

        let weights = self.config.reward;
        let distance = paper_distance(self.goal, obs[0], obs[1], weights.distance_precision);
        let success = distance < self.config.goal_radius;
        let progress_distance = self.course.progress_distance(p, self.goal, distance);
        let terms = RewardTerms::compute(
            &weights,
            &RewardInputs {
                success,
                distance,
                progress_distance,
                previous_progress_distance: self.progress_distance,
                action: self.driver.action(),
                previous_action: &self.previous_action,
                work,
            },
        );
        self.previous_action.copy_from_slice(self.driver.action());
        self.distance = distance;
        self.progress_distance = progress_distance;
        let reward = terms.total(&weights);
        // The limits keep these finite; if physics ever drifts out of float32's range anyway, it is
        // an error, never an inf handed to a learner.
        if let Err(e) = finite_output(obs, reward, self.episode_return + reward) {
            self.phase = Phase::NeedsReset;
            return Err(e);
        }
        self.episode_step += 1;
        self.episode_return += reward;
        // The course ends the episode off the ground (beyond the rough ground's edge the body falls
        // for the rest of it, which can no longer succeed: 10 % of steer's episodes did so before)
        // and in its hazards.
        let terminated = success || self.course.ends_at(p);
        let truncated = self.episode_step >= self.config.max_episode_steps;
        if terminated || truncated {
            self.phase = Phase::Done;
        }
        self.add_obs_noise(obs);
        Ok(StepOutcome {
            reward,
            terminated,
            truncated,
            info: self.info(terms, success),
        })
    }

    /// A step may run: an episode is running, `obs` has the observation's length and `action` one
    /// finite value per action dimension.
    fn check_step<A: Copy + Into<f64>>(&self, action: &[A], obs: &[f32]) -> Result<()> {
        match self.phase {
            Phase::Running => {}
            Phase::NeedsReset => {
                return Err(invalid(
                    "step() needs reset() first (no episode is running)",
                ))
            }
            Phase::Done => {
                return Err(invalid(
                    "step() after the episode ended (terminated or truncated); call reset() first",
                ))
            }
        }
        self.check_obs_len(obs)?;
        let n = self.action_dim();
        if action.len() != n {
            return Err(invalid(format!(
                "action must have {n} values (one per joint), got {}",
                action.len()
            )));
        }
        for (j, a) in action.iter().enumerate() {
            let a: f64 = (*a).into();
            if !a.is_finite() {
                return Err(invalid(format!("action[{j}] must be finite, got {a}")));
            }
        }
        Ok(())
    }

    /// The physics of one env step (`physics_steps_per_env_step` steps, the driver's targets set
    /// before each or before the first) and the observation after it; returns the base's state and
    /// the motors' mechanical work (J) over the step.
    fn simulate(&mut self, obs: &mut [f32]) -> Result<(observation::BaseState, f64)> {
        let Some(snake) = self.snake.as_mut().map(Body::sim_mut) else {
            return Err(invalid(
                "step() needs reset() first (no episode is running)",
            ));
        };
        let dt = snake.dt();
        let mut work = 0.0;
        let driver = &mut self.driver;
        let per_physics_step = driver.per_physics_step();
        let mut trace = self.trace.as_mut();
        if let Some(trace) = trace.as_mut() {
            trace.clear();
        }
        if !per_physics_step {
            driver.next_targets(&mut self.targets);
            snake.set_targets(&self.targets)?;
        }
        for _ in 0..self.config.physics_steps_per_env_step {
            if per_physics_step {
                driver.next_targets(&mut self.targets);
                snake.set_targets(&self.targets)?;
            }
            snake.step()?;
            snake.read_joint_states(&mut [], &mut self.joints.velocities, &mut self.torques)?;
            let power: f64 = self
                .torques
                .iter()
                .zip(&self.joints.velocities)
                .map(|(t, v)| (t * v).abs())
                .sum();
            work += power * dt;
            if let Some(trace) = trace.as_mut() {
                trace.record(snake, Some(&self.targets))?;
            }
        }
        let phase = per_physics_step.then(|| driver.wave_phase());
        let base = observation::write(
            self.config.observation,
            &self.structure,
            snake,
            self.goal,
            phase.filter(|_| self.config.observes_wave_phase()),
            (&self.ground, &self.config.height_map),
            &mut self.joints,
            obs,
        )?;
        Ok((base, work))
    }

    fn check_obs_len(&self, obs: &[f32]) -> Result<()> {
        let d = self.observation_dim();
        if obs.len() != d {
            return Err(invalid(format!(
                "observation buffer must have {d} values, got {}",
                obs.len()
            )));
        }
        Ok(())
    }

    fn info(&self, reward_terms: RewardTerms, success: bool) -> Info {
        Info {
            distance: self.distance,
            reward_terms,
            success,
            episode_step: self.episode_step,
            episode_return: self.episode_return,
            time: self.snake.as_ref().map_or(0.0, |b| b.sim().time()),
            goal: self.goal,
            start: self.start,
            work: self.work,
            path_length: self.path_length,
            displacement: (self.position.0 - self.origin.0).hypot(self.position.1 - self.origin.1),
        }
    }

    /// The observation noise of [`Randomize::obs_noise`] on the observation handed out (after the
    /// reward and the termination read the noiseless one); nothing without it.
    fn add_obs_noise(&mut self, obs: &mut [f32]) {
        if let Some(std) = self.physics.obs_noise {
            let rng = self.noise_rng.get_or_insert_with(ChaCha12Rng::from_entropy);
            randomize::add_noise(obs, std, rng);
        }
    }

    /// The wave's phase when the observation holds it.
    fn wave_phase(&self) -> Option<f64> {
        self.config
            .observes_wave_phase()
            .then(|| self.driver.wave_phase())
    }
}

/// Fails with [`Error::NonFinite`](crate::Error::NonFinite) naming the first non-finite output.
fn finite_output(obs: &[f32], reward: f64, episode_return: f64) -> Result<()> {
    if let Some(i) = obs.iter().position(|v| !v.is_finite()) {
        return Err(crate::Error::NonFinite(format!(
            "observation[{i}] is {} (outside float32's range)",
            obs[i]
        )));
    }
    if !reward.is_finite() || !episode_return.is_finite() {
        return Err(crate::Error::NonFinite(format!(
            "reward {reward}, episode return {episode_return}"
        )));
    }
    Ok(())
}
