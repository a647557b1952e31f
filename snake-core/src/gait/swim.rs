//! Kelasidi et al.'s two swimming gaits (issue 60): lateral undulation and eel-like motion.
//!
//! E. Kelasidi, P. Liljebäck, K. Y. Pettersen, J. T. Gravdahl, "Innovation in underwater robots:
//! biologically inspired swimming snake robots", IEEE Robotics & Automation Magazine 23(1), March 2016,
//! and "Experimental investigation of efficient locomotion of underwater snake robots for lateral
//! undulation and eel-like motion patterns", Robotics and Biomimetics 2:8, 2015, write the reference
//! angle of joint `i` of a robot of `n` links (joints `1 ..= n - 1`, joint 1 at the tail) as
//!
//! ```text
//! phi_i(t) = alpha g(i, n) sin(omega t + (i - 1) delta) + phi_0
//! lateral undulation: g(i, n) = 1         eel-like motion: g(i, n) = (n - i) / (n + 1)
//! ```
//!
//! so that the wave runs from the head to the tail (the phase leads towards the head) and, in eel-like
//! motion, its amplitude grows from the head towards the tail. snakesim numbers joints from the head:
//! on a robot whose yaw joints are `j = 0 ..= J - 1` head first, joint `j` is Kelasidi's `i = J - j`
//! and `n = J + 1`. Only yaw joints move (Kelasidi's robots swim in the horizontal plane; Mamba's
//! pitch joints were held straight); every other joint holds 0. `ramp` grows the wave from straight
//! over its first seconds, as the library's gaits do.

use serde::Serialize;

use super::joints::{JointRole, JointRoles};
use super::{Gait, GaitKind};
use crate::error::{invalid, Result};
use crate::limits::{
    check_range, GAIT_AMPLITUDE, GAIT_OFFSET, GAIT_PHASE, GAIT_RAMP, MAX_SWIM_OMEGA,
};

/// Which of Kelasidi et al.'s envelopes `g(i, n)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SwimPattern {
    /// `g = 1`: the same amplitude on every joint.
    Lateral,
    /// `g = (n - i) / (n + 1)`: the amplitude grows towards the tail.
    Eel,
}

impl std::str::FromStr for SwimPattern {
    type Err = crate::Error;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "lateral" => Ok(SwimPattern::Lateral),
            "eel" => Ok(SwimPattern::Eel),
            _ => Err(invalid(format!(
                "unknown swimming pattern '{s}' (expected lateral or eel)"
            ))),
        }
    }
}

/// The gait's parameters, Kelasidi et al.'s names.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SwimParams {
    /// `alpha`, radians.
    pub alpha: f64,
    /// `omega`, rad/s.
    pub omega: f64,
    /// `delta`, radians between neighbouring joints.
    pub delta: f64,
    /// `phi_0`, radians (steering).
    pub offset: f64,
    /// Seconds over which the wave grows from straight (0: at once).
    pub ramp: f64,
}

/// The `--gait-param` keys of the swimming gaits.
pub const PARAM_KEYS: [&str; 5] = ["alpha", "omega", "delta", "offset", "ramp"];

/// The swimming gaits' defaults: this project's reading of Kelasidi et al.'s lateral undulation on
/// Mamba (alpha 30 degrees, omega 70 deg/s, delta 40 degrees; their parameters were not retrieved,
/// docs/media.md), grown over 2 s.
pub const DEFAULTS: SwimParams = SwimParams {
    alpha: 30.0 * std::f64::consts::PI / 180.0,
    omega: 70.0 * std::f64::consts::PI / 180.0,
    delta: 40.0 * std::f64::consts::PI / 180.0,
    offset: 0.0,
    ramp: 2.0,
};

/// Sets one parameter of `p` by its `--gait-param` key; an unknown key lists the known ones.
pub fn set(p: &mut SwimParams, gait: GaitKind, key: &str, value: f64) -> Result<()> {
    let slot = match key {
        "alpha" => &mut p.alpha,
        "omega" => &mut p.omega,
        "delta" => &mut p.delta,
        "offset" => &mut p.offset,
        "ramp" => &mut p.ramp,
        _ => {
            return Err(invalid(format!(
                "unknown gait parameter '{key}' for gait {gait} (expected one of: {})",
                PARAM_KEYS.join(", ")
            )))
        }
    };
    *slot = value;
    Ok(())
}

/// One of the swimming gaits on a robot's joints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Swim {
    /// Which envelope.
    pub pattern: SwimPattern,
    /// Its parameters.
    pub params: SwimParams,
    /// Movable-joint index of each yaw joint, head first.
    #[serde(skip)]
    yaw: Vec<usize>,
    #[serde(skip)]
    joints: usize,
    /// Physics time step, seconds (for [`Gait`]).
    pub dt: f64,
    #[serde(skip)]
    step: u64,
}

