//! Robots described by a URDF file, on the paper's ground plane, driven as a pybullet user drives them.
//!
//! A [`RobotSpec`] is a parsed URDF plus what pybullet users set in code: anisotropic friction (whole
//! robot or per link), motor gains, the motors' maximum velocity (whole robot or per joint) and the
//! start pose. It comes from a URDF file alone or from a small YAML robot file around one
//! ([`RobotFile`]). A [`Robot`] is that robot in a world of its own, built in the order of a pybullet
//! script (docs/parity.md, "URDF robots"):
//!
//! ```python
//! p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE))
//! robot = p.loadURDF(urdf, [x, y, z], p.getQuaternionFromEuler([0, 0, yaw]))  # flags for --inertia file
//! p.setGravity(0, 0, -9.81)
//! for link in [-1] + list(range(p.getNumJoints(robot))):
//!     p.changeDynamics(robot, link, anisotropicFriction=...)  # only where the robot file sets it
//! # every step:
//! p.setJointMotorControlArray(robot, movable, p.POSITION_CONTROL, targetPositions=targets,
//!                             forces=[effort of each joint], positionGains=[kp] * M, velocityGains=[kd] * M)
//! # or, where the robot file sets a max_velocity (the array call has no maxVelocity):
//! for j, target, effort, v in zip(movable, targets, efforts, max_velocities):
//!     p.setJointMotorControl2(robot, j, p.POSITION_CONTROL, targetPosition=target, force=effort,
//!                             positionGain=kp, velocityGain=kd, maxVelocity=v)  # v left out if none
//! p.stepSimulation()
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::drawing::ShapeDrawing;
use crate::error::{invalid, Error, Result};
use crate::gait::{Gait, GaitKind, JointRoles, LateralUndulation, Serpenoid};
use crate::limits::{short, MAX_MOTOR_VELOCITY, MAX_URDF_BYTES};
use crate::math::StartPose;
use crate::media::water::{self, Coefficients, CoefficientsFile};
use crate::media::{MediaState, Primitive};
use crate::recorded::{FileOrRecord, Reader, RecordedFiles};
use crate::skin::{SkinAxis, SkinFriction};
use crate::urdf::{Geometry, InertiaSource, UrdfRobot};
use crate::world::{BaseState, BodyId, Dynamics, Pose, World};
use crate::world_file::WorldSpec;
use crate::{Snake, SnakeConfig};

/// The skin axis of a robot link that names none: +x of the link frame.
pub const ROBOT_SKIN_AXIS: SkinAxis = SkinAxis::X;

/// pybullet's default position gain of `setJointMotorControlArray`.
pub const DEFAULT_KP: f64 = 0.1;
/// pybullet's default velocity gain.
pub const DEFAULT_KD: f64 = 1.0;

/// Motor gains of a robot file, and how fast its servos turn.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Motors {
    /// Position gain (pybullet's positionGains), default 0.1.
    pub kp: f64,
    /// Velocity gain (pybullet's velocityGains), default 1.0.
    pub kd: f64,
    /// Largest velocity every motor drives its joint at, rad/s (m/s for a prismatic joint): pybullet's
    /// `setJointMotorControl2(maxVelocity=...)`, which clamps the motor's target velocity (a servo's
    /// no-load speed). `None`, the default, is no limit (`setJointMotorControlArray`, as without it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_velocity: Option<f64>,
}

impl Default for Motors {
    fn default() -> Self {
        Motors {
            kp: DEFAULT_KP,
            kd: DEFAULT_KD,
            max_velocity: None,
        }
    }
}

/// Settings of one movable joint's motor in a robot file.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSettings {
    /// This joint's maximum velocity (overrides `motors: max_velocity`), rad/s or m/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_velocity: Option<f64>,
}

/// Settings of one link in a robot file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSettings {
    /// `changeDynamics(anisotropicFriction=...)` of this link (overrides the robot's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub anisotropic_friction: Option<[f64; 3]>,
    /// Skin friction of this link (overrides the robot's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin_friction: Option<SkinFriction>,
    /// Water's coefficients for this link (each key over the robot's `water`, then the water's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water: Option<CoefficientsFile>,
}

