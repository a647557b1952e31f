//! `snake-cli bench`: physics steps per second, ours beside pybullet's in the same run.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use crate::output::say;
use crate::python::find_python;
use anyhow::{bail, Context, Result};
use clap::Args;
use snake_core::{
    Gait, LateralUndulation, Preset, Robot, RobotGait, RobotSpec, Simulation, SkinFriction, Snake,
    StartPose, WorldSpec,
};

/// The pybullet side of the benchmark, in the repository this binary was built from.
fn pybullet_bench_script() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/reference/pybullet_bench.py")
}

use snake_rl::config::limits::{MAX_BENCH_REPEATS, MAX_BENCH_SIZES};

/// Arguments of `snake-cli bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Joint counts to measure, comma separated.
    #[arg(long, value_delimiter = ',', default_values_t = [5usize, 10, 20])]
    pub joints: Vec<usize>,
    /// Physics steps per run.
    #[arg(long, default_value_t = 2400)]
    pub steps: u64,
    /// Runs per joint count; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Python with pybullet 3.2.7 (default: $SNAKESIM_PYTHON, else .venv/bin/python here or in the repository).
    #[arg(long)]
    pub python: Option<PathBuf>,
    /// Measure snakesim only.
    #[arg(long)]
    pub no_reference: bool,
    /// Measure a robot (a URDF or robot file) driven by its sine gait instead of the built-in snake;
    /// both sides replay the same precomputed targets.
    #[arg(long, conflicts_with = "joints")]
    pub robot: Option<PathBuf>,
    /// Measure the built-in snake on this world file beside the flat plane, in the same run, ours
    /// and pybullet's (interleaved runs): steps/s on each and their ratios.
    #[arg(long, conflicts_with_all = ["robot", "skin_friction"])]
    pub world: Option<PathBuf>,
    /// Measure the cost of skin friction F,B,T on the built-in snake: runs with and without it,
    /// alternated, and the ratio of their step times (snakesim only).
    #[arg(long, conflicts_with = "robot", value_parser = crate::flags::parse_skin)]
    pub skin_friction: Option<SkinFriction>,
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        (values[n / 2 - 1] + values[n / 2]) / 2.0
    }
}

/// Steps per second of one run: gait targets, position control and a physics step, as pybullet's loop.
fn one_run(joints: usize, steps: u64, skin: Option<SkinFriction>) -> Result<f64> {
    one_run_in(joints, steps, skin, &WorldSpec::default())
}

/// [`one_run`] on a world, the snake's start raised as `snake-cli run` raises it.
fn one_run_in(
    joints: usize,
    steps: u64,
    skin: Option<SkinFriction>,
    world: &WorldSpec,
) -> Result<f64> {
    let mut config = Preset::Paper.config(joints);
    config.skin_friction = skin;
    let mut start = StartPose::resting(config.half_extent);
    start.z = start_height(joints, world);
    let mut snake = Snake::in_world(&config, start, world)?;
    let mut gait = LateralUndulation::default();
    let mut targets = vec![0.0; joints];
    let clock = Instant::now();
    for _ in 0..steps {
        gait.next_targets(&mut targets);
        snake.set_targets(&targets)?;
        snake.step()?;
    }
    Ok(steps as f64 / clock.elapsed().as_secs_f64())
}