impl Swim {
    /// `pattern` with `params` on a robot with `roles`; fails, naming the parameter, when a value is
    /// outside the library's gait limits, or when the robot has no yaw joint.
    pub fn new(pattern: SwimPattern, params: SwimParams, roles: &JointRoles) -> Result<Swim> {
        let checks = [
            ("alpha", params.alpha, GAIT_AMPLITUDE),
            ("delta", params.delta, GAIT_PHASE),
            ("offset", params.offset, GAIT_OFFSET),
            ("ramp", params.ramp, GAIT_RAMP),
            ("omega", params.omega, (0.0, MAX_SWIM_OMEGA)),
        ];
        for (name, v, (lo, hi)) in checks {
            check_range(&format!("swimming gait parameter {name}"), v, lo, hi)?;
        }
        let yaw: Vec<usize> = roles
            .roles
            .iter()
            .enumerate()
            .filter(|(_, r)| **r == JointRole::Yaw)
            .map(|(k, _)| k)
            .collect();
        if yaw.is_empty() {
            return Err(invalid(
                "the swimming gaits need yaw joints (axis along z at rest); this robot has none",
            ));
        }
        Ok(Swim {
            pattern,
            params,
            yaw,
            joints: roles.roles.len(),
            dt: 1.0 / 240.0,
            step: 0,
        })
    }

    /// The gait stepped every `dt` seconds (positive and finite).
    pub fn with_dt(mut self, dt: f64) -> Result<Swim> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(invalid(format!(
                "gait dt must be positive and finite, got {dt}"
            )));
        }
        self.dt = dt;
        Ok(self)
    }

    /// The envelope `g(i, n)` of Kelasidi's joint `i` (1 at the tail) on a robot of `n` links.
    pub fn envelope(&self, i: usize, n: usize) -> f64 {
        match self.pattern {
            SwimPattern::Lateral => 1.0,
            SwimPattern::Eel => (n - i) as f64 / (n + 1) as f64,
        }
    }

    /// The targets at `t` seconds into `targets` (one per movable joint).
    pub fn targets_at(&self, t: f64, targets: &mut [f64]) {
        let p = &self.params;
        let r = if p.ramp > 0.0 {
            (t / p.ramp).min(1.0)
        } else {
            1.0
        };
        targets[..self.joints].fill(0.0);
        let count = self.yaw.len();
        let n = count + 1;
        for (j, &k) in self.yaw.iter().enumerate() {
            let i = count - j;
            let wave =
                p.alpha * self.envelope(i, n) * (p.omega * t + (i as f64 - 1.0) * p.delta).sin();
            targets[k] = r * (wave + p.offset);
        }
    }

    /// Targets for `steps` physics steps of `dt` seconds, row `s` at `t = s dt` (as the gait gives
    /// them before step `s + 1`, like the library's gaits), row after row.
    pub fn table(&self, dt: f64, steps: usize) -> Vec<f64> {
        let mut out = vec![0.0; steps * self.joints];
        for (s, row) in out.chunks_mut(self.joints.max(1)).enumerate() {
            self.targets_at(s as f64 * dt, row);
        }
        out
    }
}

impl Gait for Swim {
    fn next_targets(&mut self, targets: &mut [f64]) {
        // Time from the step count, as the library's gaits: no drift over long runs.
        self.targets_at(self.step as f64 * self.dt, targets);
        self.step += 1;
    }

    fn reset(&mut self) {
        self.step = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> SwimParams {
        SwimParams {
            alpha: 0.5,
            omega: 1.0,
            delta: 0.7,
            offset: 0.0,
            ramp: 0.0,
        }
    }

    #[test]
    fn eel_amplitude_grows_towards_the_tail_and_the_wave_runs_backwards() {
        let roles = JointRoles::new(vec![JointRole::Yaw; 9]);
        let eel = Swim::new(SwimPattern::Eel, params(), &roles).unwrap();
        // n = 10 links: the head joint (Kelasidi's i = 9) has 1/11 of alpha, the tail's (i = 1) 9/11.
        assert!((eel.envelope(9, 10) - 1.0 / 11.0).abs() < 1e-15);
        assert!((eel.envelope(1, 10) - 9.0 / 11.0).abs() < 1e-15);
        let mut q = [0.0; 9];
        // At t = 0 the tail joint (snakesim's last) is at sin(0) = 0, the head one at sin(8 delta).
        eel.targets_at(0.0, &mut q);
        assert_eq!(q[8], 0.0);
        assert!((q[0] - 0.5 / 11.0 * (8.0f64 * 0.7).sin()).abs() < 1e-15);
        // The head leads: the joint behind it reaches the head's phase delta / omega seconds later.
        let lateral = Swim::new(SwimPattern::Lateral, params(), &roles).unwrap();
        let (mut a, mut b) = ([0.0; 9], [0.0; 9]);
        lateral.targets_at(2.0, &mut a);
        lateral.targets_at(2.0 + 0.7, &mut b);
        assert!((a[3] - b[4]).abs() < 1e-12);
    }

    #[test]
    fn only_yaw_joints_move_and_bad_values_are_named() {
        let roles = JointRoles::new(vec![JointRole::Pitch, JointRole::Yaw, JointRole::Pitch]);
        let g = Swim::new(SwimPattern::Lateral, params(), &roles).unwrap();
        let mut q = [9.0; 3];
        g.targets_at(1.3, &mut q);
        assert_eq!((q[0], q[2]), (0.0, 0.0));
        assert!((q[1] - 0.5 * 1.3f64.sin()).abs() < 1e-15);
        let bad = SwimParams {
            alpha: 3.0,
            ..params()
        };
        let e = Swim::new(SwimPattern::Eel, bad, &roles)
            .unwrap_err()
            .to_string();
        assert!(e.contains("alpha"), "{e}");
        let e = Swim::new(
            SwimPattern::Eel,
            params(),
            &JointRoles::new(vec![JointRole::Pitch]),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("yaw joints"), "{e}");
    }
}