/// A robot file: a small YAML around a URDF. Every key but `urdf` may be left out.
///
/// ```yaml
/// urdf: yaw-pitch-16.urdf          # relative to this file
/// start: [0, 0, 0.03, 0]           # x, y, z (root link frame, m), yaw (rad); pybullet's default 0, 0, 0, 0
/// inertia: shapes                  # or file (URDF_USE_INERTIA_FROM_FILE)
/// motors: {kp: 0.1, kd: 1.0, max_velocity: 3.5}   # pybullet's gains; max_velocity (rad/s, m/s for a
///                                  # prismatic joint): setJointMotorControl2's maxVelocity, no limit if absent
/// anisotropic_friction: [1, 0.01, 0.01]   # every link, in its own frame
/// skin_friction: {forward: 0.1, backward: 0.15, transverse: 0.2, axis: x}   # every link (issue 27)
/// water: {drag: 1.2, added_mass: 1.0}   # water's coefficients, every link, over the water's (issue 60)
/// links:                           # per link, by URDF name
///   head: {anisotropic_friction: [1, 1, 1]}
///   tail: {skin_friction: {forward: 0.1, backward: 0.1, transverse: 0.1}, water: {drag: 2.5}}
/// joints:                          # per movable joint, by URDF name
///   neck: {max_velocity: 3.0}      # overrides motors: max_velocity for this joint
/// gait: {segment_length: 0.0635, wave_length: 0.5, amplitude: 0.6}   # the sine gait's wave
/// wave: {gait: lateral, steering: 0.1}   # the envs' steered wave (default: the sine)
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotFile {
    /// The URDF, relative to the robot file.
    pub urdf: PathBuf,
    /// Start pose `[x, y, z, yaw]` of the root link's frame.
    #[serde(default)]
    pub start: Option<[f64; 4]>,
    /// Where inertias come from.
    #[serde(default)]
    pub inertia: InertiaSource,
    /// Motor gains and the motors' maximum velocity.
    #[serde(default)]
    pub motors: Motors,
    /// Anisotropic friction of every link (pybullet's `changeDynamics(anisotropicFriction=...)`).
    #[serde(default)]
    pub anisotropic_friction: Option<[f64; 3]>,
    /// Skin friction of every link (Hu et al.'s forward/backward/transverse law), in place of their
    /// lateral and anisotropic friction; its axis defaults to x.
    #[serde(default)]
    pub skin_friction: Option<SkinFriction>,
    /// Water's coefficients for every link (`skin_friction`, `drag`, `added_mass`, `added_inertia`,
    /// `linear`), over those of the water it swims in (docs/media.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub water: Option<CoefficientsFile>,
    /// Per-link settings by URDF link name.
    #[serde(default)]
    pub links: BTreeMap<String, LinkSettings>,
    /// Per-joint motor settings by URDF joint name (movable joints only).
    #[serde(default)]
    pub joints: BTreeMap<String, JointSettings>,
    /// Parameters of the sine gait (`--gait sine`) for this robot; left out, pybullet's snake.py wave.
    #[serde(default)]
    pub gait: Option<LateralUndulation>,
    /// The wave the envs' `gait` and `residual` actions drive: a gait of the library with parameters
    /// over its defaults; left out, the sine gait above (see [`crate::gait::SteeredWave`]).
    #[serde(default)]
    pub wave: Option<WaveFile>,
}

/// The largest yaw offset, radians, that the envs' steering sets on a robot file's `wave` unless the
/// file says otherwise: measured on yaw-pitch-16's lateral wave, 0.1 rad turns it at about 15
/// degrees/s as it crawls, while 0.5 rad spins it in place (see [`crate::gait::steered`]).
pub const DEFAULT_WAVE_STEERING: f64 = 0.1;

/// A robot file's `wave`: a gait of the library (`lateral`, `sidewind`, `roll`, `linear`, `turn`),
/// `--gait-param` style parameters over that gait's defaults for this robot, and how far the envs'
/// steering bends it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaveFile {
    /// The gait's name.
    pub gait: String,
    /// Parameters by key ([`crate::gait::serpenoid::PARAM_KEYS`]).
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
    /// The yaw offset, radians, of a full steering action ([`DEFAULT_WAVE_STEERING`]).
    #[serde(default = "default_wave_steering")]
    pub steering: f64,
}

fn default_wave_steering() -> f64 {
    DEFAULT_WAVE_STEERING
}

/// A robot's library wave for the envs: the gait and the yaw offset of a full steering action.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotWave {
    /// The gait, unsteered.
    pub gait: Serpenoid,
    /// Yaw offset of a full steering action, radians (> 0).
    pub steering: f64,
}

