//! A physics world that behaves as a pybullet 3.2.7 `p.connect(p.DIRECT)` server does.
//!
//! [`World`] owns its Bullet objects and frees them on drop. It exposes the handful of pybullet calls
//! the snake needs (createMultiBody for a plane and for a chain of boxes, changeDynamics,
//! setJointMotorControl2, stepSimulation and the state reads) with pybullet's defaults and semantics.

use std::ptr::NonNull;

use nalgebra::{Quaternion, UnitQuaternion, Vector3};

use crate::error::{check, invalid, Error, Result};
use crate::skin::{SkinAxis, SkinFriction};
use crate::urdf::{Geometry, InertiaSource, Inertial, Joint, JointKind, Origin, UrdfRobot};

/// Index of a body within its [`World`], in creation order (pybullet's body unique id).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BodyId(pub(crate) i32);

impl BodyId {
    /// The body's index in creation order.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// A rigid pose: position and orientation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Position in metres.
    pub position: Vector3<f64>,
    /// Orientation. Stored exactly as Bullet returns it (normalised only to rounding).
    pub orientation: UnitQuaternion<f64>,
}

impl Pose {
    /// Heading: rotation about the world z axis, in radians, of the pose's x axis.
    pub fn yaw(&self) -> f64 {
        self.orientation.euler_angles().2
    }
}

/// State of a body's base: pose of its centre of mass and its velocities, all in the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseState {
    /// Pose of the base's centre of mass (pybullet's `getBasePositionAndOrientation`).
    pub pose: Pose,
    /// Linear velocity in m/s.
    pub linear_velocity: Vector3<f64>,
    /// Angular velocity in rad/s.
    pub angular_velocity: Vector3<f64>,
}

/// State of one joint after the last step (pybullet's `getJointState`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct JointState {
    /// Angle in radians.
    pub position: f64,
    /// Angular velocity in rad/s.
    pub velocity: f64,
    /// Torque the joint motor applied during the last step, in N m.
    pub motor_torque: f64,
}

/// Velocities of a link's centre of mass, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkVelocity {
    /// m/s.
    pub linear: Vector3<f64>,
    /// rad/s.
    pub angular: Vector3<f64>,
}

/// One contact point of a body, from the last step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Link of the queried body (-1 for its base).
    pub link: i32,
    /// The other body, if it is one of this world's multibodies.
    pub other_body: Option<BodyId>,
    /// Link of the other body (-1 for its base).
    pub other_link: i32,
    /// Contact position on the queried body, world frame.
    pub position_on_body: Vector3<f64>,
    /// Contact position on the other object, world frame.
    pub position_on_other: Vector3<f64>,
    /// Contact normal, from the other object towards the queried body.
    pub normal: Vector3<f64>,
    /// Signed distance (negative when penetrating), in metres.
    pub distance: f64,
    /// Normal force of the last step, in newtons.
    pub normal_force: f64,
}

/// How a joint motor is driven (pybullet's control modes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointControl {
    /// `POSITION_CONTROL`: a PD servo on angle and velocity, limited to `max_force`.
    Position {
        /// Target angle, radians.
        target: f64,
        /// Target velocity, rad/s (pybullet's default 0).
        target_velocity: f64,
        /// Largest torque the motor may apply, N m.
        max_force: f64,
        /// Position gain (pybullet's default 0.1).
        kp: f64,
        /// Velocity gain (pybullet's default 1.0).
        kd: f64,
        /// Clamp on the motor's target velocity; `None` leaves it as it was (unclamped by default).
        max_velocity: Option<f64>,
    },
    /// `VELOCITY_CONTROL`: drive to a velocity, limited to `max_force`.
    Velocity {
        /// Target velocity, rad/s.
        target_velocity: f64,
        /// Largest torque the motor may apply, N m (0 switches the motor off).
        max_force: f64,
        /// Velocity gain (pybullet's default 1.0).
        kd: f64,
    },
    /// `TORQUE_CONTROL`: add this torque (N m) during the next step. The default motors stay active
    /// until switched off with `Velocity { max_force: 0.0, .. }`, as in pybullet.
    Torque(f64),
}

impl JointControl {
    /// Position control with pybullet's default gains (kp 0.1, kd 1.0) and target velocity 0.
    pub fn position(target: f64, max_force: f64) -> Self {
        JointControl::Position {
            target,
            target_velocity: 0.0,
            max_force,
            kp: 0.1,
            kd: 1.0,
            max_velocity: None,
        }
    }
}

/// pybullet `changeDynamics` arguments; `None` leaves a property as it is.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Dynamics {
    /// Coulomb friction coefficient (multiplied with the other object's).
    pub lateral_friction: Option<f64>,
    /// Torsional friction about the contact normal.
    pub spinning_friction: Option<f64>,
    /// Rolling friction.
    pub rolling_friction: Option<f64>,
    /// Coefficient of restitution.
    pub restitution: Option<f64>,
    /// Per-axis scaling of friction in the link's own frame.
    pub anisotropic_friction: Option<[f64; 3]>,
    /// Friction anchors (contact points keep their anchor while static).
    pub friction_anchor: Option<bool>,
    /// Viscous joint damping, N m s/rad (links only).
    pub joint_damping: Option<f64>,
    /// Linear damping of the whole body (Bullet default 0.04).
    pub linear_damping: Option<f64>,
    /// Angular damping of the whole body (Bullet default 0.04).
    pub angular_damping: Option<f64>,
}

/// What `getDynamicsInfo` reports of a body part, in part: [`World::dynamics_info`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicsInfo {
    /// Mass, kg (0: a fixed base or a massless link).
    pub mass: f64,
    /// Lateral (Coulomb) friction coefficient.
    pub lateral_friction: f64,
    /// Local inertia diagonal, kg m^2.
    pub inertia: [f64; 3],
}

