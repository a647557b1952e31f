//! The trajectory CSV: one row per physics step with the state after that step.
//!
//! Header: `step,t,base_x,base_y,base_z,base_qx,base_qy,base_qz,base_qw,q0,...,q{N-1}`. Steps are
//! numbered from 1; floats are written in shortest round-trip form, so reading them back gives the
//! simulator's exact bits.

use std::fmt::Write as _;
use std::fs::File;
use std::io::{BufWriter, Write};

use anyhow::{Context, Result};
use snake_core::Simulation;

use crate::output::OutputFile;

/// Streams rows to a CSV file (through a temporary file that becomes the target on `finish`).
pub struct TrajectoryWriter {
    out: BufWriter<File>,
    file: OutputFile,
    line: String,
    joints: Vec<f64>,
}

impl TrajectoryWriter {
    /// Starts the file (checked by [`OutputFile::new`]) and writes the header.
    pub fn create(file: OutputFile, joints: usize) -> Result<Self> {
        let path = file.path();
        let handle = File::create(file.temp_path())
            .with_context(|| format!("cannot write trajectory to {}", path.display()))?;
        let mut out = BufWriter::new(handle);
        let mut header =
            String::from("step,t,base_x,base_y,base_z,base_qx,base_qy,base_qz,base_qw");
        for j in 0..joints {
            write!(header, ",q{j}").expect("writing to a String cannot fail");
        }
        writeln!(out, "{header}")
            .with_context(|| format!("cannot write trajectory to {}", path.display()))?;
        Ok(TrajectoryWriter {
            out,
            file,
            line: String::new(),
            joints: vec![0.0; joints],
        })
    }

    /// Appends the body's current state as the row of its latest step.
    pub fn record(&mut self, snake: &dyn Simulation) -> Result<()> {
        let base = snake.base_state()?;
        snake.read_joints(&mut self.joints, &mut [])?;
        let p = base.pose.position;
        let q = base.pose.orientation.coords; // x, y, z, w
        self.line.clear();
        // `{:?}` is Rust's shortest round-trip form (with an exponent for very small or large values).
        write!(self.line, "{},{:?}", snake.steps(), snake.time()).expect("String write");
        for v in [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
            .iter()
            .chain(&self.joints)
        {
            write!(self.line, ",{v:?}").expect("String write");
        }
        self.line.push('\n');
        self.out
            .write_all(self.line.as_bytes())
            .context("cannot write trajectory row")
    }

    /// Flushes everything and puts the file in place.
    pub fn finish(mut self) -> Result<()> {
        self.out
            .flush()
            .and_then(|()| self.out.get_ref().sync_all())
            .with_context(|| {
                format!("cannot write trajectory to {}", self.file.path().display())
            })?;
        drop(self.out);
        self.file.commit()
    }
}