impl WaveFile {
    /// The wave on a robot of `urdf`, checked: a library gait the robot has the joints for, with
    /// parameters inside their limits, and a steering offset inside the gait's offset limits.
    fn wave(&self, urdf: &UrdfRobot) -> Result<RobotWave> {
        let high = crate::limits::GAIT_OFFSET.1;
        if !(self.steering.is_finite() && self.steering > 0.0 && self.steering <= high) {
            return Err(invalid(format!(
                "steering must be in (0, {high}] radians, got {}",
                self.steering
            )));
        }
        Ok(RobotWave {
            gait: self.gait(urdf)?,
            steering: self.steering,
        })
    }

    fn gait(&self, urdf: &UrdfRobot) -> Result<Serpenoid> {
        let kind: GaitKind = self.gait.parse()?;
        if kind == GaitKind::Sine {
            return Err(invalid(
                "gait sine is the envs' wave already (set its parameters under the robot file's \
                 `gait`); name a gait of the library here",
            ));
        }
        let params: Vec<(String, f64)> = self.params.iter().map(|(k, v)| (k.clone(), *v)).collect();
        // The env sets its own time step on the wave; this one only passes the check.
        let dt = SnakeConfig::default().dt;
        Serpenoid::new(kind, &JointRoles::of_urdf(urdf), &params, 0.0, dt)
    }
}

/// Everything needed to build a [`Robot`].
#[derive(Debug, Clone, PartialEq)]
pub struct RobotSpec {
    /// The parsed URDF.
    pub urdf: UrdfRobot,
    /// Where inertias come from.
    pub inertia: InertiaSource,
    /// Motor gains, and the maximum velocity of every motor that `max_velocities` leaves unset.
    pub motors: Motors,
    /// Each movable joint's own maximum velocity, in pybullet's joint order (a robot file's `joints`);
    /// `None` takes `motors.max_velocity`. See [`RobotSpec::max_velocity`].
    pub max_velocities: Vec<Option<f64>>,
    /// Anisotropic friction per link in pybullet's order (index 0: the root); `None` leaves Bullet's.
    pub anisotropic_friction: Vec<Option<[f64; 3]>>,
    /// Skin friction per link in pybullet's order (index 0: the root); `None` keeps Bullet's friction.
    pub skin_friction: Vec<Option<SkinFriction>>,
    /// Water's coefficients per link in pybullet's order (index 0: the root), checked; `None` takes
    /// the water's.
    pub water: Vec<Option<CoefficientsFile>>,
    /// The start pose the robot file names, if any.
    pub start: Option<StartPose>,
    /// The file it was read from.
    pub source: PathBuf,
    /// The sine gait's parameters for this robot (snake.py's when `None`).
    pub gait: Option<LateralUndulation>,
    /// The library gait the envs' actions steer instead of the sine wave (the robot file's `wave`).
    pub wave: Option<RobotWave>,
}

/// A robot file's `max_velocity` (at `key`): a finite speed in (0, [`MAX_MOTOR_VELOCITY`]]. Zero and
/// negative values are refused rather than read as pybullet's "no limit": leaving the key out says that.
fn check_max_velocity(file: &str, key: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 && v <= MAX_MOTOR_VELOCITY {
        Ok(())
    } else {
        Err(invalid(format!(
            "{file}: {key} must be in (0, {}] rad/s (m/s for a prismatic joint), got {}",
            short(MAX_MOTOR_VELOCITY),
            short(v)
        )))
    }
}

fn check_friction(file: &str, key: &str, a: [f64; 3]) -> Result<()> {
    if a.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(invalid(format!(
            "{file}: {key} must be three finite numbers >= 0, got {a:?}"
        )))
    }
}

impl RobotSpec {
    /// Mass of each link, kg, in pybullet's link order (the root first): the URDF's `<inertial>`
    /// masses, and pybullet's default of 1 kg for a link without one.
    pub fn masses(&self) -> Vec<f64> {
        self.urdf
            .links
            .iter()
            .map(|l| l.inertial.as_ref().map_or(1.0, |i| i.mass))
            .collect()
    }

    /// Reads a robot: a `.urdf` file alone (pybullet's defaults for everything else) or a `.yaml` /
    /// `.yml` robot file.
    pub fn load(path: &Path) -> Result<Self> {
        Self::read(&Reader::disk(path))
    }