/// The collision shape of a static body (pybullet's `createCollisionShape` types a world file uses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StaticShape<'a> {
    /// `GEOM_PLANE`: the plane z = 0 of the body's frame.
    Plane,
    /// `GEOM_BOX` with `halfExtents`.
    Box {
        /// Half extents, metres.
        half_extents: [f64; 3],
    },
    /// `GEOM_SPHERE`.
    Sphere {
        /// Radius, metres.
        radius: f64,
    },
    /// `GEOM_CYLINDER` (axis along z).
    Cylinder {
        /// Radius, metres.
        radius: f64,
        /// Full height, metres.
        height: f64,
    },
    /// `GEOM_HEIGHTFIELD` with `heightfieldData`: `rows` values along x per grid line
    /// (`numHeightfieldRows`), `columns` lines along y (`numHeightfieldColumns`), `heights[y * rows + x]`,
    /// float32 as pybullet's client sends them; `scale` is `meshScale`. Bullet centres the grid on the
    /// body's origin, vertically at the middle of the lowest and highest sample.
    Heightfield {
        /// Values per grid line.
        rows: usize,
        /// Grid lines.
        columns: usize,
        /// The samples, `rows * columns` of them.
        heights: &'a [f32],
        /// `meshScale`: grid spacing in x and y, and the height factor, metres.
        scale: [f64; 3],
    },
}

/// A tree of equal boxes joined by revolute joints, as pybullet's `createMultiBody` makes it from one
/// `GEOM_BOX` collision shape. Inertial frames are the link frames.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxChain {
    /// Box half extents, metres.
    pub half_extents: [f64; 3],
    /// Base mass in kg; 0 fixes the base in place.
    pub base_mass: f64,
    /// Base pose in the world.
    pub base_position: [f64; 3],
    /// Base orientation as (x, y, z, w).
    pub base_orientation: [f64; 4],
    /// The links, in pybullet's order.
    pub links: Vec<BoxLink>,
}

/// One link of a [`BoxChain`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoxLink {
    /// Mass in kg.
    pub mass: f64,
    /// Joint frame position in the parent link's frame.
    pub position: [f64; 3],
    /// Joint frame orientation (x, y, z, w) in the parent link's frame.
    pub orientation: [f64; 4],
    /// Parent: `None` for the base, `Some(k)` for link k (which must come earlier).
    pub parent: Option<usize>,
    /// Revolute joint axis in the link frame.
    pub axis: [f64; 3],
}

/// A Bullet world set up as pybullet sets one up.
///
/// A new world has no bodies, gravity 0 (as pybullet's) and a time step of 1/240 s.
pub struct World {
    raw: NonNull<bullet_sys::ss_world>,
    time_step: f64,
    /// Gravity as last set, m/s^2 (zero until [`World::set_gravity`]): the one value the media's
    /// buoyancy reads, so that it always works against the gravity the bodies fall under.
    gravity: Vector3<f64>,
    /// Joint count per body, to size reads without crossing the boundary.
    joints: Vec<usize>,
}

// SAFETY: a World exclusively owns its Bullet objects, which reference no other world's; the shim
// replaces Bullet's process-wide profiler hooks with no-ops and sets its one global (gDbvtMargin) to a
// constant before the first world exists, so a World may move to another thread.
unsafe impl Send for World {}

impl Drop for World {
    fn drop(&mut self) {
        // SAFETY: raw came from ss_world_new and is freed exactly once, here.
        unsafe { bullet_sys::ss_world_free(self.raw.as_ptr()) }
    }
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("time_step", &self.time_step)
            .field("bodies", &self.joints.len())
            .finish()
    }
}

fn finite(values: &[f64], what: &str) -> Result<()> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(invalid(format!("{what} must be finite")))
    }
}

impl World {
    /// An empty world as `p.connect(p.DIRECT)` creates it.
    pub fn new() -> Result<Self> {
        // SAFETY: ss_world_new has no preconditions; a null return is an allocation failure.
        let raw = unsafe { bullet_sys::ss_world_new() };
        let raw = NonNull::new(raw).ok_or_else(|| Error::Engine {
            code: bullet_sys::SS_ERR_EXCEPTION,
            message: "could not create a Bullet world".into(),
        })?;
        Ok(World {
            raw,
            time_step: 1.0 / 240.0,
            gravity: Vector3::zeros(),
            joints: Vec::new(),
        })
    }

    fn ptr(&self) -> *mut bullet_sys::ss_world {
        self.raw.as_ptr()
    }

    /// `setGravity`.
    pub fn set_gravity(&mut self, gravity: Vector3<f64>) -> Result<()> {
        finite(gravity.as_slice(), "gravity")?;
        // SAFETY: self.ptr() is a live world owned by self.
        check(unsafe {
            bullet_sys::ss_world_set_gravity(self.ptr(), gravity.x, gravity.y, gravity.z)
        })?;
        self.gravity = gravity;
        Ok(())
    }

