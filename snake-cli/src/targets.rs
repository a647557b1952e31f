//! Joint-target files (`snake-cli run --targets FILE.csv`).
//!
//! A header `step,<joint names>` (the joint columns in any order, every movable joint of the robot
//! exactly once), then one row per physics step: row k has step k (from 1) and the targets set before
//! physics step k, in radians (metres for prismatic joints). The run lasts as many steps as there are rows.

use std::path::Path;

use anyhow::{bail, Result};
use snake_core::files::excerpt;
use snake_core::limits::{MAX_TARGET_ROWS, MAX_URDF_BYTES};

/// Targets read from a file, one row per step, columns in the robot's movable-joint order.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetTable {
    /// `rows[k][j]`: target of joint j before physics step k + 1.
    pub rows: Vec<Vec<f64>>,
}

impl TargetTable {
    /// Reads `path` for the joints named `joints` (the robot's movable joints in order).
    pub fn load(path: &Path, joints: &[&str]) -> Result<Self> {
        let shown = path.display();
        // A row of 512 targets in shortest round-trip form is about 12 kB; an hour of rows at 240 Hz
        // would not fit in memory for large robots, so a file is held to the robot files' size limit
        // times 64.
        let text = snake_core::files::read_text(path, 64 * MAX_URDF_BYTES, "targets")
            .map_err(|e| anyhow::anyhow!(e.message()))?;
        Self::parse(&text, &shown.to_string(), joints)
    }

    /// Parses the text of a targets file; `file` labels messages.
    pub fn parse(text: &str, file: &str, joints: &[&str]) -> Result<Self> {
        let mut lines = text.lines().enumerate();
        let Some((_, header)) = lines.next() else {
            bail!("{file}: empty; expected a header step,<joint names>");
        };
        let names: Vec<&str> = header.split(',').map(str::trim).collect();
        if names.first() != Some(&"step") {
            bail!(
                "{file}:1: the first column must be 'step' (not quoted: the file may not be a \
                 targets file at all)"
            );
        }
        // column index (in the file) -> joint index (in the robot)
        let mut slot = vec![usize::MAX; names.len()];
        let mut seen = vec![false; joints.len()];
        for (c, name) in names.iter().enumerate().skip(1) {
            let Some(j) = joints.iter().position(|n| n == name) else {
                bail!(
                    "{file}:1: column {} is not a movable joint of the robot (its joints: {})",
                    excerpt(name),
                    joints.join(", ")
                );
            };
            if seen[j] {
                bail!("{file}:1: joint {} has two columns", excerpt(name));
            }
            seen[j] = true;
            slot[c] = j;
        }
        if let Some(j) = seen.iter().position(|s| !s) {
            bail!("{file}:1: no column for joint '{}'", joints[j]);
        }
        let mut rows = Vec::new();
        for (i, line) in lines {
            let line_no = i + 1;
            if line.trim().is_empty() {
                continue;
            }
            let cells: Vec<&str> = line.split(',').map(str::trim).collect();
            if cells.len() != names.len() {
                bail!(
                    "{file}:{line_no}: {} cells, the header has {}",
                    cells.len(),
                    names.len()
                );
            }
            let expected = rows.len() + 1;
            if cells[0].parse::<usize>().ok() != Some(expected) {
                bail!(
                    "{file}:{line_no}: step {}, expected {expected} (one row per physics step, from 1)",
                    excerpt(cells[0])
                );
            }
            let mut row = vec![0.0; joints.len()];
            for (c, cell) in cells.iter().enumerate().skip(1) {
                match cell.parse::<f64>() {
                    Ok(v) if v.is_finite() => row[slot[c]] = v,
                    _ => bail!(
                        "{file}:{line_no}: {}: {} is not a finite number",
                        names[c],
                        excerpt(cell)
                    ),
                }
            }
            rows.push(row);
            if rows.len() > MAX_TARGET_ROWS {
                bail!("{file}: more than {MAX_TARGET_ROWS} rows (an hour of steps)");
            }
        }
        if rows.is_empty() {
            bail!("{file}: no rows after the header");
        }
        Ok(TargetTable { rows })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_in_any_order() {
        let t = TargetTable::parse("step,b,a\n1,2,1\n2,4,3\n", "t.csv", &["a", "b"]).unwrap();
        assert_eq!(t.rows, vec![vec![1.0, 2.0], vec![3.0, 4.0]]);
    }

    #[test]
    fn bad_tables_are_one_line() {
        for (text, expected) in [
            ("step,a\n1,1,2\n", "3 cells"),
            ("step,a\n2,1\n", "expected 1"),
            ("step,a,c\n1,1,1\n", "column \"c\""),
            ("step\n1\n", "no column for joint 'a'"),
            ("step,a,a\n1,1,1\n", "two columns"),
            ("step,a\n1,nan\n", "not a finite number"),
            ("step,a\n", "no rows"),
        ] {
            let e = TargetTable::parse(text, "t.csv", &["a"])
                .unwrap_err()
                .to_string();
            assert!(e.contains(expected) && e.contains("t.csv"), "{e}");
        }
    }
}
