//! `snake-cli run`: drive the snake with a gait and report how it moved.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use snake_core::{Gait, GaitKind, LateralUndulation, Preset, Snake, StartPose};

use crate::output::{check_distinct, say, OutputFile};
use crate::plot::{self, PathPlot};
use crate::recording::{self, Converter};
use crate::trace::TraceWriter;
use crate::trajectory::TrajectoryWriter;

/// Arguments of `snake-cli run`.
#[derive(Args, Debug)]
pub struct RunArgs {
    /// Number of joints N (the snake has N + 1 cubes).
    #[arg(long, default_value_t = 10)]
    pub joints: usize,
    /// Gait: sine (pybullet's snake.py lateral undulation).
    #[arg(long, default_value = "sine")]
    pub gait: GaitKind,
    /// Parameter preset: paper (every cube 0.06 kg) or snakebot-gym (links 1.0 kg, the paper's code).
    #[arg(long, default_value = "paper")]
    pub preset: Preset,
    /// Simulated duration in seconds.
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub seconds: f64,
    /// Start pose of the base: X,Y,Z,YAW (metres, radians). Default: 0,0,<half extent>,0.
    #[arg(long, value_parser = parse_start, allow_hyphen_values = true)]
    pub start: Option<StartPose>,
    /// Steering offset in radians (snake.py uses +-0.2; positive turns left).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub steer: f64,
    /// Write the trajectory here as CSV (one row per 1/240 s step).
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Draw the path seen from above, with the snake's pose at regular moments, as PNG.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Write the full state after every physics step (cube poses, joint angles, velocities, torques,
    /// targets) as CSV: the physics trace that `snakesim convert` turns into a Rerun recording.
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Write a Rerun recording (.rrd) of the run: the cubes in 3D at every physics step and plots of
    /// the joints. Open it with `.venv/bin/rerun FILE` or `snakesim view FILE --serve`. Needs the
    /// snakesim Python package (`bash scripts/setup`): found as $SNAKESIM_PYTHON, .venv/bin/python or
    /// the `snakesim` command.
    #[arg(long)]
    pub rrd: Option<PathBuf>,
}

fn parse_start(text: &str) -> Result<StartPose, String> {
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{text}' is not X,Y,Z,YAW (four numbers separated by commas)"))?;
    let [x, y, z, yaw] = values[..] else {
        return Err(format!(
            "'{text}' has {} values; expected X,Y,Z,YAW",
            values.len()
        ));
    };
    let pose = StartPose { x, y, z, yaw };
    pose.validate().map_err(|e| e.to_string())?;
    Ok(pose)
}