    /// Gravity as last set by [`World::set_gravity`], m/s^2, world frame (zero before).
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }

    /// `setTimeStep`: seconds per [`World::step`].
    pub fn set_time_step(&mut self, dt: f64) -> Result<()> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(invalid(format!(
                "time step must be positive and finite, got {dt}"
            )));
        }
        // SAFETY: live world owned by self.
        check(unsafe { bullet_sys::ss_world_set_time_step(self.ptr(), dt) })?;
        self.time_step = dt;
        Ok(())
    }

    /// Seconds per step.
    pub fn time_step(&self) -> f64 {
        self.time_step
    }

    /// Adds the ground: `createMultiBody(0, createCollisionShape(GEOM_PLANE))`, the plane z = 0.
    pub fn add_plane(&mut self) -> Result<BodyId> {
        let mut id = 0;
        // SAFETY: live world; id is a valid out pointer.
        check(unsafe { bullet_sys::ss_world_add_plane(self.ptr(), &mut id) })?;
        self.joints.push(0);
        Ok(BodyId(id))
    }

    /// Adds a static body: `createMultiBody(0, createCollisionShape(shape), -1, position, orientation)`
    /// with the orientation as (x, y, z, w).
    pub fn add_static(
        &mut self,
        shape: &StaticShape<'_>,
        position: [f64; 3],
        orientation: [f64; 4],
    ) -> Result<BodyId> {
        finite(&position, "static body position")?;
        finite(&orientation, "static body orientation")?;
        let mut desc = bullet_sys::ss_static_desc {
            type_: 0,
            size: [0.0; 3],
            position,
            orientation,
            rows: 0,
            columns: 0,
            heights: std::ptr::null(),
        };
        let positive = |v: &[f64], what: &str| -> Result<()> {
            if v.iter().all(|x| x.is_finite() && *x > 0.0) {
                Ok(())
            } else {
                Err(invalid(format!(
                    "{what} must be positive and finite, got {v:?}"
                )))
            }
        };
        match *shape {
            StaticShape::Plane => desc.type_ = bullet_sys::SS_GEOM_PLANE as i32,
            StaticShape::Box { half_extents } => {
                positive(&half_extents, "box half extents")?;
                desc.type_ = bullet_sys::SS_GEOM_BOX as i32;
                desc.size = half_extents;
            }
            StaticShape::Sphere { radius } => {
                positive(&[radius], "sphere radius")?;
                desc.type_ = bullet_sys::SS_GEOM_SPHERE as i32;
                desc.size = [radius, 0.0, 0.0];
            }
            StaticShape::Cylinder { radius, height } => {
                positive(&[radius, height], "cylinder radius and height")?;
                desc.type_ = bullet_sys::SS_GEOM_CYLINDER as i32;
                desc.size = [radius, height, 0.0];
            }
            StaticShape::Heightfield {
                rows,
                columns,
                heights,
                scale,
            } => {
                positive(&scale, "heightfield scale")?;
                if rows < 2 || columns < 2 || rows.checked_mul(columns) != Some(heights.len()) {
                    return Err(invalid(format!(
                        "a heightfield of {rows} x {columns} needs rows, columns >= 2 and that many \
                         heights, got {}",
                        heights.len()
                    )));
                }
                desc.type_ = bullet_sys::SS_GEOM_HEIGHTFIELD as i32;
                desc.size = scale;
                desc.rows = i32::try_from(rows).map_err(|_| invalid("heightfield too large"))?;
                desc.columns =
                    i32::try_from(columns).map_err(|_| invalid("heightfield too large"))?;
                desc.heights = heights.as_ptr();
            }
        }
        let mut id = 0;
        // SAFETY: live world; desc.heights (when set) addresses rows * columns floats that outlive the
        // call (the shim copies them).
        check(unsafe { bullet_sys::ss_world_add_static(self.ptr(), &desc, &mut id) })?;
        self.joints.push(0);
        Ok(BodyId(id))
    }

    /// Adds a tree of boxes (see [`BoxChain`]) with pybullet's default joint motors.
    pub fn add_box_chain(&mut self, chain: &BoxChain) -> Result<BodyId> {
        let n = chain.links.len();
        let mut masses = Vec::with_capacity(n);
        let mut positions = Vec::with_capacity(3 * n);
        let mut orientations = Vec::with_capacity(4 * n);
        let mut parents = Vec::with_capacity(n);
        let mut axes = Vec::with_capacity(3 * n);
        for (i, link) in chain.links.iter().enumerate() {
            let parent = match link.parent {
                None => 0,
                Some(p) if p < i => p as i32 + 1,
                Some(p) => {
                    return Err(invalid(format!(
                        "link {i} has parent {p}, which is not an earlier link"
                    )))
                }
            };
            masses.push(link.mass);
            positions.extend_from_slice(&link.position);
            orientations.extend_from_slice(&link.orientation);
            parents.push(parent);
            axes.extend_from_slice(&link.axis);
        }
        let num_links = i32::try_from(n).map_err(|_| invalid("too many links"))?;
        let desc = bullet_sys::ss_chain_desc {
            half_extents: chain.half_extents,
            base_mass: chain.base_mass,
            base_position: chain.base_position,
            base_orientation: chain.base_orientation,
            num_links,
            link_masses: masses.as_ptr(),
            link_positions: positions.as_ptr(),
            link_orientations: orientations.as_ptr(),
            link_parents: parents.as_ptr(),
            link_axes: axes.as_ptr(),
        };
        let mut id = 0;
        // SAFETY: live world; desc's arrays hold num_links entries each and outlive the call.
        check(unsafe { bullet_sys::ss_world_add_box_chain(self.ptr(), &desc, &mut id) })?;
        self.joints.push(n);
        Ok(BodyId(id))
    }

    /// `loadURDF(robot, basePosition, baseOrientation)` with default flags, or with
    /// `URDF_USE_INERTIA_FROM_FILE` for [`InertiaSource::File`]: the multibody as pybullet's importer
    /// builds it, then pybullet's default motors on every revolute, continuous and prismatic joint.
    /// `position` and `orientation` (x, y, z, w) place the root link's frame.
    pub fn add_urdf(
        &mut self,
        robot: &UrdfRobot,
        position: [f64; 3],
        orientation: [f64; 4],
        inertia: InertiaSource,
    ) -> Result<BodyId> {
        finite(&position, "base position")?;
        finite(&orientation, "base orientation")?;
        robot.check_inertia(inertia)?;
        let origin = |o: &Origin| bullet_sys::ss_urdf_origin {
            xyz: o.xyz,
            rpy: o.rpy.unwrap_or([0.0; 3]),
            has_rpy: o.rpy.is_some() as i32,
        };
        let shapes: Vec<Vec<bullet_sys::ss_urdf_shape>> = robot
            .links
            .iter()
            .map(|l| {
                l.collisions
                    .iter()
                    .map(|c| {
                        let (kind, size) = match c.geometry {
                            Geometry::Box(s) => (bullet_sys::SS_SHAPE_BOX, s),
                            Geometry::Sphere(r) => (bullet_sys::SS_SHAPE_SPHERE, [r, 0.0, 0.0]),
                            Geometry::Cylinder { radius, length } => {
                                (bullet_sys::SS_SHAPE_CYLINDER, [radius, length, 0.0])
                            }
                            Geometry::Capsule { radius, length } => {
                                (bullet_sys::SS_SHAPE_CAPSULE, [radius, length, 0.0])
                            }
                        };
                        bullet_sys::ss_urdf_shape {
                            type_: kind as i32,
                            size,
                            origin: origin(&c.origin),
                        }
                    })
                    .collect()
            })
            .collect();
        let mut links = Vec::with_capacity(robot.links.len());
        for (k, (link, shapes)) in robot.links.iter().zip(&shapes).enumerate() {
            let parent = match (k, link.parent) {
                (0, None) => -1,
                (k, Some(p)) if p < k => p as i32,
                _ => {
                    return Err(invalid(format!(
                        "{}: links are not in depth-first order",
                        robot.shown()
                    )))
                }
            };
            // UrdfParser: a link without <inertial> has mass 1, inertia diagonal 1, identity frame.
            let inertial = link.inertial.unwrap_or(Inertial {
                origin: Origin::default(),
                mass: 1.0,
                inertia: [1.0, 0.0, 0.0, 1.0, 0.0, 1.0],
            });
            let c = &link.contact;
            let mut flags = 0u32;
            let mut set = |v: Option<f64>, flag: u32| {
                if v.is_some() {
                    flags |= flag;
                }
                v.unwrap_or(0.0)
            };
            let rolling = set(c.rolling_friction, bullet_sys::SS_CONTACT_ROLLING_FRICTION);
            let spinning = set(
                c.spinning_friction,
                bullet_sys::SS_CONTACT_SPINNING_FRICTION,
            );
            let restitution = set(c.restitution, bullet_sys::SS_CONTACT_RESTITUTION);
            let scaling = set(c.inertia_scaling, bullet_sys::SS_CONTACT_INERTIA_SCALING);
            if c.stiffness.is_some() || c.damping.is_some() {
                flags |= bullet_sys::SS_CONTACT_STIFFNESS_DAMPING;
            }
            if c.friction_anchor {
                flags |= bullet_sys::SS_CONTACT_FRICTION_ANCHOR;
            }
            let joint = link.joint.as_ref();
            let joint_type = match joint.map(|j| j.kind) {
                None | Some(JointKind::Fixed) => bullet_sys::SS_JOINT_FIXED,
                Some(JointKind::Revolute) => bullet_sys::SS_JOINT_REVOLUTE,
                Some(JointKind::Continuous) => bullet_sys::SS_JOINT_CONTINUOUS,
                Some(JointKind::Prismatic) => bullet_sys::SS_JOINT_PRISMATIC,
            };
            let j = |f: fn(&Joint) -> f64| joint.map_or(0.0, f);
            links.push(bullet_sys::ss_urdf_link {
                parent,
                mass: inertial.mass,
                inertial_origin: origin(&inertial.origin),
                inertia: inertial.inertia,
                num_shapes: shapes.len() as i32,
                shapes: shapes.as_ptr(),
                has_collision_group: link.collision_group.is_some() as i32,
                collision_group: link.collision_group.unwrap_or(0),
                has_collision_mask: link.collision_mask.is_some() as i32,
                collision_mask: link.collision_mask.unwrap_or(0),
                contact: bullet_sys::ss_urdf_contact {
                    flags: flags as i32,
                    lateral_friction: c.lateral_friction.unwrap_or(0.5),
                    rolling_friction: rolling,
                    spinning_friction: spinning,
                    restitution,
                    inertia_scaling: scaling,
                    stiffness: c.stiffness.unwrap_or(1e4),
                    damping: c.damping.unwrap_or(1.0),
                },
                joint_type: joint_type as i32,
                joint_origin: origin(&joint.map(|j| j.origin).unwrap_or_default()),
                axis: joint.map_or([1.0, 0.0, 0.0], |j| j.axis),
                lower: j(|j| j.lower),
                upper: j(|j| j.upper),
                effort: j(|j| j.effort),
                velocity: j(|j| j.velocity),
                damping: j(|j| j.damping),
                friction: j(|j| j.friction),
            });
        }
        let num_links = i32::try_from(links.len()).map_err(|_| invalid("too many links"))?;
        let desc = bullet_sys::ss_urdf_desc {
            num_links,
            links: links.as_ptr(),
            base_position: position,
            base_orientation: orientation,
            inertia_from_file: (inertia == InertiaSource::File) as i32,
        };
        let mut id = 0;
        // SAFETY: live world; desc, links and every shapes vector outlive the call, with the counts given.
        check(unsafe { bullet_sys::ss_world_add_urdf(self.ptr(), &desc, &mut id) })?;
        self.joints.push(links.len() - 1);
        Ok(BodyId(id))
    }

    /// `setJointMotorControlArray(body, joints, POSITION_CONTROL, targetPositions=targets,
    /// forces=forces, positionGains=[kp]*n, velocityGains=[kd]*n)`: each of `joints` must be a revolute,
    /// continuous or prismatic joint.
    ///
    /// `max_velocities`, one per joint, makes it `setJointMotorControl2(body, joint, POSITION_CONTROL,
    /// ..., maxVelocity=v)` on each joint instead (the array call has no `maxVelocity`): a `v > 0`
    /// clamps the motor's target velocity to `[-v, v]` (rad/s, m/s for a prismatic joint), 0 leaves that
    /// joint's clamp as it is, as pybullet treats a `maxVelocity` that is not > 0. `None` is the array
    /// call, bit for bit.
    #[allow(clippy::too_many_arguments)] // pybullet's own argument list, one slice or gain each
    pub fn set_position_targets_at(
        &mut self,
        body: BodyId,
        joints: &[i32],
        targets: &[f64],
        forces: &[f64],
        kp: f64,
        kd: f64,
        max_velocities: Option<&[f64]>,
    ) -> Result<()> {
        self.joint_count(body)?;
        let n = joints.len();
        if targets.len() != n || forces.len() != n || max_velocities.is_some_and(|v| v.len() != n) {
            return Err(invalid(format!(
                "{n} joints, {} targets, {} forces and {} maximum velocities",
                targets.len(),
                forces.len(),
                max_velocities.map_or(n, <[f64]>::len)
            )));
        }
        finite(targets, "joint targets")?;
        finite(forces, "motor forces")?;
        finite(&[kp, kd], "motor gains")?;
        if let Some(v) = max_velocities {
            if let Some(bad) = v.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                return Err(invalid(format!(
                    "maximum joint velocities must be finite and >= 0, got {bad}"
                )));
            }
        }
        let max_velocities = max_velocities.map_or(std::ptr::null(), <[f64]>::as_ptr);
        // SAFETY: live world; the three slices hold n values each, and max_velocities is null or
        // addresses n values too.
        check(unsafe {
            bullet_sys::ss_set_position_targets_at(
                self.ptr(),
                body.0,
                n as i32,
                joints.as_ptr(),
                targets.as_ptr(),
                forces.as_ptr(),
                kp,
                kd,
                max_velocities,
            )
        })
    }

    /// Angles, velocities and motor torques of the given joints (`getJointStates(body, joints)`),
    /// written into slices as long as `joints` (an empty slice skips that quantity).
    pub fn read_joints_at(
        &self,
        body: BodyId,
        joints: &[i32],
        positions: &mut [f64],
        velocities: &mut [f64],
        torques: &mut [f64],
    ) -> Result<()> {
        self.joint_count(body)?;
        let n = joints.len();
        let (p, v, t) = (
            out_slice(positions, n, "positions")?,
            out_slice(velocities, n, "velocities")?,
            out_slice(torques, n, "torques")?,
        );
        // SAFETY: live world; joints holds n indices and every non-null pointer addresses n f64.
        check(unsafe {
            bullet_sys::ss_get_joint_states_at(
                self.ptr(),
                body.0,
                n as i32,
                joints.as_ptr(),
                p,
                v,
                t,
            )
        })
    }

    fn joint_count(&self, body: BodyId) -> Result<usize> {
        self.joints
            .get(body.index())
            .copied()
            .ok_or_else(|| invalid(format!("no body {}", body.0)))
    }

    /// Number of joints (= links) of a body.
    pub fn num_joints(&self, body: BodyId) -> Result<usize> {
        self.joint_count(body)
    }

    /// `changeDynamics(body, link, ...)`; `link` `None` is the base.
    pub fn change_dynamics(
        &mut self,
        body: BodyId,
        link: Option<usize>,
        dynamics: &Dynamics,
    ) -> Result<()> {
        let unset = -1.0;
        let nonneg = |v: Option<f64>, what: &str| -> Result<f64> {
            match v {
                None => Ok(unset),
                Some(x) if x.is_finite() && x >= 0.0 => Ok(x),
                Some(x) => Err(invalid(format!("{what} must be finite and >= 0, got {x}"))),
            }
        };
        let raw = bullet_sys::ss_dynamics {
            lateral_friction: nonneg(dynamics.lateral_friction, "lateral friction")?,
            spinning_friction: nonneg(dynamics.spinning_friction, "spinning friction")?,
            rolling_friction: nonneg(dynamics.rolling_friction, "rolling friction")?,
            restitution: nonneg(dynamics.restitution, "restitution")?,
            linear_damping: nonneg(dynamics.linear_damping, "linear damping")?,
            angular_damping: nonneg(dynamics.angular_damping, "angular damping")?,
            joint_damping: nonneg(dynamics.joint_damping, "joint damping")?,
            has_anisotropic_friction: dynamics.anisotropic_friction.is_some() as i32,
            anisotropic_friction: match dynamics.anisotropic_friction {
                Some(a) => {
                    finite(&a, "anisotropic friction")?;
                    a
                }
                None => [1.0; 3],
            },
            friction_anchor: dynamics.friction_anchor.map_or(-1, i32::from),
        };
        let link = match link {
            None => -1,
            Some(l) if l < self.joint_count(body)? => l as i32,
            Some(l) => return Err(invalid(format!("body {} has no link {l}", body.0))),
        };
        // SAFETY: live world; raw is a valid struct for the duration of the call.
        check(unsafe { bullet_sys::ss_change_dynamics(self.ptr(), body.0, link, &raw) })
    }

    fn link_index(&self, body: BodyId, link: Option<usize>) -> Result<i32> {
        match link {
            None => {
                self.joint_count(body)?;
                Ok(-1)
            }
            Some(l) if l < self.joint_count(body)? => Ok(l as i32),
            Some(l) => Err(invalid(format!("body {} has no link {l}", body.0))),
        }
    }

    /// `changeDynamics(body, link, mass=mass)` (`link` `None`: the base): the part's mass, and its
    /// local inertia recomputed from its collision shape as pybullet does (an inertia read from a URDF
    /// file is replaced, as in pybullet). `mass` must be finite and > 0 and the part dynamic (a fixed
    /// base or a massless link is refused).
    pub fn set_mass(&mut self, body: BodyId, link: Option<usize>, mass: f64) -> Result<()> {
        let link = self.link_index(body, link)?;
        if !(mass.is_finite() && mass > 0.0) {
            return Err(invalid(format!("mass must be finite and > 0, got {mass}")));
        }
        // SAFETY: live world; body and link checked above (the shim checks them again).
        check(unsafe { bullet_sys::ss_set_mass(self.ptr(), body.0, link, mass) })
    }

    /// `getDynamicsInfo(body, link)`'s mass, lateral friction and local inertia diagonal (`link`
    /// `None`: the base).
    pub fn dynamics_info(&self, body: BodyId, link: Option<usize>) -> Result<DynamicsInfo> {
        let link = self.link_index(body, link)?;
        let (mut mass, mut lateral_friction, mut inertia) = (0.0, 0.0, [0.0; 3]);
        // SAFETY: live world; the three out-pointers address one, one and three f64.
        check(unsafe {
            bullet_sys::ss_get_dynamics_info(
                self.ptr(),
                body.0,
                link,
                &mut mass,
                &mut lateral_friction,
                inertia.as_mut_ptr(),
            )
        })?;
        Ok(DynamicsInfo {
            mass,
            lateral_friction,
            inertia,
        })
    }

    /// Multiplies the skin friction coefficients of a link (`None`: the base) by `factor` (finite,
    /// >= 0); returns whether the link has skin friction (nothing changes if not).
    pub fn scale_skin_friction(
        &mut self,
        body: BodyId,
        link: Option<usize>,
        factor: f64,
    ) -> Result<bool> {
        let link = self.link_index(body, link)?;
        if !(factor.is_finite() && factor >= 0.0) {
            return Err(invalid(format!(
                "skin friction scale must be finite and >= 0, got {factor}"
            )));
        }
        let mut had = 0;
        // SAFETY: live world; had is one i32 for the duration of the call.
        check(unsafe {
            bullet_sys::ss_scale_skin_friction(self.ptr(), body.0, link, factor, &mut had)
        })?;
        Ok(had != 0)
    }

    /// Skin friction on a link (`None`: the base), with `default_axis` where the skin names none: Hu
    /// et al.'s forward/backward/transverse law in place of the link's lateral and anisotropic friction
    /// (see [`SkinFriction`]). Not a pybullet call; a world without it keeps pybullet parity.
    pub fn set_skin_friction(
        &mut self,
        body: BodyId,
        link: Option<usize>,
        skin: &SkinFriction,
        default_axis: SkinAxis,
    ) -> Result<()> {
        skin.validate("skin friction")?;
        let link = match link {
            None => -1,
            Some(l) if l < self.joint_count(body)? => l as i32,
            Some(l) => return Err(invalid(format!("body {} has no link {l}", body.0))),
        };
        let axis = skin.axis_vector(default_axis);
        // SAFETY: live world; axis holds three f64 for the duration of the call.
        check(unsafe {
            bullet_sys::ss_set_skin_friction(
                self.ptr(),
                body.0,
                link,
                skin.forward,
                skin.backward,
                skin.transverse,
                axis.as_ptr(),
            )
        })
    }

    /// `setJointMotorControl2` on one joint.
    pub fn set_joint_control(
        &mut self,
        body: BodyId,
        joint: usize,
        control: JointControl,
    ) -> Result<()> {
        if joint >= self.joint_count(body)? {
            return Err(invalid(format!("body {} has no joint {joint}", body.0)));
        }
        let (mode, pos, vel, force, kp, kd, max_vel) = match control {
            JointControl::Position {
                target,
                target_velocity,
                max_force,
                kp,
                kd,
                max_velocity,
            } => (
                bullet_sys::SS_POSITION_CONTROL,
                target,
                target_velocity,
                max_force,
                kp,
                kd,
                max_velocity.unwrap_or(-1.0),
            ),
            JointControl::Velocity {
                target_velocity,
                max_force,
                kd,
            } => (
                bullet_sys::SS_VELOCITY_CONTROL,
                0.0,
                target_velocity,
                max_force,
                0.0,
                kd,
                -1.0,
            ),
            JointControl::Torque(t) => (bullet_sys::SS_TORQUE_CONTROL, 0.0, 0.0, t, 0.0, 0.0, -1.0),
        };
        finite(&[pos, vel, force, kp, kd, max_vel], "joint control values")?;
        // SAFETY: live world; joint index checked above.
        check(unsafe {
            bullet_sys::ss_set_joint_motor(
                self.ptr(),
                body.0,
                joint as i32,
                mode as i32,
                pos,
                vel,
                force,
                kp,
                kd,
                max_vel,
            )
        })
    }

    /// Position control with target velocity 0 on joints `0..targets.len()`, in one call: the same
    /// effect as [`World::set_joint_control`] with [`JointControl::Position`] on each joint.
    pub fn set_position_targets(
        &mut self,
        body: BodyId,
        targets: &[f64],
        max_force: f64,
        kp: f64,
        kd: f64,
    ) -> Result<()> {
        let n = self.joint_count(body)?;
        if targets.len() > n {
            return Err(invalid(format!("{} targets for {n} joints", targets.len())));
        }
        finite(targets, "joint targets")?;
        finite(&[max_force, kp, kd], "motor force and gains")?;
        // SAFETY: live world; targets holds targets.len() values.
        check(unsafe {
            bullet_sys::ss_set_position_targets(
                self.ptr(),
                body.0,
                targets.len() as i32,
                targets.as_ptr(),
                max_force,
                kp,
                kd,
            )
        })
    }

    /// `stepSimulation()`: one step of [`World::time_step`] seconds.
    pub fn step(&mut self) -> Result<()> {
        // SAFETY: live world owned by self.
        check(unsafe { bullet_sys::ss_world_step(self.ptr()) })
    }

    /// The body's base pose is finite after physics step `step` (counted by the caller), or the
    /// simulation blew up: [`Error::NonFinite`], and the world should be discarded.
    pub fn check_finite_base(&self, body: BodyId, step: u64) -> Result<()> {
        let base = self.base_state(body)?;
        let finite = base.pose.position.iter().all(|v| v.is_finite())
            && base.pose.orientation.coords.iter().all(|v| v.is_finite());
        if finite {
            Ok(())
        } else {
            Err(Error::NonFinite(format!(
                "base pose after step {step} is {:?}",
                base.pose
            )))
        }
    }

    /// The base's pose and velocity.
    pub fn base_state(&self, body: BodyId) -> Result<BaseState> {
        self.joint_count(body)?;
        let mut raw = bullet_sys::ss_base_state::default();
        // SAFETY: live world; raw is a valid out struct.
        check(unsafe { bullet_sys::ss_get_base_state(self.ptr(), body.0, &mut raw) })?;
        let [x, y, z, w] = raw.orientation;
        Ok(BaseState {
            pose: Pose {
                position: Vector3::from(raw.position),
                // Bullet's quaternion is kept bit for bit, not renormalised.
                orientation: UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z)),
            },
            linear_velocity: Vector3::from(raw.linear_velocity),
            angular_velocity: Vector3::from(raw.angular_velocity),
        })
    }

    /// Angles, velocities and motor torques of every joint, written into the given slices, which must
    /// each be as long as the body has joints (pass an empty slice to skip one).
    pub fn read_joints(
        &self,
        body: BodyId,
        positions: &mut [f64],
        velocities: &mut [f64],
        torques: &mut [f64],
    ) -> Result<()> {
        let n = self.joint_count(body)?;
        let (p, v, t) = (
            out_slice(positions, n, "positions")?,
            out_slice(velocities, n, "velocities")?,
            out_slice(torques, n, "torques")?,
        );
        // SAFETY: live world; every non-null pointer addresses n writable f64.
        check(unsafe { bullet_sys::ss_get_joint_states(self.ptr(), body.0, n as i32, p, v, t) })
    }

    /// Every joint's state.
    pub fn joint_states(&self, body: BodyId) -> Result<Vec<JointState>> {
        let n = self.joint_count(body)?;
        let (mut p, mut v, mut t) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        self.read_joints(body, &mut p, &mut v, &mut t)?;
        Ok((0..n)
            .map(|j| JointState {
                position: p[j],
                velocity: v[j],
                motor_torque: t[j],
            })
            .collect())
    }

    /// World pose of every link's centre of mass (the base not included).
    pub fn link_poses(&self, body: BodyId) -> Result<Vec<Pose>> {
        let n = self.joint_count(body)?;
        let mut raw = vec![0.0; 7 * n];
        // SAFETY: live world; raw holds 7 * n writable f64.
        check(unsafe {
            bullet_sys::ss_get_link_poses(self.ptr(), body.0, n as i32, raw.as_mut_ptr())
        })?;
        Ok(poses_from_shim(&raw))
    }

    /// Poses of a link's collision shapes in its centre-of-mass frame (`link` `None`: the base), in
    /// the order of the URDF's `<collision>` elements: for drawing.
    pub fn shape_poses(&self, body: BodyId, link: Option<usize>) -> Result<Vec<Pose>> {
        let n = self.joint_count(body)?;
        let link = match link {
            None => -1,
            Some(l) if l < n => l as i32,
            Some(l) => return Err(invalid(format!("body {} has no link {l}", body.0))),
        };
        let mut count = 0;
        // SAFETY: live world; capacity 0 with a null buffer only counts.
        check(unsafe {
            bullet_sys::ss_get_shape_poses(
                self.ptr(),
                body.0,
                link,
                std::ptr::null_mut(),
                0,
                &mut count,
            )
        })?;
        let mut raw = vec![0.0; 7 * count.max(0) as usize];
        // SAFETY: raw has room for `count` poses.
        check(unsafe {
            bullet_sys::ss_get_shape_poses(
                self.ptr(),
                body.0,
                link,
                raw.as_mut_ptr(),
                count,
                &mut count,
            )
        })?;
        Ok(poses_from_shim(&raw))
    }

    /// World-frame velocities of each link's centre of mass (pybullet's `getLinkState` with
    /// `computeLinkVelocity=1`): linear in m/s, angular in rad/s, for links 0..n.
    pub fn link_velocities(&self, body: BodyId) -> Result<Vec<LinkVelocity>> {
        let n = self.joint_count(body)?;
        let mut raw = vec![0.0; 6 * n];
        // SAFETY: live world; raw holds 6 * n writable f64.
        check(unsafe {
            bullet_sys::ss_get_link_velocities(self.ptr(), body.0, n as i32, raw.as_mut_ptr())
        })?;
        Ok(raw
            .chunks_exact(6)
            .map(|v| LinkVelocity {
                linear: Vector3::new(v[0], v[1], v[2]),
                angular: Vector3::new(v[3], v[4], v[5]),
            })
            .collect())
    }

    /// `applyExternalForce(..., flags=WORLD_FRAME)`: `force` (N) at the world point `position`, on a link
    /// (`None`: the base), acting during the next [`World::step`] only.
    pub fn apply_external_force(
        &mut self,
        body: BodyId,
        link: Option<usize>,
        force: Vector3<f64>,
        position: Vector3<f64>,
    ) -> Result<()> {
        let link = self.link_index(body, link)?;
        finite(force.as_slice(), "external force")?;
        finite(position.as_slice(), "external force position")?;
        let (f, p): ([f64; 3], [f64; 3]) = (force.into(), position.into());
        // SAFETY: live world; f and p are 3 readable f64 each.
        check(unsafe {
            bullet_sys::ss_apply_external_force(self.ptr(), body.0, link, f.as_ptr(), p.as_ptr())
        })
    }

    /// `applyExternalTorque(..., flags=WORLD_FRAME)` on a link (`None`: the base), for the next step only.
    pub fn apply_external_torque(
        &mut self,
        body: BodyId,
        link: Option<usize>,
        torque: Vector3<f64>,
    ) -> Result<()> {
        let link = self.link_index(body, link)?;
        finite(torque.as_slice(), "external torque")?;
        let t: [f64; 3] = torque.into();
        // SAFETY: live world; t is 3 readable f64.
        check(unsafe { bullet_sys::ss_apply_external_torque(self.ptr(), body.0, link, t.as_ptr()) })
    }

    /// `resetBasePositionAndOrientation` and `resetBaseVelocity` in one: the base's centre of mass pose
    /// and world-frame velocities; the links follow.
    pub fn reset_base_state(&mut self, body: BodyId, state: &BaseState) -> Result<()> {
        self.joint_count(body)?;
        let q = state.pose.orientation.quaternion();
        let raw = bullet_sys::ss_base_state {
            position: state.pose.position.into(),
            orientation: [q.i, q.j, q.k, q.w],
            linear_velocity: state.linear_velocity.into(),
            angular_velocity: state.angular_velocity.into(),
        };
        // SAFETY: live world; raw is a valid struct.
        check(unsafe { bullet_sys::ss_reset_base_state(self.ptr(), body.0, &raw) })
    }

    /// `resetJointState(body, j, positions[j], velocities[j])` for joints 0..n; both slices must be as
    /// long as the body has joints.
    pub fn reset_joint_states(
        &mut self,
        body: BodyId,
        positions: &[f64],
        velocities: &[f64],
    ) -> Result<()> {
        let n = self.joint_count(body)?;
        if positions.len() != n || velocities.len() != n {
            return Err(invalid(format!(
                "body {} has {n} joints: got {} positions and {} velocities",
                body.0,
                positions.len(),
                velocities.len()
            )));
        }
        finite(positions, "joint positions")?;
        finite(velocities, "joint velocities")?;
        // SAFETY: live world; both slices hold n readable f64.
        check(unsafe {
            bullet_sys::ss_reset_joint_states(
                self.ptr(),
                body.0,
                n as i32,
                positions.as_ptr(),
                velocities.as_ptr(),
            )
        })
    }

    /// Contact points of the last step that involve `body`.
    pub fn contacts(&self, body: BodyId) -> Result<Vec<Contact>> {
        self.joint_count(body)?;
        let mut count = 0;
        // SAFETY: live world; capacity 0 with a null buffer only counts.
        check(unsafe {
            bullet_sys::ss_get_contacts(self.ptr(), body.0, std::ptr::null_mut(), 0, &mut count)
        })?;
        let mut raw = vec![bullet_sys::ss_contact::default(); count.max(0) as usize];
        // SAFETY: raw has room for `count` contacts; nothing stepped in between.
        check(unsafe {
            bullet_sys::ss_get_contacts(self.ptr(), body.0, raw.as_mut_ptr(), count, &mut count)
        })?;
        Ok(raw
            .iter()
            .map(|c| Contact {
                link: c.link,
                other_body: (c.other_body >= 0).then_some(BodyId(c.other_body)),
                other_link: c.other_link,
                position_on_body: Vector3::from(c.position_on_body),
                position_on_other: Vector3::from(c.position_on_other),
                normal: Vector3::from(c.normal_on_other),
                distance: c.distance,
                normal_force: c.normal_force,
            })
            .collect())
    }
}

/// An output slice of `n` joint values for the shim: its pointer, or null for an empty slice (the
/// caller does not want that quantity).
fn out_slice(s: &mut [f64], n: usize, what: &str) -> Result<*mut f64> {
    match s.len() {
        0 => Ok(std::ptr::null_mut()),
        len if len == n => Ok(s.as_mut_ptr()),
        len => Err(invalid(format!("{what}: slice of {len} for {n} joints"))),
    }
}

/// Poses from the shim's records of 7 values: position x, y, z, then the quaternion x, y, z, w.
fn poses_from_shim(raw: &[f64]) -> Vec<Pose> {
    raw.chunks_exact(7)
        .map(|c| Pose {
            position: Vector3::new(c[0], c[1], c[2]),
            orientation: UnitQuaternion::new_unchecked(Quaternion::new(c[6], c[3], c[4], c[5])),
        })
        .collect()
}