    /// The robot of a record of its files ([`RecordedFiles`]), read as if they lay at its path.
    pub fn from_record(record: &RecordedFiles) -> Result<Self> {
        let reader = Reader::record(record);
        let spec = Self::read(&reader)?;
        reader.finish()?;
        Ok(spec)
    }

    fn read(reader: &Reader) -> Result<Self> {
        let path = reader.path();
        match path.extension().and_then(|e| e.to_str()) {
            Some("urdf") => {
                let text = reader.main(MAX_URDF_BYTES, "URDF")?;
                Self::from_urdf(UrdfRobot::parse_file(&text, path)?, path)
            }
            Some("yaml") | Some("yml") => Self::from_robot_file(reader),
            _ => Err(invalid(format!(
                "{}: a robot is a .urdf file or a .yaml robot file",
                path.display()
            ))),
        }
    }

    fn from_urdf(urdf: UrdfRobot, path: &Path) -> Result<Self> {
        let n = urdf.links.len();
        let movable = urdf.movable_joints().len();
        Ok(RobotSpec {
            urdf,
            inertia: InertiaSource::Shapes,
            motors: Motors::default(),
            max_velocities: vec![None; movable],
            anisotropic_friction: vec![None; n],
            skin_friction: vec![None; n],
            water: vec![None; n],
            start: None,
            source: path.to_path_buf(),
            gait: None,
            wave: None,
        })
    }

    fn from_robot_file(reader: &Reader) -> Result<Self> {
        let path = reader.path();
        let shown = path.display().to_string();
        let text = reader.main(MAX_URDF_BYTES, "robot file")?;
        crate::files::check_yaml_shape(&text, &shown)?;
        let file: RobotFile = crate::files::from_yaml(&text, &shown, "a robot file")?;
        let urdf_path = reader.dir().join(&file.urdf);
        let urdf = UrdfRobot::parse_file(
            &reader.named(&file.urdf, MAX_URDF_BYTES, "URDF")?,
            &urdf_path,
        )?;
        let m = file.motors;
        if !(m.kp.is_finite() && m.kp >= 0.0 && m.kd.is_finite() && m.kd >= 0.0) {
            return Err(invalid(format!(
                "{shown}: motors: kp and kd must be finite and >= 0, got {} and {}",
                m.kp, m.kd
            )));
        }
        if let Some(v) = m.max_velocity {
            check_max_velocity(&shown, "motors: max_velocity", v)?;
        }
        let max_velocities = joint_max_velocities(&file.joints, &urdf, &shown, &urdf_path)?;
        let mut friction = vec![file.anisotropic_friction; urdf.links.len()];
        if let Some(a) = file.anisotropic_friction {
            check_friction(&shown, "anisotropic_friction", a)?;
        }
        let mut skin = vec![file.skin_friction; urdf.links.len()];
        if let Some(s) = &file.skin_friction {
            s.validate(&format!("{shown}: skin_friction"))?;
        }
        if let Some(w) = &file.water {
            w.over(Coefficients::default(), &format!("{shown}: water"))?;
        }
        let mut water = vec![file.water; urdf.links.len()];
        for (name, settings) in &file.links {
            let k = urdf
                .links
                .iter()
                .position(|l| &l.name == name)
                .ok_or_else(|| {
                    invalid(format!(
                        "{shown}: links: {name}: no such link in {}",
                        urdf_path.display()
                    ))
                })?;
            if let Some(a) = settings.anisotropic_friction {
                check_friction(&shown, &format!("links: {name}: anisotropic_friction"), a)?;
                friction[k] = Some(a);
            }
            if let Some(s) = &settings.skin_friction {
                s.validate(&format!("{shown}: links: {name}: skin_friction"))?;
                skin[k] = Some(*s);
            }
            if let Some(w) = &settings.water {
                w.over(
                    Coefficients::default(),
                    &format!("{shown}: links: {name}: water"),
                )?;
                water[k] = Some(file.water.map_or(*w, |base| w.merged_over(&base)));
            }
        }
        if let Some(g) = &file.gait {
            g.validate()
                .map_err(|e| invalid(format!("{shown}: gait: {}", e.message())))?;
        }
        let wave = file
            .wave
            .as_ref()
            .map(|w| w.wave(&urdf))
            .transpose()
            .map_err(|e| invalid(format!("{shown}: wave: {}", e.message())))?;
        let start = file
            .start
            .map(|[x, y, z, yaw]| {
                let s = StartPose { x, y, z, yaw };
                s.validate()
                    .map_err(|e| invalid(format!("{shown}: start: {}", e.message())))?;
                Ok::<_, Error>(s)
            })
            .transpose()?;
        Ok(RobotSpec {
            urdf,
            inertia: file.inertia,
            motors: m,
            max_velocities,
            anisotropic_friction: friction,
            skin_friction: skin,
            water,
            start,
            source: path.to_path_buf(),
            gait: file.gait,
            wave,
        })
    }

