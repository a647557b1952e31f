//! The paper's snake in a world of its own: ground plane, gravity, the cube chain and its friction.

use nalgebra::Vector3;

use crate::config::SnakeConfig;
use crate::error::Result;
use crate::math::StartPose;
use crate::media::{MediaState, Primitive};
use crate::world::{BaseState, BodyId, BoxChain, BoxLink, Dynamics, JointState, Pose, World};
use crate::world_file::WorldSpec;

/// A snake on a ground plane, built in the order the reference builds it: plane, gravity, snake
/// (base then links), then friction on the base and on every link.
#[derive(Debug)]
pub struct Snake {
    world: World,
    body: BodyId,
    ground: BodyId,
    config: SnakeConfig,
    steps: u64,
    /// The world file's media acting on the snake; `None` without media (nothing runs then).
    media: Option<MediaState>,
}

impl Snake {
    /// Builds the world and places the snake's base at `start`.
    pub fn new(config: &SnakeConfig, start: StartPose) -> Result<Self> {
        Self::in_world(config, start, &WorldSpec::default())
    }

    /// As [`Snake::new`] on the ground and among the obstacles of `ground` (a world file), built where
    /// the plane is built today: before gravity and the snake.
    pub fn in_world(config: &SnakeConfig, start: StartPose, ground: &WorldSpec) -> Result<Self> {
        config.validate()?;
        start.validate()?;
        let mut world = World::new()?;
        world.set_time_step(config.dt)?;
        let (ground_body, _) = ground.build(&mut world)?;
        world.set_gravity(Vector3::new(0.0, 0.0, config.gravity))?;

        let h = config.half_extent;
        let link = BoxLink {
            mass: config.link_mass,
            position: [0.0, config.link_spacing(), 0.0],
            orientation: [0.0, 0.0, 0.0, 1.0],
            parent: None,
            axis: [0.0, 0.0, 1.0],
        };
        let chain = BoxChain {
            half_extents: [h, h, h],
            base_mass: config.base_mass,
            base_position: [start.x, start.y, start.z],
            base_orientation: start.orientation(),
            links: (0..config.joints)
                .map(|i| BoxLink {
                    parent: i.checked_sub(1),
                    ..link
                })
                .collect(),
        };
        let body = world.add_box_chain(&chain)?;

        let friction = Dynamics {
            lateral_friction: Some(config.lateral_friction),
            anisotropic_friction: Some(config.anisotropic_friction),
            ..Dynamics::default()
        };
        world.change_dynamics(body, None, &friction)?;
        for link in 0..config.joints {
            world.change_dynamics(body, Some(link), &friction)?;
        }
        if let Some(skin) = &config.skin_friction {
            world.set_skin_friction(body, None, skin, SnakeConfig::HEAD_AXIS)?;
            for link in 0..config.joints {
                world.set_skin_friction(body, Some(link), skin, SnakeConfig::HEAD_AXIS)?;
            }
        }
        let cube = vec![Primitive::Box([h, h, h])];
        let media =
            MediaState::for_body(&ground.media, &world, body, &vec![cube; config.joints + 1])?;
        Ok(Snake {
            world,
            body,
            ground: ground_body,
            config: config.clone(),
            steps: 0,
            media,
        })
    }

    /// The configuration the snake was built with.
    pub fn config(&self) -> &SnakeConfig {
        &self.config
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.config.joints
    }

    /// Physics steps taken since construction.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Simulated time since construction, seconds.
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.config.dt
    }

    /// The underlying world, for reads and controls beyond the snake's own.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The underlying world, mutable (other control modes, changed dynamics, more bodies).
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// The snake's body in [`Snake::world`].
    pub fn body(&self) -> BodyId {
        self.body
    }

    /// The ground's body in [`Snake::world`].
    pub fn ground(&self) -> BodyId {
        self.ground
    }

    /// Multiplies the motor force and the position and velocity gains that [`Snake::set_targets`]
    /// drives the joints with (and [`Snake::config`] reports) by these factors.
    pub fn scale_motors(&mut self, effort: f64, kp: f64, kd: f64) {
        self.config.motor_force *= effort;
        self.config.position_gain *= kp;
        self.config.velocity_gain *= kd;
    }

    /// Position control of every joint towards `targets` (radians), with the configured motor force
    /// and gains: pybullet's `setJointMotorControl2(POSITION_CONTROL, targetPosition, force)`.
    pub fn set_targets(&mut self, targets: &[f64]) -> Result<()> {
        if targets.len() != self.config.joints {
            return Err(crate::error::invalid(format!(
                "expected {} joint targets, got {}",
                self.config.joints,
                targets.len()
            )));
        }
        let c = &self.config;
        self.world.set_position_targets(
            self.body,
            targets,
            c.motor_force,
            c.position_gain,
            c.velocity_gain,
        )
    }

    /// One physics step. Fails with [`crate::Error::NonFinite`] if the base or a joint left the finite range.
    pub fn step(&mut self) -> Result<()> {
        if let Some(media) = &mut self.media {
            media.apply(&mut self.world, self.body)?;
        }
        self.world.step()?;
        self.steps += 1;
        self.world.check_finite_base(self.body, self.steps)
    }

    /// The media acting on the snake, when its world has any.
    pub fn media(&self) -> Option<&MediaState> {
        self.media.as_ref()
    }

    /// The media acting on the snake, mutable (randomized physics set the water's current).
    pub fn media_mut(&mut self) -> Option<&mut MediaState> {
        self.media.as_mut()
    }

    /// Pose and velocity of the base (the head cube).
    pub fn base_state(&self) -> Result<BaseState> {
        self.world.base_state(self.body)
    }

    /// Every joint's angle, velocity and motor torque.
    pub fn joint_states(&self) -> Result<Vec<JointState>> {
        self.world.joint_states(self.body)
    }

    /// Joint angles and velocities written into slices of length [`Snake::joints`]; either may be
    /// empty to skip it. Allocation-free, for hot loops.
    pub fn read_joints(&self, positions: &mut [f64], velocities: &mut [f64]) -> Result<()> {
        self.world
            .read_joints(self.body, positions, velocities, &mut [])
    }

    /// Pose of every cube: the base first, then each link.
    pub fn cube_poses(&self) -> Result<Vec<Pose>> {
        let mut poses = vec![self.base_state()?.pose];
        poses.extend(self.world.link_poses(self.body)?);
        Ok(poses)
    }
}
