//! `snake-cli run`: drive the built-in snake or a URDF robot and report how it moved.
//!
//! The clap flags ([`RunArgs`]) fill a typed [`RunPlan`]: what is simulated ([`BodyPlan`]: the built-in
//! cubes or a robot file), where it starts and for how long, how its joints are driven ([`Drive`]: a gait
//! or a targets CSV) and what is written ([`Outputs`]). Everything is checked while the plan is made, so
//! a bad flag or file fails before any simulation and before anything is written; [`execute`] then runs
//! it.
// The flags' doc comments are their --help text, where `<joint names>` is plain text, not HTML.
#![allow(rustdoc::invalid_html_tags)]

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use snake_core::urdf::Geometry;
use snake_core::{
    Body, Gait, GaitChoice, GaitKind, InertiaSource, JointRoles, LateralUndulation, Preset, Robot,
    RobotGait, RobotSpec, Simulation, SkinAxis, SkinFriction, Snake, SnakeConfig, StartPose,
};
use snake_core::{WorldRef, WorldSpec};

use crate::flags::{parse_friction, parse_gait_param, parse_skin, parse_start};
use crate::output::{check_distinct, say, OutputFile};
use crate::plot::{self, PathPlot};
use crate::recording::{self, Converter};
use crate::targets::TargetTable;
use crate::trace::TraceWriter;
use crate::trajectory::TrajectoryWriter;