    /// The maximum velocity of movable joint `k` (pybullet's joint order among the movable joints):
    /// its own, else the robot's, else `None` (no limit).
    pub fn max_velocity(&self, k: usize) -> Option<f64> {
        self.max_velocities
            .get(k)
            .copied()
            .flatten()
            .or(self.motors.max_velocity)
    }

    /// Names of the movable joints, in pybullet's joint order.
    pub fn joint_names(&self) -> Vec<&str> {
        self.urdf
            .movable_joints()
            .into_iter()
            .map(|j| self.urdf.joint(j).expect("movable joint").name.as_str())
            .collect()
    }

    /// Positions, among the movable joints, of the actuated ones (URDF effort > 0); a joint of effort 0
    /// (a passive wheel) is driven with force 0, which leaves it free. The gait's wave runs over the
    /// actuated joints in order.
    pub fn actuated_joints(&self) -> Vec<usize> {
        self.urdf
            .movable_joints()
            .into_iter()
            .enumerate()
            .filter(|(_, j)| self.urdf.joint(*j).expect("movable joint").effort > 0.0)
            .map(|(k, _)| k)
            .collect()
    }

    /// Every body part's shapes as Bullet places them (see [`Robot::drawing`]), from a robot built
    /// for the purpose.
    pub fn drawing(&self) -> Result<Vec<Vec<ShapeDrawing>>> {
        Robot::new(self, self.default_start())?.drawing(self)
    }

    /// The start pose: the robot file's, else pybullet's default (the origin, yaw 0).
    pub fn default_start(&self) -> StartPose {
        self.start.unwrap_or(StartPose {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            yaw: 0.0,
        })
    }
}

/// A robot file's `joints` table as one maximum velocity (or none) per movable joint, in pybullet's
/// joint order; a name that is no movable joint of the URDF, or a bad value, is an error naming it.
fn joint_max_velocities(
    joints: &BTreeMap<String, JointSettings>,
    urdf: &UrdfRobot,
    shown: &str,
    urdf_path: &Path,
) -> Result<Vec<Option<f64>>> {
    let movable = urdf.movable_joints();
    let mut out = vec![None; movable.len()];
    for (name, settings) in joints {
        let k = movable
            .iter()
            .position(|&j| urdf.joint(j).is_some_and(|joint| &joint.name == name))
            .ok_or_else(|| {
                let fixed = urdf.links.iter().any(|l| {
                    l.joint
                        .as_ref()
                        .is_some_and(|j| &j.name == name && !j.kind.is_movable())
                });
                let why = if fixed {
                    "a fixed joint has no motor"
                } else {
                    "no such joint"
                };
                invalid(format!(
                    "{shown}: joints: {name}: {why} in {}",
                    urdf_path.display()
                ))
            })?;
        if let Some(v) = settings.max_velocity {
            check_max_velocity(shown, &format!("joints: {name}: max_velocity"), v)?;
            out[k] = Some(v);
        }
    }
    Ok(out)
}

/// A gait on a robot's joints: the gait's wave over the actuated joints (URDF effort > 0) in order,
/// target 0 on the passive ones. This is what `snake-cli run --robot ... --gait sine` sets.
#[derive(Debug, Clone)]
pub struct RobotGait<G> {
    gait: G,
    actuated: Vec<usize>,
    wave: Vec<f64>,
}

impl<G: Gait> RobotGait<G> {
    /// `gait` on `spec`'s actuated joints.
    pub fn new(gait: G, spec: &RobotSpec) -> Self {
        let actuated = spec.actuated_joints();
        RobotGait {
            gait,
            wave: vec![0.0; actuated.len()],
            actuated,
        }
    }
}

