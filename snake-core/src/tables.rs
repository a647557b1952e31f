//! The two CSV tables of a robot driven by joint targets, parsed here once for every reader: a targets
//! file (`snake-cli run --targets`, `snakesim calibrate --targets`) and a log of such a run (`snake-cli
//! run --output`, `snakesim calibrate --log`).
//!
//! Both are read a line at a time from a regular file (as [`crate::files`] opens it) under one set of
//! limits: [`MAX_CSV_BYTES`] bytes, lines of at most [`MAX_CSV_LINE_CHARS`] characters, and
//! [`MAX_TARGET_ROWS`] rows, refused at the first line over, before the rest is read. Blank lines are
//! skipped; cells are trimmed. Errors name the file and line and never quote a cell that does not read
//! as a name or number ([`excerpt`]).
//!
//! - Targets: a header `step,<joint names>` (every movable joint exactly once, in any order), then row k
//!   with step k (from 1) and the targets set before physics step k, finite, in radians (metres for
//!   prismatic joints). The run lasts as many steps as there are rows.
//! - Log: the header [`LOG_BASE_COLUMNS`] then `q0..q{n-1}`, and optionally the velocities
//!   [`LOG_VELOCITY_COLUMNS`] then `qd0..qd{n-1}` (all or none); row k is step k at `t` = k dt (within
//!   [`LOG_T_TOLERANCE`]), every value within +-[`MAX_POSITION`].

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use crate::error::invalid;
use crate::files::{excerpt, open_regular};
use crate::limits::{MAX_CSV_BYTES, MAX_CSV_LINE_CHARS, MAX_POSITION, MAX_TARGET_ROWS};
use crate::Result;

/// The first columns of a log: the step, the time and the base's centre-of-mass pose.
pub const LOG_BASE_COLUMNS: [&str; 9] = [
    "step", "t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw",
];

/// The base's velocity columns of a log that holds velocities (`getBaseVelocity`, world frame); the
/// joint velocities `qd0..` follow them.
pub const LOG_VELOCITY_COLUMNS: [&str; 6] = [
    "base_vx", "base_vy", "base_vz", "base_wx", "base_wy", "base_wz",
];

/// Most a log's `t` may differ from step x dt, s: time stamps written to the millisecond pass; a row a
/// step early or late (4.2 ms at 240 Hz) does not.
pub const LOG_T_TOLERANCE: f64 = 1e-3;

/// A table of numbers, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Number of rows.
    pub rows: usize,
    /// Values per row.
    pub columns: usize,
    /// `values[r * columns + c]`.
    pub values: Vec<f64>,
}

impl Table {
    /// Row `r`.
    pub fn row(&self, r: usize) -> &[f64] {
        &self.values[r * self.columns..(r + 1) * self.columns]
    }
}

/// A log read back: its values after `step` and `t` (the base pose, the joints, then the velocities
/// when it holds them), one row per physics step.
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// `7 + joints` columns, or `13 + 2 joints` with the velocities.
    pub table: Table,
    /// Whether the log holds the velocity columns.
    pub velocities: bool,
}

/// The non-blank lines of a CSV, as trimmed cells, a line at a time under the module's limits.
struct Lines<R> {
    reader: R,
    file: String,
    line: usize,
    read: u64,
    buffer: Vec<u8>,
}

impl<R: BufRead> Lines<R> {
    fn new(reader: R, file: &str) -> Self {
        Lines {
            reader,
            file: file.to_string(),
            line: 0,
            read: 0,
            buffer: Vec::new(),
        }
    }

    /// The next non-blank line's number and cells; `None` at the end.
    fn next_cells(&mut self) -> Result<Option<(usize, Vec<String>)>> {
        loop {
            self.buffer.clear();
            let cap = MAX_CSV_LINE_CHARS as u64 + 1;
            let n = (&mut self.reader)
                .take(cap)
                .read_until(b'\n', &mut self.buffer)
                .map_err(|e| invalid(format!("{}: cannot read: {e}", self.file)))?;
            if n == 0 {
                return Ok(None);
            }
            self.line += 1;
            self.read += n as u64;
            if n as u64 == cap && self.buffer.last() != Some(&b'\n') {
                return Err(invalid(format!(
                    "{}:{}: a line longer than {MAX_CSV_LINE_CHARS} characters",
                    self.file, self.line
                )));
            }
            if self.read > MAX_CSV_BYTES {
                return Err(invalid(format!(
                    "{}: more than {MAX_CSV_BYTES} bytes (LIMITS['csv_bytes'])",
                    self.file
                )));
            }
            let text = std::str::from_utf8(&self.buffer).map_err(|_| {
                invalid(format!(
                    "{}: not UTF-8 text (line {})",
                    self.file, self.line
                ))
            })?;
            if text.trim().is_empty() {
                continue;
            }
            let cells = text.split(',').map(|c| c.trim().to_string()).collect();
            return Ok(Some((self.line, cells)));
        }
    }