/// Arguments of `snake-cli run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// Number of joints N of the built-in snake (N + 1 cubes).
    #[arg(long, default_value_t = 10, conflicts_with = "robot")]
    pub joints: usize,
    /// A robot instead of the built-in snake: a URDF file (pybullet's loadURDF with default flags) or a
    /// YAML robot file around one (anisotropic friction, motor gains, start pose; see robots/).
    #[arg(long)]
    pub robot: Option<PathBuf>,
    /// Gait: sine (pybullet's snake.py lateral undulation, on every actuated joint in joint order; a
    /// robot file may set the wave's parameters), or one of the library over the robot's yaw and pitch
    /// joints: lateral, sidewind, roll, linear, turn (docs/gaits.md); for water, Kelasidi et al.'s
    /// swim (lateral undulation) and eel (eel-like motion) over the yaw joints; for sand, Maladen et
    /// al.'s sandfish wave over the yaw joints (docs/media.md).
    #[arg(long, default_value = "sine")]
    pub gait: GaitKind,
    /// A gait parameter KEY=VALUE, repeatable, over the gait's defaults. sine: amplitude, period,
    /// wave_length, segment_length, ramp_segments; the library: amplitude_yaw, amplitude_pitch,
    /// spatial_yaw, spatial_pitch, period, phase, offset_yaw, offset_pitch, ramp; swim and eel: alpha,
    /// omega, delta, offset (radians, rad/s), ramp; sandfish: amplitude, wavelength, segment (metres:
    /// y = amplitude sin(2 pi (x / wavelength + frequency t)) along the body, each segment at the
    /// slope of its centre), frequency (Hz); default the robot sandfish's (0.091, 0.455, 0.065, 1).
    #[arg(long = "gait-param", value_name = "KEY=VALUE", value_parser = parse_gait_param, conflicts_with = "targets")]
    pub gait_params: Vec<(String, f64)>,
    /// Joint targets from a CSV instead of the gait (--robot only): header step,<joint names> (any
    /// order), one row per 1/240 s physics step, applied before that step; the run lasts as many steps
    /// as the file has rows.
    #[arg(long, requires = "robot", conflicts_with_all = ["seconds", "steer"])]
    pub targets: Option<PathBuf>,
    /// Parameter preset of the built-in snake: paper (every cube 0.06 kg) or snakebot-gym (links 1.0 kg,
    /// the paper's code).
    #[arg(long, default_value = "paper", conflicts_with = "robot")]
    pub preset: Preset,
    /// Simulated duration in seconds.
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub seconds: f64,
    /// Start pose of the base: X,Y,Z,YAW (metres, radians). Default: 0,0,<half extent>,0 for the snake;
    /// for a robot, its robot file's start, else pybullet's 0,0,0,0 (the root link's frame).
    #[arg(long, value_parser = parse_start, allow_hyphen_values = true)]
    pub start: Option<StartPose>,
    /// Steering offset in radians (snake.py uses +-0.2; positive turns left).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub steer: f64,
    /// Anisotropic friction X,Y,Z of the robot's base and every link, in each link's frame (pybullet's
    /// changeDynamics(anisotropicFriction=...)); replaces the robot file's.
    #[arg(long, requires = "robot", value_parser = parse_friction)]
    pub anisotropic_friction: Option<[f64; 3]>,
    /// Skin friction F,B,T (forward, backward, transverse; Hu et al. 2009) of every cube or robot link,
    /// in place of their lateral and anisotropic friction; each is multiplied by the ground's friction
    /// (0.5, Bullet's default for the plane). For a robot it replaces the robot file's skin_friction.
    #[arg(long, value_parser = parse_skin)]
    pub skin_friction: Option<SkinFriction>,
    /// Head direction of the skin in each link's frame: x, -x, y, -y, z or -z. Default: the built-in
    /// snake's head direction (-y); for a robot, its robot file's skin axis, else x.
    #[arg(long, requires = "skin_friction", allow_hyphen_values = true)]
    pub skin_axis: Option<SkinAxis>,
    /// Where the robot's link inertias come from: shapes (pybullet's default) or file
    /// (URDF_USE_INERTIA_FROM_FILE). Default: the robot file's, else shapes.
    #[arg(long, requires = "robot")]
    pub inertia: Option<InertiaSource>,
    /// A world file (YAML): the ground (plane, slope, heightfield, rough), its friction and static
    /// obstacles, built before the robot as pybullet would (docs/worlds.md, worlds/). Default: the
    /// flat plane. Without --start, the body starts raised by the ground's highest point near it.
    #[arg(long)]
    pub world: Option<PathBuf>,
    /// Write the trajectory here as CSV (one row per 1/240 s step). `--out` is the same flag, the
    /// name the `snakesim` command uses for its outputs.
    #[arg(long, visible_alias = "out")]
    pub output: Option<PathBuf>,
    /// Draw the path seen from above, with the snake's pose at regular moments, as PNG.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Width and height of the --plot PNG, pixels.
    #[arg(long, default_value_t = plot::DEFAULT_SIZE, value_parser = clap::value_parser!(u32).range(plot::MIN_SIZE as i64..=plot::MAX_SIZE as i64))]
    pub plot_size: u32,
    /// Write the full state after every physics step (cube poses, joint angles, velocities, torques,
    /// targets) as CSV: the physics trace that `snakesim convert` turns into a Rerun recording (for a
    /// robot, every link, and its shapes in the metadata).
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Write a Rerun recording (.rrd) of the run: the cubes in 3D at every physics step and plots of
    /// the joints. Open it with `.venv/bin/rerun FILE` or `snakesim view FILE --serve`. Needs the
    /// snakesim Python package (`bash scripts/setup`): found as $SNAKESIM_PYTHON, .venv/bin/python or
    /// the `snakesim` command. A robot's boxes, spheres, cylinders and capsules are drawn as such.
    #[arg(long)]
    pub rrd: Option<PathBuf>,
}

/// What is simulated.
pub enum BodyPlan {
    /// The built-in snake of `config.joints` cubes.
    Cubes {
        /// Its parameters.
        config: SnakeConfig,
        /// The preset they come from.
        preset: Preset,
    },
    /// A URDF robot (from a URDF or a robot file, with the command line's overrides applied).
    Robot(Box<RobotSpec>),
}

impl BodyPlan {
    fn joints(&self) -> usize {
        match self {
            BodyPlan::Cubes { config, .. } => config.joints,
            BodyPlan::Robot(spec) => spec.urdf.movable_joints().len(),
        }
    }