/// Runs the gait and prints a summary.
pub fn run(args: &RunArgs) -> Result<()> {
    if args.joints < 1 {
        bail!("--joints must be at least 1, got {}", args.joints);
    }
    let max_seconds = snake_core::limits::MAX_RUN_SECONDS;
    if !(args.seconds.is_finite() && args.seconds > 0.0 && args.seconds <= max_seconds) {
        bail!(
            "--seconds must be a positive number of at most {max_seconds}, got {:?}",
            args.seconds
        );
    }
    let config = args.preset.config(args.joints);
    config.validate()?;
    let mut gait = match args.gait {
        GaitKind::Sine => LateralUndulation::default().with_steering(args.steer),
    };
    gait.dt = config.dt;
    gait.validate()?;
    let start = args
        .start
        .unwrap_or_else(|| StartPose::resting(config.half_extent));
    let steps = (args.seconds / config.dt).round() as u64;
    if steps == 0 {
        bail!(
            "--seconds {} is shorter than one physics step ({} s)",
            args.seconds,
            config.dt
        );
    }

    // Check the outputs first: a bad path or format fails before any simulation time is spent, and
    // nothing replaces an existing file until its new contents are complete.
    let outputs: Vec<(&str, &std::path::Path)> = [
        ("--output", &args.output),
        ("--plot", &args.plot),
        ("--trace", &args.trace),
        ("--rrd", &args.rrd),
    ]
    .into_iter()
    .filter_map(|(flag, path)| path.as_deref().map(|p| (flag, p)))
    .collect();
    check_distinct(&outputs)?;
    for (flag, path) in [("--rrd", &args.rrd), ("--trace", &args.trace)] {
        if path.is_some() {
            recording::check_seconds(flag, args.seconds)?;
        }
    }
    let rrd_file = args
        .rrd
        .as_deref()
        .map(|p| OutputFile::new(p, "recording", &["rrd"]))
        .transpose()?;
    // Before any simulation: the recording's converter must be there.
    let converter = args.rrd.as_ref().map(|_| Converter::find()).transpose()?;
    let plot_file = args.plot.as_deref().map(plot::output).transpose()?;
    // The trace goes to --trace, or (for --rrd alone) to a temporary file.
    let trace_file = match (&args.trace, &rrd_file) {
        (Some(p), _) => Some(recording::TraceFile::Output(OutputFile::new(
            p,
            "trace",
            &["csv"],
        )?)),
        (None, Some(_)) => Some(recording::TraceFile::temporary()?),
        (None, None) => None,
    };
    let meta = serde_json::json!({
        "source": "snake-cli run",
        "joints": args.joints,
        "dt": config.dt,
        "half_extent": config.half_extent,
        "preset": args.preset.to_string(),
        "seconds": args.seconds,
        "steps": steps,
        "start": {"x": start.x, "y": start.y, "z": start.z, "yaw": start.yaw},
        "gait": &gait,
        "snake": &config,
    });
    let mut trace = trace_file
        .as_ref()
        .map(|f| TraceWriter::create(f.write_path(), f.shown_path(), args.joints, &meta))
        .transpose()?;
    let mut csv = args
        .output
        .as_deref()
        .map(|p| {
            let file = OutputFile::new(p, "trajectory", &[])?;
            TrajectoryWriter::create(file, args.joints)
        })
        .transpose()?;

    let mut snake = Snake::new(&config, start)?;
    let start_position = snake.base_state()?.pose.position;
    let mut path = PathPlot::new();
    path.sample(&snake)?;
    let snapshot_every = (steps / 4).max(1);
    let mut targets = vec![0.0; args.joints];
    let clock = Instant::now();
    for step in 1..=steps {
        gait.next_targets(&mut targets);
        snake.set_targets(&targets)?;
        snake.step().with_context(|| format!("at step {step}"))?;
        if let Some(csv) = csv.as_mut() {
            csv.record(&snake)?;
        }
        if let Some(trace) = trace.as_mut() {
            trace.record(&snake, &targets)?;
        }
        if step % 24 == 0 || step == steps {
            path.trace(&snake)?;
        }
        if step % snapshot_every == 0 {
            path.sample(&snake)?;
        }
    }
    let wall = clock.elapsed().as_secs_f64();

    let end = snake.base_state()?.pose;
    let moved = end.position - start_position;
    let distance = moved.xy().norm();
    say!(
        "snake: {} joints ({} cubes), preset {}, gait {}, steering {}",
        args.joints,
        args.joints + 1,
        args.preset,
        args.gait,
        args.steer
    )?;
    say!(
        "simulated {:.2} s ({steps} steps of 1/{:.0} s) in {wall:.2} s wall: {:.0} steps/s",
        snake.time(),
        1.0 / config.dt,
        steps as f64 / wall
    )?;
    say!(
        "distance   {distance:.3} m, from ({:.3}, {:.3}) to ({:.3}, {:.3})",
        start_position.x,
        start_position.y,
        end.position.x,
        end.position.y
    )?;
    say!("mean speed {:.3} m/s", distance / snake.time())?;
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
    )?;
    if let (Some(csv), Some(path)) = (csv, &args.output) {
        csv.finish()?;
        say!("wrote {} ({steps} rows)", path.display())?;
    }
    if let Some(file) = plot_file {
        let out = file.path().to_path_buf();
        let title = format!(
            "{} joints, {} preset: {distance:.2} m in {:.1} s",
            args.joints,
            args.preset,
            snake.time()
        );
        path.draw(file, &title)?;
        say!("wrote {}", out.display())?;
    }
    if let (Some(trace), Some(file)) = (trace, trace_file) {
        trace.finish()?;
        let path = file.commit()?;
        if let Some(shown) = &args.trace {
            say!("wrote {} ({steps} rows)", shown.display())?;
        }
        if let (Some(rrd), Some(converter)) = (rrd_file, converter) {
            let out = rrd.path().to_path_buf();
            converter.convert(&path, rrd.temp_path(), &out)?;
            rrd.commit()?;
            say!(
                "wrote {} (open it with: .venv/bin/rerun {0}, or snakesim view {0} --serve)",
                out.display()
            )?;
        }
    }
    Ok(())
}