    fn header(&mut self) -> Result<(usize, Vec<String>)> {
        self.next_cells()?
            .ok_or_else(|| invalid(format!("{}: empty; expected a header", self.file)))
    }
}

/// Row `k` (from 1) has the header's number of cells and step `k`.
fn check_row(file: &str, line: usize, cells: &[String], header: usize, k: usize) -> Result<()> {
    if cells.len() != header {
        return Err(invalid(format!(
            "{file}:{line}: {} cells, the header has {header}",
            cells.len()
        )));
    }
    if cells[0].parse::<usize>().ok() != Some(k) {
        return Err(invalid(format!(
            "{file}:{line}: step {}, expected {k} (rows sorted, one per physics step, from 1)",
            excerpt(&cells[0])
        )));
    }
    Ok(())
}

/// A cell as a finite number of magnitude at most `bound`.
fn number(file: &str, line: usize, name: &str, cell: &str, bound: f64) -> Result<f64> {
    let Ok(v) = cell.parse::<f64>() else {
        return Err(invalid(format!(
            "{file}:{line}: {name}: {} is not a number",
            excerpt(cell)
        )));
    };
    if !v.is_finite() {
        return Err(invalid(format!(
            "{file}:{line}: {name}: {} is not a finite number",
            excerpt(cell)
        )));
    }
    if v.abs() > bound {
        return Err(invalid(format!(
            "{file}:{line}: {name}: {} is beyond +-{bound} (LIMITS['position'])",
            excerpt(cell)
        )));
    }
    Ok(v)
}

fn open(path: &Path, what: &str) -> Result<(BufReader<std::fs::File>, String)> {
    let shown = path.display().to_string();
    // The size is checked here, so that the message names the limit as both CLIs list it.
    let file = open_regular(path, u64::MAX, what)?;
    let len = file
        .metadata()
        .map_err(|e| invalid(format!("{what} {shown}: cannot read: {e}")))?
        .len();
    if len > MAX_CSV_BYTES {
        return Err(invalid(format!(
            "{what} {shown}: more than {MAX_CSV_BYTES} bytes (LIMITS['csv_bytes'])"
        )));
    }
    Ok((BufReader::new(file), shown))
}

/// Reads a targets file for the joints named `joints` (the robot's movable joints in order): one row
/// per step, its columns in the robot's joint order.
pub fn read_targets(path: &Path, joints: &[&str]) -> Result<Table> {
    let (reader, file) = open(path, "targets")?;
    targets_from(Lines::new(reader, &file), joints)
}

/// [`read_targets`] on text; `file` labels messages.
pub fn parse_targets(text: &str, file: &str, joints: &[&str]) -> Result<Table> {
    targets_from(Lines::new(text.as_bytes(), file), joints)
}

fn targets_from<R: BufRead>(mut lines: Lines<R>, joints: &[&str]) -> Result<Table> {
    let file = lines.file.clone();
    let (first, names) = lines.header()?;
    if names[0] != "step" {
        return Err(invalid(format!(
            "{file}:{first}: the first column must be 'step' (not quoted: the file may not be a \
             targets file at all)"
        )));
    }
    // column in the file -> joint in the robot
    let mut slot = vec![usize::MAX; names.len()];
    let mut seen = vec![false; joints.len()];
    for (c, name) in names.iter().enumerate().skip(1) {
        let Some(j) = joints.iter().position(|n| n == name) else {
            return Err(invalid(format!(
                "{file}:{first}: column {} is not a movable joint of the robot (its joints: {})",
                excerpt(name),
                joints.join(", ")
            )));
        };
        if seen[j] {
            return Err(invalid(format!(
                "{file}:{first}: joint {} has two columns",
                excerpt(name)
            )));
        }
        seen[j] = true;
        slot[c] = j;
    }
    if let Some(j) = seen.iter().position(|s| !s) {
        return Err(invalid(format!(
            "{file}:{first}: no column for joint '{}'",
            joints[j]
        )));
    }
    let mut values = Vec::new();
    let mut k = 0;
    while let Some((line, cells)) = lines.next_cells()? {
        k += 1;
        if k > MAX_TARGET_ROWS {
            return Err(invalid(format!(
                "{file}:{line}: more than {} rows (LIMITS['target_rows']: an hour of 1/240 s steps)",
                thousands(MAX_TARGET_ROWS)
            )));
        }
        check_row(&file, line, &cells, names.len(), k)?;
        let start = values.len();
        values.resize(start + joints.len(), 0.0);
        for (c, cell) in cells.iter().enumerate().skip(1) {
            values[start + slot[c]] = number(&file, line, &names[c], cell, f64::INFINITY)?;
        }
    }
    if k == 0 {
        return Err(invalid(format!("{file}: no rows after the header")));
    }
    Ok(Table {
        rows: k,
        columns: joints.len(),
        values,
    })
}

