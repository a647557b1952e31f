//! Helpers the `snake-cli` integration tests share (each test file is its own crate and uses some).
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the `snake-cli` binary under test.
pub fn snake_cli(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_snake-cli"))
        .args(args)
        .output()
        .expect("snake-cli starts")
}

/// A fresh folder of this test process for `tag` (`group` names the test file).
pub fn temp_dir(group: &str, tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("snake-cli-{group}-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The centre of mass's displacement `snake-cli run` reports: (distance, dx, dy) in metres, from
/// its "centre of mass moved D m (DX, DY)" line; panics with the output if the run failed.
pub fn com_moved(args: &[&str]) -> (f64, f64, f64) {
    let out = snake_cli(args);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{args:?}: {text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix("centre of mass moved "))
        .unwrap_or_else(|| panic!("no centre-of-mass line in {text}"));
    let distance = line.split(' ').next().unwrap().parse().unwrap();
    let inside = &line[line.find('(').unwrap() + 1..line.find(')').unwrap()];
    let v: Vec<f64> = inside
        .split(',')
        .map(|x| x.trim().parse().unwrap())
        .collect();
    (distance, v[0], v[1])
}