/// Runs a pybullet benchmark script and reads the JSON it prints last (pybullet prints its own banner
/// lines first); its last stderr line when it fails.
fn run_reference(python: &Path, command: &mut Command) -> Result<serde_json::Value> {
    let out = command
        .output()
        .with_context(|| format!("cannot run {}", python.display()))?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        bail!(
            "the pybullet benchmark failed: {}",
            stderr.lines().last().unwrap_or("no output")
        );
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{') || l.starts_with('['))
        .unwrap_or("");
    serde_json::from_str(line).context("the pybullet benchmark printed no JSON")
}

fn pybullet_rates(python: &Path, args: &BenchArgs) -> Result<serde_json::Value> {
    let joints: Vec<String> = args.joints.iter().map(|j| j.to_string()).collect();
    let script = pybullet_bench_script();
    if !script.exists() {
        bail!(
            "{} is missing (run bench from a snakesim checkout)",
            script.display()
        );
    }
    run_reference(
        python,
        Command::new(python)
            .arg(&script)
            .arg(joints.join(","))
            .arg(args.steps.to_string())
            .arg(args.repeats.to_string()),
    )
}

/// Steps per second of one robot run replaying `rows` of targets.
fn one_robot_run(spec: &RobotSpec, rows: &[Vec<f64>]) -> Result<f64> {
    let mut robot = Robot::new(spec, spec.default_start())?;
    let clock = Instant::now();
    for row in rows {
        robot.set_targets(row)?;
        robot.step()?;
    }
    Ok(rows.len() as f64 / clock.elapsed().as_secs_f64())
}

/// pybullet's rates on the same robot and targets (tests/reference/urdf_bench.py).
fn pybullet_robot_rates(
    python: &Path,
    spec: &RobotSpec,
    rows: &[Vec<f64>],
    repeats: usize,
) -> Result<Vec<f64>> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/reference/urdf_bench.py");
    if !script.exists() {
        bail!(
            "{} is missing (run bench from a snakesim checkout)",
            script.display()
        );
    }
    let dir = tempfile::tempdir().context("cannot make a temporary directory")?;
    let targets = dir.path().join("targets.csv");
    let text: String = rows
        .iter()
        .map(|r| {
            let cells: Vec<String> = r.iter().map(|v| format!("{v:?}")).collect();
            cells.join(",") + "\n"
        })
        .collect();
    std::fs::write(&targets, text).context("cannot write the targets")?;
    let start = spec.default_start();
    let urdf = spec
        .urdf
        .source
        .as_ref()
        .context("the robot has no file")?
        .canonicalize()
        .context("cannot find the robot's URDF")?;
    let scenario = serde_json::json!({
        "name": "bench",
        "urdf": urdf,
        "start": [start.x, start.y, start.z, start.yaw],
        "inertia": spec.inertia.to_string(),
        "friction": spec.anisotropic_friction.iter().enumerate()
            .filter_map(|(k, a)| a.map(|a| (k as i32 - 1, a)))
            .collect::<Vec<_>>(),
        "kp": spec.motors.kp,
        "kd": spec.motors.kd,
        "targets": targets,
    });
    let spec_path = dir.path().join("scenario.json");
    std::fs::write(&spec_path, scenario.to_string()).context("cannot write the scenario")?;
    let rates = run_reference(
        python,
        Command::new(python)
            .arg(&script)
            .arg(&spec_path)
            .arg(repeats.to_string()),
    )?;
    serde_json::from_value(rates).context("the pybullet benchmark printed no list of rates")
}

fn bench_robot(args: &BenchArgs, path: &Path) -> Result<()> {
    let spec = RobotSpec::load(path)?;
    let mut gait = RobotGait::new(spec.gait.clone().unwrap_or_default(), &spec);
    let m = spec.urdf.movable_joints().len();
    let rows: Vec<Vec<f64>> = (0..args.steps)
        .map(|_| {
            let mut row = vec![0.0; m];
            gait.next_targets(&mut row);
            row
        })
        .collect();
    say!(
        "physics steps per second, one core, {} ({} links, {m} movable joints) on its sine gait; median of {} runs of {} steps",
        spec.urdf.name,
        spec.urdf.links.len(),
        args.repeats,
        args.steps
    )?;
    // Ours and pybullet's runs alternate, so that a load that changes during the benchmark (other
    // processes on a shared machine) weighs on both alike.
    let python = if args.no_reference {
        None
    } else {
        let found = find_python(args.python.as_deref());
        if found.is_none() {
            eprintln!("note: no Python with pybullet found (.venv/bin/python or --python); measuring snakesim only");
        }
        found
    };
    let (mut ours, mut theirs) = (Vec::new(), python.as_ref().map(|_| Vec::new()));
    for _ in 0..args.repeats {
        ours.push(one_robot_run(&spec, &rows)?);
        if let (Some(python), Some(rates)) = (&python, theirs.as_mut()) {
            match pybullet_robot_rates(python, &spec, &rows, 1) {
                Ok(r) => rates.extend(r),
                Err(e) => {
                    eprintln!("note: pybullet reference not measured: {e:#}");
                    theirs = None;
                }
            }
        }
    }
    let ours = median(ours);
    let theirs = theirs.filter(|r| !r.is_empty()).map(median);
    say!(
        "{:>16}  {:>16}  {:>7}",
        "snakesim",
        "pybullet 3.2.7",
        "ratio"
    )?;
    match theirs {
        Some(t) => say!("{ours:>16.0}  {t:>16.0}  {:>6.2}x", ours / t),
        None => say!("{ours:>16.0}  {:>16}  {:>7}", "-", "-"),
    }
}

/// Runs the benchmark and prints a table.
pub fn bench(args: &BenchArgs) -> Result<()> {
    let max_joints = snake_core::limits::MAX_JOINTS;
    let in_range = |&j: &usize| snake_core::limits::check_joints(j).is_ok();
    if args.joints.is_empty() || !args.joints.iter().all(in_range) {
        bail!("--joints needs one or more counts, each in [1, {max_joints}]");
    }
    if args.joints.len() > MAX_BENCH_SIZES {
        bail!("--joints takes at most {MAX_BENCH_SIZES} counts");
    }
    // As long as the longest `snake-cli run` (an hour of simulated time).
    let max_steps = (snake_core::limits::MAX_RUN_SECONDS * 240.0) as u64;
    if !(1..=max_steps).contains(&args.steps) {
        bail!("--steps must be in [1, {max_steps}], got {}", args.steps);
    }
    if !(1..=MAX_BENCH_REPEATS).contains(&args.repeats) {
        bail!(
            "--repeats must be in [1, {MAX_BENCH_REPEATS}], got {}",
            args.repeats
        );
    }
    if let Some(path) = &args.robot {
        return bench_robot(args, path);
    }
    if let Some(path) = &args.world {
        return bench_world(args, path);
    }
    if let Some(skin) = args.skin_friction {
        return bench_skin(args, skin);
    }
    say!(
        "physics steps per second, one core, gait running; median of {} runs of {} steps",
        args.repeats,
        args.steps
    )?;
    let ours: Vec<f64> = args
        .joints
        .iter()
        .map(|&j| {
            Ok(median(
                (0..args.repeats)
                    .map(|_| one_run(j, args.steps, None))
                    .collect::<Result<_>>()?,
            ))
        })
        .collect::<Result<_>>()?;

    let reference = if args.no_reference {
        None
    } else {
        match find_python(args.python.as_deref()) {
            Some(python) => match pybullet_rates(&python, args) {
                Ok(v) => Some(v),
                Err(e) => {
                    eprintln!("note: pybullet reference not measured: {e:#}");
                    None
                }
            },
            None => {
                eprintln!("note: no Python with pybullet found (.venv/bin/python or --python); measuring snakesim only");
                None
            }
        }
    };

    say!(
        "{:>6}  {:>16}  {:>16}  {:>7}",
        "joints",
        "snakesim",
        "pybullet 3.2.7",
        "ratio"
    )?;
    for (&joints, &rate) in args.joints.iter().zip(&ours) {
        let theirs = reference
            .as_ref()
            .and_then(|r| r.get(joints.to_string()))
            .and_then(|v| serde_json::from_value::<Vec<f64>>(v.clone()).ok())
            .map(median);
        match theirs {
            Some(t) => say!("{joints:>6}  {rate:>16.0}  {t:>16.0}  {:>6.2}x", rate / t)?,
            None => say!("{joints:>6}  {rate:>16.0}  {:>16}  {:>7}", "-", "-")?,
        }
    }
    Ok(())
}

/// The world as a pybullet user writes it, for tests/reference/world_bench.py: generators expanded
/// into a heightfield CSV (written into `dir`) and a list of obstacles, as JSON (serde_json writes
/// shortest round-trip floats, which Python's json reads back to the same doubles).
fn pybullet_world_json(world: &WorldSpec, dir: &Path) -> Result<PathBuf> {
    use serde_json::json;
    use snake_core::world_file::{Ground, ObstacleShape};
    let ground = match &world.ground {
        Ground::Plane => json!({"plane": {}}),
        Ground::Slope(degrees) => json!({"slope": {"degrees": degrees}}),
        Ground::Heightfield(h) => {
            let csv = dir.join("heightfield.csv");
            std::fs::write(&csv, h.to_csv()).context("cannot write the heightfield")?;
            json!({"heightfield": {"file": csv, "scale": h.scale}})
        }
    };
    let obstacles: Vec<serde_json::Value> = world
        .obstacles
        .iter()
        .map(|o| {
            let mut v = match o.shape {
                ObstacleShape::Box(h) => json!({"shape": "box", "half_extents": h}),
                ObstacleShape::Cylinder { radius, height } => {
                    json!({"shape": "cylinder", "radius": radius, "height": height})
                }
                ObstacleShape::Sphere(r) => json!({"shape": "sphere", "radius": r}),
            };
            v["position"] = json!(o.position);
            v["yaw"] = json!(o.yaw);
            if let Some(mu) = o.lateral_friction {
                v["lateral_friction"] = json!(mu);
            }
            v
        })
        .collect();
    let mut spec = json!({"ground": ground, "obstacles": obstacles});
    if let Some(mu) = world.ground_friction {
        spec["ground_friction"] = json!(mu);
    }
    let path = dir.join("world.json");
    std::fs::write(&path, spec.to_string()).context("cannot write the world")?;
    Ok(path)
}

/// The snake's start height on `world`, raised over the ground as `snake-cli run` raises it.
fn start_height(joints: usize, world: &WorldSpec) -> f64 {
    let config = Preset::Paper.config(joints);
    let start = StartPose::resting(config.half_extent);
    start.z + world.ground_top((joints as f64 + 0.5) * config.link_spacing() + config.half_extent)
}

/// pybullet's rates on the flat plane and on the world, one run each (tests/reference/world_bench.py).
fn pybullet_world_rates(
    python: &Path,
    world_json: &Path,
    joints: usize,
    z: f64,
    steps: u64,
) -> Result<(f64, f64)> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/reference/world_bench.py");
    if !script.exists() {
        bail!(
            "{} is missing (run bench from a snakesim checkout)",
            script.display()
        );
    }
    let rates = run_reference(
        python,
        Command::new(python)
            .arg(&script)
            .arg(world_json)
            .arg(joints.to_string())
            .arg(format!("{z:?}"))
            .arg(steps.to_string())
            .arg("1"),
    )?;
    let first = |key: &str| -> Result<f64> {
        rates
            .get(key)
            .and_then(|v| v.get(0))
            .and_then(serde_json::Value::as_f64)
            .with_context(|| format!("the pybullet benchmark printed no {key} rate"))
    };
    Ok((first("flat")?, first("world")?))
}