    /// Which joints a gait of the library bends sideways and which up and down.
    pub fn joint_roles(&self) -> JointRoles {
        match self {
            BodyPlan::Cubes { config, .. } => JointRoles::all_yaw(config.joints),
            BodyPlan::Robot(spec) => JointRoles::of_urdf(&spec.urdf),
        }
    }

    /// Mass of each body part, kg, in [`Simulation::body_poses`] order (pybullet's 1 kg for a URDF
    /// link without `<inertial>`).
    pub fn masses(&self) -> Vec<f64> {
        match self {
            BodyPlan::Cubes { config, .. } => std::iter::once(config.base_mass)
                .chain(std::iter::repeat_n(config.link_mass, config.joints))
                .collect(),
            BodyPlan::Robot(spec) => spec.masses(),
        }
    }

    fn build(&self, start: StartPose, world: &WorldSpec) -> Result<Body> {
        Ok(match self {
            BodyPlan::Cubes { config, .. } => Body::Cubes(Snake::in_world(config, start, world)?),
            BodyPlan::Robot(spec) => Body::Robot(Robot::in_world(spec, start, world)?),
        })
    }

    /// Largest distance of a body part from the base at rest, metres: the footprint over which a
    /// world's ground lifts the default start.
    fn reach(&self) -> f64 {
        match self {
            BodyPlan::Cubes { config, .. } => {
                (config.joints as f64 + 0.5) * config.link_spacing() + config.half_extent
            }
            BodyPlan::Robot(spec) => {
                // The sum of the joint offsets bounds every link's distance from the root.
                spec.urdf
                    .links
                    .iter()
                    .filter_map(|l| l.joint.as_ref())
                    .map(|j| {
                        let [x, y, z] = j.origin.xyz;
                        (x * x + y * y + z * z).sqrt()
                    })
                    .sum::<f64>()
                    + 2.0 * self.draw_half_extent()
            }
        }
    }

    /// Half the size of a body part, for the plot's squares.
    fn draw_half_extent(&self) -> f64 {
        match self {
            BodyPlan::Cubes { config, .. } => config.half_extent,
            BodyPlan::Robot(spec) => {
                let sizes: Vec<f64> =
                    spec.urdf
                        .links
                        .iter()
                        .flat_map(|l| l.collisions.iter())
                        .map(|c| match c.geometry {
                            Geometry::Box(s) => s.iter().copied().fold(0.0, f64::max) / 2.0,
                            Geometry::Sphere(r) => r,
                            Geometry::Cylinder { radius, .. }
                            | Geometry::Capsule { radius, .. } => radius,
                        })
                        .collect();
                if sizes.is_empty() {
                    0.05
                } else {
                    sizes.iter().sum::<f64>() / sizes.len() as f64
                }
            }
        }
    }
}

/// How the joints are driven.
pub enum Drive {
    /// A gait, stepped once per physics step.
    Gait(GaitChoice),
    /// Targets from a file, one row per physics step.
    Targets {
        /// The file.
        path: PathBuf,
        /// Its rows, in the robot's joint order.
        table: TargetTable,
    },
}

/// Where results go; every path was checked before the run.
pub struct Outputs {
    /// Trajectory CSV.
    pub trajectory: Option<PathBuf>,
    /// PNG plot.
    pub plot: Option<PathBuf>,
    /// The plot's width and height, pixels.
    pub plot_size: u32,
    /// Physics trace CSV (the built-in snake).
    pub trace: Option<PathBuf>,
    /// Rerun recording (the built-in snake).
    pub rrd: Option<PathBuf>,
    /// Print nothing (the atlas runs many plans and prints its own line for each).
    pub quiet: bool,
}