impl<G: Gait> Gait for RobotGait<G> {
    /// `targets` holds one value per movable joint.
    fn next_targets(&mut self, targets: &mut [f64]) {
        self.gait.next_targets(&mut self.wave);
        for (&j, &v) in self.actuated.iter().zip(&self.wave) {
            targets[j] = v;
        }
    }

    fn reset(&mut self) {
        self.gait.reset();
    }
}

/// A simulated body the command line and the tests drive: the built-in snake or a URDF robot.
pub trait Simulation {
    /// Number of driven (movable) joints.
    fn joints(&self) -> usize;
    /// Physics steps taken.
    fn steps(&self) -> u64;
    /// Simulated seconds.
    fn time(&self) -> f64;
    /// Pose and velocity of the base (root link's centre of mass).
    fn base_state(&self) -> Result<BaseState>;
    /// Angles and velocities of the driven joints (either slice may be empty).
    fn read_joints(&self, positions: &mut [f64], velocities: &mut [f64]) -> Result<()>;
    /// Position targets of the driven joints, radians (metres for prismatic joints).
    fn set_targets(&mut self, targets: &[f64]) -> Result<()>;
    /// One physics step.
    fn step(&mut self) -> Result<()>;
    /// World poses of every body part: the base, then each link.
    fn body_poses(&self) -> Result<Vec<Pose>>;
    /// Angles, velocities and motor torques of the driven joints (any slice may be empty).
    fn read_joint_states(
        &self,
        positions: &mut [f64],
        velocities: &mut [f64],
        torques: &mut [f64],
    ) -> Result<()>;
    /// Seconds per physics step.
    fn dt(&self) -> f64;
}

impl Simulation for Snake {
    fn joints(&self) -> usize {
        Snake::joints(self)
    }
    fn steps(&self) -> u64 {
        Snake::steps(self)
    }
    fn time(&self) -> f64 {
        Snake::time(self)
    }
    fn base_state(&self) -> Result<BaseState> {
        Snake::base_state(self)
    }
    fn read_joints(&self, positions: &mut [f64], velocities: &mut [f64]) -> Result<()> {
        Snake::read_joints(self, positions, velocities)
    }
    fn set_targets(&mut self, targets: &[f64]) -> Result<()> {
        Snake::set_targets(self, targets)
    }
    fn step(&mut self) -> Result<()> {
        Snake::step(self)
    }
    fn body_poses(&self) -> Result<Vec<Pose>> {
        self.cube_poses()
    }
    fn read_joint_states(
        &self,
        positions: &mut [f64],
        velocities: &mut [f64],
        torques: &mut [f64],
    ) -> Result<()> {
        self.world()
            .read_joints(self.body(), positions, velocities, torques)
    }
    fn dt(&self) -> f64 {
        self.config().dt
    }
}

/// A URDF robot on the ground plane (see the module docs for the order it is built in).
#[derive(Debug)]
pub struct Robot {
    world: World,
    body: BodyId,
    ground: BodyId,
    movable: Vec<i32>,
    efforts: Vec<f64>,
    motors: Motors,
    /// Each movable joint's maximum velocity, 0 where it has none (the shim's "not given"); `None`
    /// when no joint has one, so that such a robot is driven exactly as pybullet's array call drives it.
    max_velocities: Option<Vec<f64>>,
    dt: f64,
    steps: u64,
    /// The world file's media acting on the robot; `None` without media (nothing runs then).
    media: Option<MediaState>,
}

impl Robot {
    /// Builds the world and loads the robot with its root link frame at `start`.
    pub fn new(spec: &RobotSpec, start: StartPose) -> Result<Self> {
        Self::in_world(spec, start, &WorldSpec::default())
    }