/// `--world`: the built-in snake on the world and on the flat plane, ours and pybullet's, runs
/// interleaved so that all four see the same machine load.
fn bench_world(args: &BenchArgs, path: &Path) -> Result<()> {
    let world = WorldSpec::load(path)?;
    say!(
        "physics steps per second, one core, gait running; median of {} runs of {} steps",
        args.repeats,
        args.steps
    )?;
    say!(
        "world {}: {} obstacles{}",
        path.display(),
        world.obstacles.len(),
        match &world.ground {
            snake_core::world_file::Ground::Heightfield(h) =>
                format!(", heightfield {} x {}", h.rows, h.columns),
            snake_core::world_file::Ground::Slope(d) => format!(", slope {d} degrees"),
            snake_core::world_file::Ground::Plane => String::new(),
        }
    )?;
    let python = if args.no_reference {
        None
    } else {
        let found = find_python(args.python.as_deref());
        if found.is_none() {
            eprintln!("note: no Python with pybullet found (.venv/bin/python or --python); measuring snakesim only");
        }
        found
    };
    let dir = tempfile::tempdir().context("cannot make a temporary directory")?;
    let world_json = match &python {
        Some(_) => Some(pybullet_world_json(&world, dir.path())?),
        None => None,
    };
    say!(
        "{:>6}  {:>11}  {:>11}  {:>6}  {:>13}  {:>13}  {:>6}",
        "joints",
        "flat plane",
        "world",
        "ratio",
        "pybullet flat",
        "pybullet world",
        "ratio"
    )?;
    for &joints in &args.joints {
        let z = start_height(joints, &world);
        let (mut on_flat, mut on_world) = (Vec::new(), Vec::new());
        let mut theirs = world_json.as_ref().map(|_| (Vec::new(), Vec::new()));
        for _ in 0..args.repeats {
            on_flat.push(one_run(joints, args.steps, None)?);
            on_world.push(one_run_in(joints, args.steps, None, &world)?);
            if let (Some(python), Some(json), Some((flat, on))) =
                (&python, &world_json, theirs.as_mut())
            {
                match pybullet_world_rates(python, json, joints, z, args.steps) {
                    Ok((f, w)) => {
                        flat.push(f);
                        on.push(w);
                    }
                    Err(e) => {
                        eprintln!("note: pybullet reference not measured: {e:#}");
                        theirs = None;
                    }
                }
            }
        }
        let (f, w) = (median(on_flat), median(on_world));
        match theirs {
            Some((pf, pw)) => {
                let (pf, pw) = (median(pf), median(pw));
                say!(
                    "{joints:>6}  {f:>11.0}  {w:>11.0}  {:>5.2}x  {pf:>13.0}  {pw:>13.0}  {:>5.2}x",
                    w / f,
                    pw / pf
                )?;
            }
            None => say!(
                "{joints:>6}  {f:>11.0}  {w:>11.0}  {:>5.2}x  {:>13}  {:>13}  {:>6}",
                w / f,
                "-",
                "-",
                "-"
            )?,
        }
    }
    Ok(())
}

/// Step time with skin friction against without, on the built-in snake and its gait: the runs alternate
/// (without, with, without, ...) so that a change of machine load hits both alike.
fn bench_skin(args: &BenchArgs, skin: SkinFriction) -> Result<()> {
    say!(
        "physics steps per second, one core, gait running, without and with skin friction {} / {} / {}; \
         median of {} alternated runs of {} steps",
        skin.forward,
        skin.backward,
        skin.transverse,
        args.repeats,
        args.steps
    )?;
    say!(
        "{:>6}  {:>14}  {:>14}  {:>10}",
        "joints",
        "without skin",
        "with skin",
        "cost ratio"
    )?;
    for &joints in &args.joints {
        let (mut without, mut with) = (Vec::new(), Vec::new());
        for _ in 0..args.repeats {
            without.push(one_run(joints, args.steps, None)?);
            with.push(one_run(joints, args.steps, Some(skin))?);
        }
        let (a, b) = (median(without), median(with));
        // Step cost is the inverse of the rate: cost with / cost without = rate without / rate with.
        say!("{joints:>6}  {a:>14.0}  {b:>14.0}  {:>9.3}x", a / b)?;
    }
    Ok(())
}