/// A checked run.
pub struct RunPlan {
    /// What is simulated.
    pub body: BodyPlan,
    /// Start pose of the base (the root link's frame for a robot).
    pub start: StartPose,
    /// Physics steps.
    pub steps: u64,
    /// How the joints are driven.
    pub drive: Drive,
    /// Steering of the gait (for the summary).
    pub steer: f64,
    /// The gait's name (for the summary).
    pub gait: GaitKind,
    /// Where results go.
    pub outputs: Outputs,
    /// Simulated seconds asked for.
    pub seconds: f64,
    /// The world file, if any (`None`: the flat plane).
    pub world: Option<WorldRef>,
}

impl RunPlan {
    /// Checks the flags and reads every input file.
    pub fn from_args(args: &RunArgs) -> Result<Self> {
        let config_dt = SnakeConfig::default().dt;
        let body = match &args.robot {
            None => {
                let mut config = args.preset.config(args.joints);
                config.skin_friction = args.skin_friction.map(|skin| SkinFriction {
                    axis: args.skin_axis,
                    ..skin
                });
                // The joint count's one check (snake_core::limits::check_joints), named as the flag.
                config.validate().map_err(|e| match e {
                    snake_core::Error::InvalidArgument(m) if m.key() == Some("joints") => {
                        anyhow::anyhow!("--joints: {}", m.detail())
                    }
                    other => other.into(),
                })?;
                BodyPlan::Cubes {
                    config,
                    preset: args.preset,
                }
            }
            Some(path) => {
                let mut spec = RobotSpec::load(path)?;
                if let Some(a) = args.anisotropic_friction {
                    spec.anisotropic_friction
                        .iter_mut()
                        .for_each(|f| *f = Some(a));
                }
                if let Some(skin) = args.skin_friction {
                    let skin = SkinFriction {
                        axis: args.skin_axis,
                        ..skin
                    };
                    spec.skin_friction.iter_mut().for_each(|s| *s = Some(skin));
                }
                if let Some(inertia) = args.inertia {
                    spec.inertia = inertia;
                }
                spec.urdf.check_inertia(spec.inertia)?;
                BodyPlan::Robot(Box::new(spec))
            }
        };
        let (drive, steps, seconds) = match &args.targets {
            Some(path) => {
                let BodyPlan::Robot(spec) = &body else {
                    bail!("--targets needs --robot");
                };
                let table = TargetTable::load(path, &spec.joint_names())?;
                let steps = table.rows.len() as u64;
                let drive = Drive::Targets {
                    path: path.clone(),
                    table,
                };
                (drive, steps, steps as f64 * config_dt)
            }
            None => {
                let max_seconds = snake_core::limits::MAX_RUN_SECONDS;
                if !(args.seconds.is_finite() && args.seconds > 0.0 && args.seconds <= max_seconds)
                {
                    bail!(
                        "--seconds must be a positive number of at most {max_seconds}, got {:?}",
                        args.seconds
                    );
                }
                let base = match &body {
                    BodyPlan::Robot(spec) => spec.gait.clone().unwrap_or_default(),
                    BodyPlan::Cubes { .. } => LateralUndulation::default(),
                };
                let gait = GaitChoice::new(
                    args.gait,
                    &args.gait_params,
                    args.steer,
                    &body.joint_roles(),
                    base,
                    config_dt,
                )?;
                let steps = (args.seconds / config_dt).round() as u64;
                if steps == 0 {
                    bail!(
                        "--seconds {} is shorter than one physics step ({} s)",
                        args.seconds,
                        config_dt
                    );
                }
                (Drive::Gait(gait), steps, args.seconds)
            }
        };
        let world = args.world.as_deref().map(WorldRef::load).transpose()?;
        let start = match (&args.start, &body) {
            (Some(s), _) => *s,
            (None, BodyPlan::Cubes { config, .. }) => StartPose::resting(config.half_extent),
            (None, BodyPlan::Robot(spec)) => spec.default_start(),
        };
        // On uneven ground a start made for the plane may lie inside it: raise the default start by
        // the ground's highest point under the body (an explicit --start is kept as given).
        let start = match (&args.start, &world) {
            (None, Some(w)) => StartPose {
                z: start.z + w.spec().ground_top(body.reach()),
                ..start
            },
            _ => start,
        };
        start.validate()?;
        Ok(RunPlan {
            body,
            start,
            steps,
            drive,
            steer: args.steer,
            gait: args.gait,
            outputs: Outputs {
                trajectory: args.output.clone(),
                plot: args.plot.clone(),
                plot_size: args.plot_size,
                trace: args.trace.clone(),
                rrd: args.rrd.clone(),
                quiet: false,
            },
            seconds,
            world,
        })
    }