/// The columns a log of a robot with `joints` movable joints has: without and with velocities.
pub fn log_columns(joints: usize, velocities: bool) -> Vec<String> {
    let mut columns: Vec<String> = LOG_BASE_COLUMNS.iter().map(|s| s.to_string()).collect();
    columns.extend((0..joints).map(|j| format!("q{j}")));
    if velocities {
        columns.extend(LOG_VELOCITY_COLUMNS.iter().map(|s| s.to_string()));
        columns.extend((0..joints).map(|j| format!("qd{j}")));
    }
    columns
}

/// Reads a log of a run of `steps` physics steps of `dt` seconds by a robot with `joints` movable
/// joints.
pub fn read_log(path: &Path, joints: usize, steps: usize, dt: f64) -> Result<Log> {
    let (reader, file) = open(path, "log")?;
    log_from(Lines::new(reader, &file), joints, steps, dt)
}

/// [`read_log`] on text; `file` labels messages.
pub fn parse_log(text: &str, file: &str, joints: usize, steps: usize, dt: f64) -> Result<Log> {
    log_from(Lines::new(text.as_bytes(), file), joints, steps, dt)
}

fn log_from<R: BufRead>(mut lines: Lines<R>, joints: usize, steps: usize, dt: f64) -> Result<Log> {
    let file = lines.file.clone();
    let (first, header) = lines.header()?;
    let plain = log_columns(joints, false);
    let full = log_columns(joints, true);
    let velocities = if header == plain {
        false
    } else if header == full {
        true
    } else if header.len() > plain.len() && header[..plain.len()] == plain[..] {
        let extra = &header[plain.len()..];
        let wanted = &full[plain.len()..];
        if let Some(unknown) = extra.iter().find(|c| !wanted.contains(c)) {
            return Err(invalid(format!(
                "{file}:{first}: column {} is not a log column (after the joints only the velocities \
                 {},... may follow)",
                excerpt(unknown),
                wanted[..7.min(wanted.len())].join(",")
            )));
        }
        let missing: Vec<&str> = wanted
            .iter()
            .filter(|c| !extra.contains(c))
            .map(String::as_str)
            .collect();
        if !missing.is_empty() {
            return Err(invalid(format!(
                "{file}:{first}: the log has velocity columns but lacks {} (give every velocity column \
                 or none; without them they are estimated)",
                missing.join(", ")
            )));
        }
        return Err(invalid(format!(
            "{file}:{first}: expected the velocity columns as {}",
            wanted.join(",")
        )));
    } else {
        let q = header
            .iter()
            .filter(|h| {
                h.strip_prefix('q')
                    .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
            })
            .count();
        if header.len() >= LOG_BASE_COLUMNS.len()
            && header[..LOG_BASE_COLUMNS.len()] == plain[..LOG_BASE_COLUMNS.len()]
            && q != joints
        {
            return Err(invalid(format!(
                "{file}:{first}: {q} joint columns, the robot has {joints} movable joints"
            )));
        }
        return Err(invalid(format!(
            "{file}:{first}: expected the header {},... (snake-cli run --output)",
            plain[..10.min(plain.len())].join(",")
        )));
    };
    let columns = header.len() - 2;
    let mut values = Vec::new();
    let mut k = 0;
    while let Some((line, cells)) = lines.next_cells()? {
        k += 1;
        if k > steps {
            return Err(invalid(format!(
                "{file}:{line}: more than {steps} rows, the targets have {steps} (one per physics step)"
            )));
        }
        check_row(&file, line, &cells, header.len(), k)?;
        let Ok(t) = cells[1].parse::<f64>() else {
            return Err(invalid(format!(
                "{file}:{line}: t: {} is not a number",
                excerpt(&cells[1])
            )));
        };
        let expected = k as f64 * dt;
        // Written so that a NaN time fails too.
        let on_time = (t - expected).abs() <= LOG_T_TOLERANCE;
        if !on_time {
            return Err(invalid(format!(
                "{file}:{line}: t: {}, expected step {k} x {} s = {expected:.6} s (one row per \
                 physics step, t = 0 at the first command)",
                excerpt(&cells[1]),
                step_length(dt)
            )));
        }
        for (name, cell) in header[2..].iter().zip(&cells[2..]) {
            values.push(number(&file, line, name, cell, MAX_POSITION)?);
        }
    }
    if k != steps {
        return Err(invalid(format!(
            "{file}: {k} rows, the targets have {steps} (one per physics step)"
        )));
    }
    Ok(Log {
        table: Table {
            rows: k,
            columns,
            values,
        },
        velocities,
    })
}

