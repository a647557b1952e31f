//! Joint-target files (`snake-cli run --targets FILE.csv`), read by snake-core's `tables`: the one
//! parser of targets and logs, which `snakesim calibrate` uses too (its format and limits are there).

use std::path::Path;

use anyhow::Result;

/// Targets read from a file, one row per step, columns in the robot's movable-joint order.
#[derive(Debug, Clone, PartialEq)]
pub struct TargetTable {
    /// `rows[k][j]`: target of joint j before physics step k + 1.
    pub rows: Vec<Vec<f64>>,
}

impl TargetTable {
    /// Reads `path` for the joints named `joints` (the robot's movable joints in order).
    pub fn load(path: &Path, joints: &[&str]) -> Result<Self> {
        let table = snake_core::tables::read_targets(path, joints)
            .map_err(|e| anyhow::anyhow!(e.message()))?;
        Ok(Self::from(table))
    }

    /// Parses the text of a targets file; `file` labels messages (the fuzz target's entry: fuzz/src/lib.rs
    /// includes this file).
    #[allow(dead_code)]
    pub fn parse(text: &str, file: &str, joints: &[&str]) -> Result<Self> {
        let table = snake_core::tables::parse_targets(text, file, joints)
            .map_err(|e| anyhow::anyhow!(e.message()))?;
        Ok(Self::from(table))
    }
}

impl From<snake_core::tables::Table> for TargetTable {
    fn from(table: snake_core::tables::Table) -> Self {
        TargetTable {
            rows: (0..table.rows).map(|r| table.row(r).to_vec()).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_come_in_the_robots_joint_order() {
        let t = TargetTable::parse("step,b,a\n1,2,1\n2,4,3\n", "t.csv", &["a", "b"]).unwrap();
        assert_eq!(t.rows, vec![vec![1.0, 2.0], vec![3.0, 4.0]]);
    }
}