    /// The world for the builders: the file's, else the flat plane.
    pub fn world_spec(&self) -> WorldSpec {
        self.world
            .as_ref()
            .map_or_else(WorldSpec::default, |w| w.spec().clone())
    }

    fn meta(&self, built: &Body) -> Result<serde_json::Value> {
        let mut meta = self.body_meta(built)?;
        if let Some(w) = &self.world {
            meta["world"] = serde_json::json!({
                "file": w.path(),
                "drawing": w.spec().drawing(),
            });
        }
        Ok(meta)
    }

    fn body_meta(&self, built: &Body) -> Result<serde_json::Value> {
        let s = &self.start;
        Ok(match (&self.body, &self.drive) {
            (BodyPlan::Cubes { config, preset }, Drive::Gait(gait)) => serde_json::json!({
                "source": "snake-cli run",
                "joints": config.joints,
                "dt": config.dt,
                "half_extent": config.half_extent,
                "preset": preset.to_string(),
                "seconds": self.seconds,
                "steps": self.steps,
                "start": {"x": s.x, "y": s.y, "z": s.z, "yaw": s.yaw},
                "gait": gait,
                "snake": config,
            }),
            (BodyPlan::Robot(spec), drive) => {
                let Some(robot) = built.robot() else {
                    bail!("a robot plan builds a robot");
                };
                serde_json::json!({
                    "source": "snake-cli run",
                    "robot": spec.urdf.name,
                    "file": spec.source,
                    "joints": self.body.joints(),
                    "joint_names": spec.joint_names(),
                    "parts": spec.urdf.links.len(),
                    "link_names": spec.urdf.links.iter().map(|l| l.name.as_str()).collect::<Vec<_>>(),
                    "shapes": robot.drawing(spec)?,
                    "dt": SnakeConfig::default().dt,
                    "inertia": spec.inertia,
                    "seconds": self.seconds,
                    "steps": self.steps,
                    "start": {"x": s.x, "y": s.y, "z": s.z, "yaw": s.yaw},
                    "drive": match drive {
                        Drive::Gait(g) => serde_json::json!({"gait": g}),
                        Drive::Targets { path, .. } => serde_json::json!({"targets": path}),
                    },
                })
            }
            (BodyPlan::Cubes { .. }, Drive::Targets { .. }) => bail!("--targets needs --robot"),
        })
    }
}

/// Runs the gait (or the targets) and prints a summary.
pub fn run(args: &RunArgs) -> Result<()> {
    let plan = RunPlan::from_args(args)?;
    execute(&plan).map(|_| ())
}

/// One moment of a run, for speeds and the cost of transport.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// Simulated seconds.
    pub time: f64,
    /// Centre of mass of the body parts (mass-weighted centres), x and y, metres.
    pub com: [f64; 2],
    /// Mechanical work of the motors so far, the sum over steps and joints of |tau * qdot| * dt, J.
    pub work: f64,
    /// Direction of the body axis, from the tail (the body part farthest from the base at the start)
    /// to the base, radians counter-clockwise from +x, in (-pi, pi].
    pub axis: f64,
}

/// What a run measured.
#[derive(Debug, Clone)]
pub struct RunReport {
    /// Total mass, kg.
    pub mass: f64,
    /// Body length: the largest distance between two body parts' centres at the start, metres.
    pub body_length: f64,
    /// The start, then every 24th physics step (0.1 s) and the last.
    pub samples: Vec<Sample>,
}