/// A step length as people write it: 1/240 rather than 0.004166666666666667.
fn step_length(dt: f64) -> String {
    let rate = 1.0 / dt;
    if (rate - rate.round()).abs() < 1e-9 {
        format!("1/{}", rate.round())
    } else {
        format!("{dt}")
    }
}

/// 864000 -> "864,000", as the messages' Python side writes limits.
fn thousands(n: usize) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, ch) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(ch);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1.0 / 240.0;

    #[test]
    fn targets_are_put_in_the_robots_order() {
        let t = parse_targets("step,b,a\n1,2,1\n\n2,4,3\n", "t.csv", &["a", "b"]).unwrap();
        assert_eq!((t.rows, t.columns), (2, 2));
        assert_eq!(t.values, vec![1.0, 2.0, 3.0, 4.0]);
    }

    #[test]
    fn bad_targets_name_the_line() {
        for (text, expected) in [
            ("", "t.csv: empty"),
            ("x,a\n", "t.csv:1: the first column must be 'step'"),
            ("step,k\n1,0\n", "column \"k\" is not a movable joint"),
            ("step,a,a\n", "joint \"a\" has two columns"),
            ("step\n1\n", "no column for joint 'a'"),
            ("step,a\n1,0.1\n2,0.1,0.3\n", "t.csv:3: 3 cells"),
            ("step,a\n2,0.1\n", "t.csv:2: step \"2\", expected 1"),
            ("step,a\n1,nan\n", "a: \"nan\" is not a finite number"),
            ("step,a\n1,x\n", "a: \"x\" is not a number"),
            ("step,a\n", "no rows after the header"),
        ] {
            let err = parse_targets(text, "t.csv", &["a"])
                .unwrap_err()
                .to_string();
            assert!(err.contains(expected), "{text:?}: {err}");
        }
    }

    #[test]
    fn a_long_line_is_refused_before_it_is_read_whole() {
        let text = format!("step,a\n1,{}\n", "1".repeat(MAX_CSV_LINE_CHARS + 10));
        let err = parse_targets(&text, "t.csv", &["a"])
            .unwrap_err()
            .to_string();
        assert!(err.contains("t.csv:2: a line longer than"), "{err}");
    }

    fn log_text(velocities: bool, rows: usize) -> String {
        let mut text = log_columns(1, velocities).join(",") + "\n";
        for k in 1..=rows {
            let t = k as f64 * DT;
            let extra = if velocities { ",0,0,0,0,0,0,0.5" } else { "" };
            text += &format!("{k},{t},0,0,0.25,0,0,0,1,0.1{extra}\n");
        }
        text
    }

    #[test]
    fn logs_with_and_without_velocities() {
        let log = parse_log(&log_text(false, 3), "l.csv", 1, 3, DT).unwrap();
        assert!(!log.velocities);
        assert_eq!((log.table.rows, log.table.columns), (3, 8));
        let log = parse_log(&log_text(true, 2), "l.csv", 1, 2, DT).unwrap();
        assert!(log.velocities);
        assert_eq!(log.table.columns, 15);
        assert_eq!(log.table.row(1)[14], 0.5);
    }

    #[test]
    fn bad_logs_name_the_problem() {
        let partial = log_columns(1, false).join(",") + ",base_vx\n";
        let err = parse_log(&partial, "l.csv", 1, 1, DT)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("l.csv:1: the log has velocity columns but lacks base_vy"),
            "{err}"
        );
        let err = parse_log(&log_text(false, 3), "l.csv", 2, 3, DT)
            .unwrap_err()
            .to_string();
        assert!(err.contains("1 joint columns, the robot has 2"), "{err}");
        let err = parse_log(&log_text(false, 3), "l.csv", 1, 2, DT)
            .unwrap_err()
            .to_string();
        assert!(err.contains("l.csv:4: more than 2 rows"), "{err}");
        let err = parse_log(&log_text(false, 2), "l.csv", 1, 3, DT)
            .unwrap_err()
            .to_string();
        assert!(err.contains("l.csv: 2 rows, the targets have 3"), "{err}");
        let shifted = log_text(false, 2).replace("\n2,0.0083", "\n2,0.0125");
        let err = parse_log(&shifted, "l.csv", 1, 2, DT)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("l.csv:3: t: \"0.0125") && err.contains("expected step 2 x 1/240 s"),
            "{err}"
        );
        let far = log_text(false, 1).replace(",0.1\n", ",1e9\n");
        let err = parse_log(&far, "l.csv", 1, 1, DT).unwrap_err().to_string();
        assert!(err.contains("q0: \"1e9\" is beyond"), "{err}");
    }

    #[test]
    fn thousands_groups_digits() {
        assert_eq!(thousands(864_000), "864,000");
        assert_eq!(thousands(12), "12");
        assert_eq!(thousands(1_234_567), "1,234,567");
    }
}