    /// As [`Robot::new`] on the ground and among the obstacles of `ground` (a world file), built where
    /// the plane is built today: before the robot and gravity.
    pub fn in_world(spec: &RobotSpec, start: StartPose, ground: &WorldSpec) -> Result<Self> {
        start.validate()?;
        let defaults = SnakeConfig::default();
        let mut world = World::new()?;
        world.set_time_step(defaults.dt)?;
        let (ground_body, _) = ground.build(&mut world)?;
        let body = world.add_urdf(
            &spec.urdf,
            [start.x, start.y, start.z],
            start.orientation(),
            spec.inertia,
        )?;
        world.set_gravity(Vector3::new(0.0, 0.0, defaults.gravity))?;
        for (k, friction) in spec.anisotropic_friction.iter().enumerate() {
            if let Some(a) = friction {
                let d = Dynamics {
                    anisotropic_friction: Some(*a),
                    ..Dynamics::default()
                };
                world.change_dynamics(body, k.checked_sub(1), &d)?;
            }
        }
        for (k, skin) in spec.skin_friction.iter().enumerate() {
            if let Some(s) = skin {
                world.set_skin_friction(body, k.checked_sub(1), s, ROBOT_SKIN_AXIS)?;
            }
        }
        let joints = spec.urdf.movable_joints();
        let efforts = joints
            .iter()
            .map(|&j| spec.urdf.joint(j).expect("movable joint").effort)
            .collect();
        let limits: Vec<Option<f64>> = (0..joints.len()).map(|k| spec.max_velocity(k)).collect();
        let max_velocities = limits
            .iter()
            .any(Option::is_some)
            .then(|| limits.iter().map(|v| v.unwrap_or(0.0)).collect());
        let shapes: Vec<Vec<Primitive>> = spec
            .urdf
            .links
            .iter()
            .map(|l| {
                l.collisions
                    .iter()
                    .map(|c| Primitive::from_urdf(&c.geometry))
                    .collect()
            })
            .collect();
        if ground
            .media
            .iter()
            .any(|m| matches!(m, crate::media::Medium::Water(_)))
        {
            let file = spec.source.display();
            water::check_volumes(&shapes, |k| {
                format!("{file}: links: {}", spec.urdf.links[k].name)
            })?;
        }
        let mut media = MediaState::for_body(&ground.media, &world, body, &shapes)?;
        if let Some(m) = &mut media {
            m.set_water_coefficients(&spec.water);
        }
        Ok(Robot {
            media,
            world,
            body,
            ground: ground_body,
            movable: joints.iter().map(|&j| j as i32).collect(),
            efforts,
            motors: spec.motors,
            max_velocities,
            dt: defaults.dt,
            steps: 0,
        })
    }

    /// The underlying world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The underlying world, mutable.
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// The robot's body in [`Robot::world`].
    pub fn body(&self) -> BodyId {
        self.body
    }

    /// The ground's body in [`Robot::world`].
    pub fn ground(&self) -> BodyId {
        self.ground
    }

    /// Multiplies every movable joint's motor force (the URDF's effort) and the position and velocity
    /// gains the robot is driven with by these factors.
    pub fn scale_motors(&mut self, effort: f64, kp: f64, kd: f64) {
        for e in &mut self.efforts {
            *e *= effort;
        }
        self.motors.kp *= kp;
        self.motors.kd *= kd;
    }

    /// The motor force of every movable joint and the gains the robot is driven with now.
    pub fn motor_settings(&self) -> (&[f64], Motors) {
        (&self.efforts, self.motors)
    }

    /// The media acting on the robot, when its world has any.
    pub fn media(&self) -> Option<&MediaState> {
        self.media.as_ref()
    }

    /// The media acting on the robot, mutable (randomized physics set the water's current).
    pub fn media_mut(&mut self) -> Option<&mut MediaState> {
        self.media.as_mut()
    }

    /// pybullet joint indices of the movable joints.
    pub fn movable_joints(&self) -> &[i32] {
        &self.movable
    }
}

impl Simulation for Robot {
    fn joints(&self) -> usize {
        self.movable.len()
    }
    fn steps(&self) -> u64 {
        self.steps
    }
    fn time(&self) -> f64 {
        self.steps as f64 * self.dt
    }
    fn base_state(&self) -> Result<BaseState> {
        self.world.base_state(self.body)
    }
    fn read_joints(&self, positions: &mut [f64], velocities: &mut [f64]) -> Result<()> {
        Simulation::read_joint_states(self, positions, velocities, &mut [])
    }
    fn set_targets(&mut self, targets: &[f64]) -> Result<()> {
        if targets.len() != self.movable.len() {
            return Err(invalid(format!(
                "expected {} joint targets, got {}",
                self.movable.len(),
                targets.len()
            )));
        }
        self.world.set_position_targets_at(
            self.body,
            &self.movable,
            targets,
            &self.efforts,
            self.motors.kp,
            self.motors.kd,
            self.max_velocities.as_deref(),
        )
    }
    fn step(&mut self) -> Result<()> {
        if let Some(media) = &mut self.media {
            media.apply(&mut self.world, self.body)?;
        }
        self.world.step()?;
        self.steps += 1;
        self.world.check_finite_base(self.body, self.steps)
    }
    fn body_poses(&self) -> Result<Vec<Pose>> {
        let mut poses = vec![self.base_state()?.pose];
        poses.extend(self.world.link_poses(self.body)?);
        Ok(poses)
    }
    fn read_joint_states(
        &self,
        positions: &mut [f64],
        velocities: &mut [f64],
        torques: &mut [f64],
    ) -> Result<()> {
        self.world
            .read_joints_at(self.body, &self.movable, positions, velocities, torques)
    }
    fn dt(&self) -> f64 {
        self.dt
    }
}