fn centre_of_mass(poses: &[snake_core::Pose], masses: &[f64]) -> [f64; 2] {
    let total: f64 = masses.iter().sum();
    let (mut x, mut y) = (0.0, 0.0);
    for (p, m) in poses.iter().zip(masses) {
        x += p.position.x * m;
        y += p.position.y * m;
    }
    [x / total, y / total]
}

/// Runs a checked plan and returns what it measured.
pub fn execute(plan: &RunPlan) -> Result<RunReport> {
    let out = &plan.outputs;
    let joints = plan.body.joints();
    // Check the outputs first: a bad path or format fails before any simulation time is spent, and
    // nothing replaces an existing file until its new contents are complete.
    let outputs: Vec<(&str, &Path)> = [
        ("--output", &out.trajectory),
        ("--plot", &out.plot),
        ("--trace", &out.trace),
        ("--rrd", &out.rrd),
    ]
    .into_iter()
    .filter_map(|(flag, path)| path.as_deref().map(|p| (flag, p)))
    .collect();
    check_distinct(&outputs)?;
    for (flag, path) in [("--rrd", &out.rrd), ("--trace", &out.trace)] {
        if path.is_some() {
            recording::check_seconds(flag, plan.seconds)?;
        }
    }
    let rrd_file = out
        .rrd
        .as_deref()
        .map(|p| OutputFile::new(p, "recording", &["rrd"]))
        .transpose()?;
    // Before any simulation: the recording's converter must be there.
    let converter = out.rrd.as_ref().map(|_| Converter::find()).transpose()?;
    let plot_file = out.plot.as_deref().map(plot::output).transpose()?;
    // The trace goes to --trace, or (for --rrd alone) to a temporary file.
    let trace_file = match (&out.trace, &rrd_file) {
        (Some(p), _) => Some(recording::TraceFile::Output(OutputFile::new(
            p,
            "trace",
            &["csv"],
        )?)),
        (None, Some(_)) => Some(recording::TraceFile::temporary()?),
        (None, None) => None,
    };
    let mut built = plan.body.build(plan.start, &plan.world_spec())?;
    let parts = built.sim().body_poses()?.len();
    let mut trace = match &trace_file {
        Some(f) => Some(TraceWriter::create(
            f.write_path(),
            f.shown_path(),
            joints,
            parts,
            &plan.meta(&built)?,
        )?),
        None => None,
    };
    let mut csv = out
        .trajectory
        .as_deref()
        .map(|p| {
            let file = OutputFile::new(p, "trajectory", &[])?;
            TrajectoryWriter::create(file, joints)
        })
        .transpose()?;

    let start_position = built.sim().base_state()?.pose.position;
    let masses = plan.body.masses();
    let start_poses = built.sim().body_poses()?;
    let body_length = start_poses
        .iter()
        .flat_map(|a| {
            start_poses
                .iter()
                .map(move |b| (a.position - b.position).norm())
        })
        .fold(0.0, f64::max);
    let tail = start_poses
        .iter()
        .enumerate()
        .map(|(k, p)| (k, (p.position - start_poses[0].position).norm()))
        .fold((0, 0.0), |best, c| if c.1 > best.1 { c } else { best })
        .0;
    let axis = |poses: &[snake_core::Pose]| {
        let d = poses[0].position - poses[tail].position;
        d.y.atan2(d.x)
    };
    let mut samples = vec![Sample {
        time: 0.0,
        com: centre_of_mass(&start_poses, &masses),
        work: 0.0,
        axis: axis(&start_poses),
    }];
    let mut work = 0.0;
    let (mut velocities, mut torques) = (vec![0.0; joints], vec![0.0; joints]);
    let water = plan
        .world_spec()
        .media
        .iter()
        .filter_map(|m| match m {
            snake_core::media::Medium::Water(w) => Some([
                w.region.min[0],
                w.region.min[1],
                w.region.max[0],
                w.region.max[1],
            ]),
            _ => None,
        })
        .collect();
    let mut path = PathPlot::new(plan.body.draw_half_extent()).with_water(water);
    path.sample(built.sim())?;
    let steps = plan.steps;
    let snapshot_every = (steps / 4).max(1);
    let mut targets = vec![0.0; joints];
    // sine's wave runs over the actuated joints; passive ones (effort 0) keep target 0. The library's
    // gaits set every movable joint by its role.
    let mut gait: Option<Box<dyn Gait>> = match (&plan.drive, &plan.body) {
        (Drive::Gait(GaitChoice::Sine(g)), BodyPlan::Cubes { .. }) => Some(Box::new(g.clone())),
        (Drive::Gait(GaitChoice::Sine(g)), BodyPlan::Robot(spec)) => {
            Some(Box::new(RobotGait::new(g.clone(), spec)))
        }
        (Drive::Gait(GaitChoice::Library(g)), _) => Some(Box::new(g.clone())),
        (Drive::Gait(GaitChoice::Swim(g)), _) => Some(Box::new(g.clone())),
        (Drive::Gait(GaitChoice::Sandfish(g)), _) => Some(Box::new(g.clone())),
        (Drive::Targets { .. }, _) => None,
    };
    let clock = Instant::now();
    for step in 1..=steps {
        match (&mut gait, &plan.drive) {
            (Some(g), _) => g.next_targets(&mut targets),
            (None, Drive::Targets { table, .. }) => {
                targets.copy_from_slice(&table.rows[(step - 1) as usize])
            }
            (None, Drive::Gait(_)) => unreachable!("a gait run has its gait"),
        }
        let body = built.sim_mut();
        if joints > 0 {
            body.set_targets(&targets)?;
        }
        body.step().with_context(|| format!("at step {step}"))?;
        if joints > 0 {
            built
                .sim()
                .read_joint_states(&mut [], &mut velocities, &mut torques)?;
            let power: f64 = velocities
                .iter()
                .zip(&torques)
                .map(|(v, t)| (v * t).abs())
                .sum();
            work += power * built.sim().dt();
        }
        if let Some(csv) = csv.as_mut() {
            csv.record(built.sim())?;
        }
        if let Some(trace) = trace.as_mut() {
            trace.record(built.sim(), &targets)?;
        }
        if step % 24 == 0 || step == steps {
            path.trace(built.sim())?;
            let poses = built.sim().body_poses()?;
            samples.push(Sample {
                time: built.sim().time(),
                com: centre_of_mass(&poses, &masses),
                work,
                axis: axis(&poses),
            });
        }
        if step % snapshot_every == 0 {
            path.sample(built.sim())?;
        }
    }
    let wall = clock.elapsed().as_secs_f64();
    let body = built.sim();
    let report = RunReport {
        mass: masses.iter().sum(),
        body_length,
        samples,
    };
    if !out.quiet {
        summary(plan, body, start_position, wall, &report)?;
    }
    if let (Some(csv), Some(path)) = (csv, &out.trajectory) {
        csv.finish()?;
        say!("wrote {} ({steps} rows)", path.display())?;
    }
    if let Some(file) = plot_file {
        let written = file.path().to_path_buf();
        let end = body.base_state()?.pose.position - start_position;
        let distance = end.xy().norm();
        let title = match &plan.body {
            BodyPlan::Cubes { config, preset } => format!(
                "{} joints, {preset} preset: {distance:.2} m in {:.1} s",
                config.joints,
                body.time()
            ),
            BodyPlan::Robot(spec) => format!(
                "{}: {distance:.2} m in {:.1} s",
                spec.urdf.name,
                body.time()
            ),
        };
        path.draw(file, &title, out.plot_size)?;
        if !out.quiet {
            say!("wrote {}", written.display())?;
        }
    }
    if let (Some(trace), Some(file)) = (trace, trace_file) {
        trace.finish()?;
        let path = file.commit()?;
        if let Some(shown) = &out.trace {
            say!("wrote {} ({steps} rows)", shown.display())?;
        }
        if let (Some(rrd), Some(converter)) = (rrd_file, converter) {
            let written = rrd.path().to_path_buf();
            converter.convert(&path, rrd.temp_path(), &written)?;
            rrd.commit()?;
            say!(
                "wrote {} (open it with: .venv/bin/rerun {0}, or snakesim view {0} --serve)",
                written.display()
            )?;
        }
    }
    Ok(report)
}

