//! [`Body`]: the simulated body of a run or an episode, the built-in snake or a URDF robot, driven
//! through [`Simulation`] either way.

use crate::world::{BodyId, World};
use crate::{Robot, Simulation, Snake};

/// A simulated body: the built-in snake of cubes or a URDF robot.
///
/// ```
/// use snake_core::{Body, Preset, Snake, StartPose};
///
/// let config = Preset::Paper.config(3);
/// let mut body = Body::Cubes(Snake::new(&config, StartPose::resting(config.half_extent))?);
/// body.sim_mut().step()?;
/// assert_eq!(body.sim().joints(), 3);
/// assert!(body.snake().is_some() && body.robot().is_none());
/// # Ok::<(), snake_core::Error>(())
/// ```
#[derive(Debug)]
pub enum Body {
    /// The built-in snake.
    Cubes(Snake),
    /// A URDF robot.
    Robot(Robot),
}

impl Body {
    /// The body, whichever it is, to read.
    pub fn sim(&self) -> &dyn Simulation {
        match self {
            Body::Cubes(s) => s,
            Body::Robot(r) => r,
        }
    }

    /// The body, whichever it is, to drive and step.
    pub fn sim_mut(&mut self) -> &mut dyn Simulation {
        match self {
            Body::Cubes(s) => s,
            Body::Robot(r) => r,
        }
    }

    /// The built-in snake, if it is one.
    pub fn snake(&self) -> Option<&Snake> {
        match self {
            Body::Cubes(s) => Some(s),
            Body::Robot(_) => None,
        }
    }

    /// The robot, if it is one.
    pub fn robot(&self) -> Option<&Robot> {
        match self {
            Body::Cubes(_) => None,
            Body::Robot(r) => Some(r),
        }
    }

    /// The body's world.
    pub fn world(&self) -> &World {
        match self {
            Body::Cubes(s) => s.world(),
            Body::Robot(r) => r.world(),
        }
    }

    /// The body's world, mutable.
    pub fn world_mut(&mut self) -> &mut World {
        match self {
            Body::Cubes(s) => s.world_mut(),
            Body::Robot(r) => r.world_mut(),
        }
    }

    /// The body in [`Body::world`].
    pub fn id(&self) -> BodyId {
        match self {
            Body::Cubes(s) => s.body(),
            Body::Robot(r) => r.body(),
        }
    }

    /// The ground's body in [`Body::world`].
    pub fn ground(&self) -> BodyId {
        match self {
            Body::Cubes(s) => s.ground(),
            Body::Robot(r) => r.ground(),
        }
    }

    /// Multiplies the motor force and gains the body is driven with by these factors.
    pub fn scale_motors(&mut self, effort: f64, kp: f64, kd: f64) {
        match self {
            Body::Cubes(s) => s.scale_motors(effort, kp, kd),
            Body::Robot(r) => r.scale_motors(effort, kp, kd),
        }
    }

    /// Sets the current of every water medium the body swims in (m/s, world frame); false when its
    /// world has no water.
    pub fn set_water_current(&mut self, current: nalgebra::Vector3<f64>) -> bool {
        let media = match self {
            Body::Cubes(s) => s.media_mut(),
            Body::Robot(r) => r.media_mut(),
        };
        media.is_some_and(|m| m.set_water_current(current))
    }
}
