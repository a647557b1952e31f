//! The physics trace: the snake's full state after every physics step of the latest reset or env
//! step, for viewers and loggers (an env step may be several physics steps; the observation shows only
//! the last). Recording only reads the world, so an episode with the trace on moves bit for bit as one
//! with it off.

use crate::error::Result;
use crate::robot::Simulation;

/// The state after each physics step of the latest [`SnakeEnv::reset`](super::SnakeEnv::reset) or
/// [`SnakeEnv::step`](super::SnakeEnv::step), when [`SnakeEnv::set_physics_trace`](super::SnakeEnv::set_physics_trace)
/// turned it on. It holds at most one env step's physics steps
/// ([`MAX_PHYSICS_STEPS_PER_ENV_STEP`](crate::limits::MAX_PHYSICS_STEPS_PER_ENV_STEP)), so it stays
/// bounded however long the episode: read it after every call.
///
/// Row `k` of each per-joint vector is `joints` values starting at `k * joints`; of `poses`,
/// `(joints + 1) * 7` values starting at `k * (joints + 1) * 7` for the built-in snake (for a URDF
/// robot, one pose per link, the root first: `poses.len() / len()` values per row).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PhysicsTrace {
    /// Number of joints N.
    pub joints: usize,
    /// Physics steps since the episode's world was built, after each recorded step (the reset's own
    /// step is 1), as [`Snake::steps`](crate::Snake::steps).
    pub steps: Vec<u64>,
    /// Simulated seconds since the world was built, after each recorded step ([`Snake::time`](crate::Snake::time)).
    pub times: Vec<f64>,
    /// Pose of every cube (every link of a robot), the head (base) first: x, y, z (metres), qx, qy,
    /// qz, qw.
    pub poses: Vec<f64>,
    /// Joint angles, radians.
    pub positions: Vec<f64>,
    /// Joint velocities, rad/s.
    pub velocities: Vec<f64>,
    /// Torques the joint motors applied during the step, N m.
    pub torques: Vec<f64>,
    /// The joint targets of the step, radians; NaN where none was set (the reset's physics step).
    pub targets: Vec<f64>,
}

impl PhysicsTrace {
    /// An empty trace of a snake of `joints` joints.
    pub fn new(joints: usize) -> Self {
        PhysicsTrace {
            joints,
            ..PhysicsTrace::default()
        }
    }

    /// Number of recorded physics steps.
    pub fn len(&self) -> usize {
        self.steps.len()
    }

    /// Whether nothing is recorded.
    pub fn is_empty(&self) -> bool {
        self.steps.is_empty()
    }

    /// Forgets every recorded step (keeping the memory).
    pub fn clear(&mut self) {
        self.steps.clear();
        self.times.clear();
        self.poses.clear();
        self.positions.clear();
        self.velocities.clear();
        self.torques.clear();
        self.targets.clear();
    }

    /// Appends the snake's current state, with the targets of the step that led to it (`None`: no
    /// targets were set). Only reads the world.
    pub fn record(&mut self, snake: &dyn Simulation, targets: Option<&[f64]>) -> Result<()> {
        let n = self.joints;
        if snake.joints() != n || targets.is_some_and(|t| t.len() != n) {
            return Err(crate::error::invalid(format!(
                "physics trace of {n} joints given a snake of {} joints",
                snake.joints()
            )));
        }
        let poses = snake.body_poses()?;
        let start = self.positions.len();
        self.positions.resize(start + n, 0.0);
        self.velocities.resize(start + n, 0.0);
        self.torques.resize(start + n, 0.0);
        if let Err(e) = snake.read_joint_states(
            &mut self.positions[start..],
            &mut self.velocities[start..],
            &mut self.torques[start..],
        ) {
            // Keep every row complete.
            self.positions.truncate(start);
            self.velocities.truncate(start);
            self.torques.truncate(start);
            return Err(e);
        }
        for pose in poses {
            let q = pose.orientation.coords;
            let p = pose.position;
            self.poses
                .extend_from_slice(&[p.x, p.y, p.z, q.x, q.y, q.z, q.w]);
        }
        match targets {
            Some(t) => self.targets.extend_from_slice(t),
            None => self.targets.resize(start + n, f64::NAN),
        }
        self.steps.push(snake.steps());
        self.times.push(snake.time());
        Ok(())
    }
}