fn summary(
    plan: &RunPlan,
    body: &dyn Simulation,
    start_position: nalgebra::Vector3<f64>,
    wall: f64,
    report: &RunReport,
) -> Result<()> {
    let steps = plan.steps;
    let dt = SnakeConfig::default().dt;
    let end = body.base_state()?.pose;
    let moved = end.position - start_position;
    let distance = moved.xy().norm();
    match (&plan.body, &plan.drive) {
        (BodyPlan::Cubes { config, preset }, _) => {
            say!(
                "snake: {} joints ({} cubes), preset {preset}, gait {}, steering {}",
                config.joints,
                config.joints + 1,
                plan.gait,
                plan.steer
            )?;
            if let Some(skin) = &config.skin_friction {
                say!(
                    "skin friction: forward {}, backward {}, transverse {}, axis {}",
                    skin.forward,
                    skin.backward,
                    skin.transverse,
                    skin.axis.unwrap_or(SnakeConfig::HEAD_AXIS)
                )?;
            }
        }
        (BodyPlan::Robot(spec), drive) => {
            let how = match drive {
                Drive::Gait(_) => format!("gait {}, steering {}", plan.gait, plan.steer),
                Drive::Targets { path, .. } => format!("targets {}", path.display()),
            };
            say!(
                "robot: {} ({}): {} links, {} movable joints, inertia from {}, {how}",
                spec.urdf.name,
                spec.source.display(),
                spec.urdf.links.len(),
                body.joints(),
                spec.inertia
            )?;
            let skins = spec.skin_friction.iter().flatten().count();
            if skins > 0 {
                say!(
                    "skin friction on {skins} of {} links",
                    spec.urdf.links.len()
                )?;
            }
        }
    }
    say!(
        "simulated {:.2} s ({steps} steps of 1/{:.0} s) in {wall:.2} s wall: {:.0} steps/s",
        body.time(),
        1.0 / dt,
        steps as f64 / wall
    )?;
    say!(
        "distance   {distance:.3} m, from ({:.3}, {:.3}) to ({:.3}, {:.3})",
        start_position.x,
        start_position.y,
        end.position.x,
        end.position.y
    )?;
    say!("mean speed {:.3} m/s", distance / body.time())?;
    if let (Some(first), Some(last)) = (report.samples.first(), report.samples.last()) {
        let (dx, dy) = (last.com[0] - first.com[0], last.com[1] - first.com[1]);
        let d = dx.hypot(dy);
        say!(
            "centre of mass moved {d:.3} m ({dx:+.3}, {dy:+.3}); motor work {:.3} J; cost of transport {}",
            last.work,
            cost_of_transport(last.work, report.mass, d)
        )?;
    }
    say!(
        "heading    travel direction {:+.1} deg (counter-clockwise from +x); head yaw {:+.1} deg",
        moved.y.atan2(moved.x).to_degrees(),
        end.yaw().to_degrees()
    )?;
    say!(
        "final pose x {:+.4} m, y {:+.4} m, z {:.4} m, yaw {:+.4} rad",
        end.position.x,
        end.position.y,
        end.position.z,
        end.yaw()
    )
}

/// Cost of transport: mechanical work over weight times distance, `W / (m g d)` (dimensionless), as
/// text; "-" when the body did not move.
pub fn cost_of_transport(work: f64, mass: f64, distance: f64) -> String {
    let g = -SnakeConfig::default().gravity;
    if distance > 1e-9 && mass > 0.0 {
        format!("{:.3}", work / (mass * g * distance))
    } else {
        "-".to_string()
    }
}
