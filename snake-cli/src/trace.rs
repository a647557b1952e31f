//! The physics-trace CSV (`snake-cli run --trace`): the snake's full state after every physics step,
//! what a Rerun recording shows (`snakesim convert` turns it into one; `snake-cli run --rrd` does both).
//!
//! Line 1: `# snakesim physics trace 1 {JSON}` (joints, dt, half extent, the run's settings). Line 2:
//! `step,t`, then `c{i}_x,c{i}_y,c{i}_z,c{i}_qx,c{i}_qy,c{i}_qz,c{i}_qw` for each cube i = 0..N (0 is
//! the head; for a robot, each link's centre of mass, the root first, and the metadata's `parts` and
//! `shapes` say how many and what to draw), then `q{j}` (angles, rad), `qd{j}` (velocities, rad/s), `tau{j}` (motor torques, N m),
//! `target{j}` (targets, rad) for each joint j. One row per physics step from step 1, floats in
//! shortest round-trip form (exact bits).

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use anyhow::{Context, Result};
use snake_core::env::PhysicsTrace;
use snake_core::Simulation;

/// First words of the metadata line.
pub const FORMAT: &str = "snakesim physics trace 1";

/// Streams physics-trace rows to a file.
pub struct TraceWriter {
    out: BufWriter<File>,
    shown: String,
    row: PhysicsTrace,
    line: String,
}

impl TraceWriter {
    /// Creates `path` (the caller makes it atomic) and writes the two header lines: `parts` poses
    /// (cubes, or a robot's links) and `joints` joints per row.
    pub fn create(
        path: &Path,
        shown: &Path,
        joints: usize,
        parts: usize,
        meta: &serde_json::Value,
    ) -> Result<Self> {
        let shown = shown.display().to_string();
        let handle =
            File::create(path).with_context(|| format!("cannot write trace to {shown}"))?;
        let mut out = BufWriter::new(handle);
        let mut header = String::from("step,t");
        for c in 0..parts {
            for k in ["x", "y", "z", "qx", "qy", "qz", "qw"] {
                write!(header, ",c{c}_{k}").expect("String write");
            }
        }
        for prefix in ["q", "qd", "tau", "target"] {
            for j in 0..joints {
                write!(header, ",{prefix}{j}").expect("String write");
            }
        }
        writeln!(out, "# {FORMAT} {meta}\n{header}")
            .with_context(|| format!("cannot write trace to {shown}"))?;
        Ok(TraceWriter {
            out,
            shown,
            row: PhysicsTrace::new(joints),
            line: String::new(),
        })
    }

    /// Appends the snake's current state with the targets of the step that led to it.
    pub fn record(&mut self, snake: &dyn Simulation, targets: &[f64]) -> Result<()> {
        self.row.clear();
        self.row.record(snake, Some(targets))?;
        let r = &self.row;
        self.line.clear();
        write!(self.line, "{},{:?}", r.steps[0], r.times[0]).expect("String write");
        for v in r
            .poses
            .iter()
            .chain(&r.positions)
            .chain(&r.velocities)
            .chain(&r.torques)
            .chain(&r.targets)
        {
            write!(self.line, ",{v:?}").expect("String write");
        }
        self.line.push('\n');
        self.out
            .write_all(self.line.as_bytes())
            .with_context(|| format!("cannot write trace to {}", self.shown))
    }

    /// Flushes everything to disk.
    pub fn finish(mut self) -> Result<()> {
        self.out
            .flush()
            .and_then(|()| self.out.get_ref().sync_all())
            .with_context(|| format!("cannot write trace to {}", self.shown))
    }
}