impl Robot {
    /// Every body part's shapes (the root first, then each link), as Bullet placed them: for viewers.
    pub fn drawing(&self, spec: &RobotSpec) -> Result<Vec<Vec<ShapeDrawing>>> {
        spec.urdf
            .links
            .iter()
            .enumerate()
            .map(|(k, link)| {
                let poses = self.world.shape_poses(self.body, k.checked_sub(1))?;
                Ok(link
                    .collisions
                    .iter()
                    .zip(poses)
                    .map(|(c, p)| {
                        let (kind, size) = match c.geometry {
                            Geometry::Box(s) => ("box", s),
                            Geometry::Sphere(r) => ("sphere", [r, 0.0, 0.0]),
                            Geometry::Cylinder { radius, length } => {
                                ("cylinder", [radius, length, 0.0])
                            }
                            Geometry::Capsule { radius, length } => {
                                ("capsule", [radius, length, 0.0])
                            }
                        };
                        let q = p.orientation.coords;
                        let x = p.position;
                        ShapeDrawing {
                            kind,
                            size,
                            pose: [x.x, x.y, x.z, q.x, q.y, q.z, q.w],
                        }
                    })
                    .collect())
            })
            .collect()
    }
}

/// A robot named by its file, as an [`EnvConfig`](crate::EnvConfig) holds it, with the texts it was
/// read from ([`RobotRef::files`]). Made from a path ([`RobotRef::load`]) it serialises as the path;
/// made from a record of its files ([`RobotRef::from_record`]), as that record, so that it never
/// becomes what the path holds now. Deserialised from either form, loaded and checked.
#[derive(Debug, Clone)]
pub struct RobotRef {
    path: PathBuf,
    spec: Arc<RobotSpec>,
    files: Arc<RecordedFiles>,
    recorded: bool,
}

impl RobotRef {
    /// Reads a robot (`.urdf` or robot file) and checks that it can be built.
    pub fn load(path: &Path) -> Result<Self> {
        let reader = Reader::disk(path);
        let spec = RobotSpec::read(&reader)?;
        Self::checked(spec, reader.finish()?, false)
    }

    /// The robot of a record of its files (what a model records of the robot it was trained on),
    /// checked as [`RobotRef::load`] checks a file; a record that holds files the robot does not use
    /// is refused.
    pub fn from_record(record: &RecordedFiles) -> Result<Self> {
        let spec = RobotSpec::from_record(record)?;
        Self::checked(spec, record.clone(), true)
    }

    fn checked(spec: RobotSpec, files: RecordedFiles, recorded: bool) -> Result<Self> {
        spec.urdf.check_inertia(spec.inertia)?;
        Ok(RobotRef {
            path: files.path.clone(),
            spec: Arc::new(spec),
            files: Arc::new(files),
            recorded,
        })
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The robot.
    pub fn spec(&self) -> &RobotSpec {
        &self.spec
    }

    /// The texts it was read from: the robot file and its URDF, or the URDF alone.
    pub fn files(&self) -> &RecordedFiles {
        &self.files
    }

    /// True when it was made from a record rather than read from its path.
    pub fn is_recorded(&self) -> bool {
        self.recorded
    }
}

impl PartialEq for RobotRef {
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path && self.spec == other.spec
    }
}

impl Serialize for RobotRef {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        if self.recorded {
            self.files.serialize(s)
        } else {
            self.path.serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for RobotRef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        match FileOrRecord::deserialize(d)? {
            FileOrRecord::Path(path) => RobotRef::load(&path),
            FileOrRecord::Record(record) => RobotRef::from_record(&record),
        }
        .map_err(serde::de::Error::custom)
    }
}
