//! The gait library: Tesch et al.'s compound serpenoid on the yaw and pitch joints of any robot.
//!
//! Every gait here is one formula of time `t` and module number `n` (see [`super::joints`]), the
//! parameterised gait equation of Tesch et al. 2009 \[1\], which extends Hirose's serpenoid curve \[2\]
//! (the joint angles of a chain that follows a serpenoid curve are a sine of the joint index):
//!
//! ```text
//! yaw joint   n:  alpha(n, t) = r(t) * (offset_yaw   + amplitude_yaw   * sin(w t - spatial_yaw   * n))
//! pitch joint n:  alpha(n, t) = r(t) * (offset_pitch + amplitude_pitch * sin(pitch_rate * w t - spatial_pitch * n + phase))
//! w = 2 pi / period,   r(t) = min(1, t / ramp)   (1 when ramp = 0),   t = step * dt
//! ```
//!
//! Tesch et al. write `beta + A sin(theta)` with `theta = (d theta / d n) n + (d theta / d t) t` for the
//! even (one axis) modules and the same with a phase offset `delta` for the odd (other axis) ones;
//! `offset` is their `beta`, `amplitude` their `A`, `spatial` their `d theta / d n` (radians per
//! module), `w` their `d theta / d t` and `phase` their `delta`. The minus sign makes a positive
//! `spatial` wave travel from the head (module 0) to the tail, as pybullet's `sine` wave does, so that
//! lateral undulation moves the robot head first. Joints that are neither yaw nor pitch hold 0. The
//! ramp `r(t)` grows the whole shape from straight over `ramp` seconds so that no joint is asked to
//! jump at the first step.
//!
//! The gaits are parameter sets of that one equation ([`GaitKind`] and [`Serpenoid::defaults`]):
//!
//! | gait | yaw wave | pitch wave | what moves the robot |
//! |---|---|---|---|
//! | `lateral` | travelling, `spatial_yaw` | small, twice the spatial and temporal frequency (`pitch_rate` 2), `phase` pi/2; none on a yaw-only robot | the serpenoid pushes against anisotropic friction (scales, wheels); on isotropic friction the vertical wave lifts the body at the curvature peaks, where it would slip sideways (the lifting of Hu et al. 2009 \[3\]) |
//! | `sidewind` | travelling | same amplitude and spatial frequency, `phase` pi/4 (Tesch et al.'s sidewinding) | the body lies down in two moving contact patches and is lifted in between: it moves across its own axis |
//! | `roll` | `spatial` 0 (every module alike) | the same, `phase` pi/2 | the body is an arc whose bending plane turns about the body axis: it rolls sideways |
//! | `linear` | none | travelling tail to head (`spatial_pitch` < 0) | a vertical travelling wave (linear progression / rectilinear-like): the body moves along its axis, head first |
//! | `turn` | travelling, on an arc: `offset_yaw` = pi / (yaw joints) | none | the lateral wave runs along a half-circle arc, which turns the body about the arc's centre |
//!
//! Steering (`--steer`, radians) adds to `offset_yaw`: an offset on every yaw joint bends the shape into
//! an arc, which turns lateral undulation, linear progression and sidewinding (Tesch et al.'s `beta`).
//!
//! \[1\] M. Tesch, K. Lipkin, I. Brown, R. Hatton, A. Peck, J. Rembisz, H. Choset, "Parameterized and
//! scripted gaits for modular snake robots", Advanced Robotics 23(9), 2009, 1131-1158.
//! \[2\] S. Hirose, "Biologically Inspired Robots: Snake-Like Locomotors and Manipulators", Oxford
//! University Press, 1993.
//! \[3\] D. L. Hu, J. Nirody, T. Scott, M. J. Shelley, "The mechanics of slithering locomotion", PNAS
//! 106(25), 2009, 10081-10085.

use std::f64::consts::PI;

use serde::Serialize;

use super::joints::{JointRole, JointRoles};
use super::{Gait, GaitKind};
use crate::error::{invalid, Result};
use crate::limits::{
    check_range, GAIT_AMPLITUDE, GAIT_OFFSET, GAIT_PERIOD, GAIT_PHASE, GAIT_PITCH_RATE, GAIT_RAMP,
    GAIT_SPATIAL,
};

/// The parameters of the gait equation (see the module docs); the CLI's `--gait-param KEY=VALUE`
/// keys are the field names.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SerpenoidParams {
    /// Yaw wave amplitude, radians.
    pub amplitude_yaw: f64,
    /// Pitch wave amplitude, radians.
    pub amplitude_pitch: f64,
    /// Yaw wave's spatial frequency, radians per module (positive: the wave runs head to tail).
    pub spatial_yaw: f64,
    /// Pitch wave's spatial frequency, radians per module.
    pub spatial_pitch: f64,
    /// Seconds per gait cycle.
    pub period: f64,
    /// Phase of the pitch wave against the yaw wave, radians (Tesch et al.'s delta).
    pub phase: f64,
    /// Cycles of the pitch wave per gait cycle (its temporal frequency over the yaw wave's: Tesch et
    /// al. give each wave its own `d theta / d t`); 2 lifts the body at both curvature peaks of a
    /// lateral wave.
    pub pitch_rate: f64,
    /// Constant yaw angle on every yaw joint, radians (Tesch et al.'s beta; steering).
    pub offset_yaw: f64,
    /// Constant pitch angle on every pitch joint, radians.
    pub offset_pitch: f64,
    /// Seconds over which the shape grows from straight.
    pub ramp: f64,
}

/// The `--gait-param` keys of the library's gaits, in the order help lists them.
pub const PARAM_KEYS: [&str; 10] = [
    "amplitude_yaw",
    "amplitude_pitch",
    "spatial_yaw",
    "spatial_pitch",
    "period",
    "phase",
    "pitch_rate",
    "offset_yaw",
    "offset_pitch",
    "ramp",
];

impl SerpenoidParams {
    fn field(&mut self, key: &str) -> Option<&mut f64> {
        Some(match key {
            "amplitude_yaw" => &mut self.amplitude_yaw,
            "amplitude_pitch" => &mut self.amplitude_pitch,
            "spatial_yaw" => &mut self.spatial_yaw,
            "spatial_pitch" => &mut self.spatial_pitch,
            "period" => &mut self.period,
            "phase" => &mut self.phase,
            "pitch_rate" => &mut self.pitch_rate,
            "offset_yaw" => &mut self.offset_yaw,
            "offset_pitch" => &mut self.offset_pitch,
            "ramp" => &mut self.ramp,
            _ => return None,
        })
    }

    /// Sets one parameter by its key; an unknown key is an error that lists the known ones.
    pub fn set(&mut self, gait: GaitKind, key: &str, value: f64) -> Result<()> {
        match self.field(key) {
            Some(f) => {
                *f = value;
                Ok(())
            }
            None => Err(invalid(format!(
                "unknown gait parameter '{key}' for gait {gait} (expected one of: {})",
                PARAM_KEYS.join(", ")
            ))),
        }
    }

    /// Checks every parameter against [`crate::limits`]; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        let checks = [
            ("amplitude_yaw", self.amplitude_yaw, GAIT_AMPLITUDE),
            ("amplitude_pitch", self.amplitude_pitch, GAIT_AMPLITUDE),
            ("spatial_yaw", self.spatial_yaw, GAIT_SPATIAL),
            ("spatial_pitch", self.spatial_pitch, GAIT_SPATIAL),
            ("period", self.period, GAIT_PERIOD),
            ("phase", self.phase, GAIT_PHASE),
            ("pitch_rate", self.pitch_rate, GAIT_PITCH_RATE),
            ("offset_yaw", self.offset_yaw, GAIT_OFFSET),
            ("offset_pitch", self.offset_pitch, GAIT_OFFSET),
            ("ramp", self.ramp, GAIT_RAMP),
        ];
        for (name, v, (lo, hi)) in checks {
            check_range(&format!("gait parameter {name}"), v, lo, hi)?;
        }
        Ok(())
    }
}

/// One of the library's gaits on one robot's joints.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Serpenoid {
    /// Which gait.
    #[serde(rename = "name", serialize_with = "as_text")]
    pub kind: GaitKind,
    /// Its parameters.
    pub params: SerpenoidParams,
    /// Physics time step, seconds.
    pub dt: f64,
    /// The role of each movable joint.
    pub roles: Vec<JointRole>,
    #[serde(skip)]
    modules: Vec<Option<usize>>,
    #[serde(skip)]
    step: u64,
}

fn as_text<S: serde::Serializer>(k: &GaitKind, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.collect_str(k)
}

impl Serpenoid {
    /// The default parameters of `kind` on a robot with `roles` (see the table in the module docs);
    /// `None` for `sine`, which is not a gait of this equation.
    pub fn defaults(kind: GaitKind, roles: &JointRoles) -> Option<SerpenoidParams> {
        let has_pitch = roles.count(JointRole::Pitch) > 0;
        let yaw_joints = roles.count(JointRole::Yaw).max(1) as f64;
        let base = SerpenoidParams {
            amplitude_yaw: 0.0,
            amplitude_pitch: 0.0,
            spatial_yaw: 0.0,
            spatial_pitch: 0.0,
            period: 2.0,
            phase: 0.0,
            pitch_rate: 1.0,
            offset_yaw: 0.0,
            offset_pitch: 0.0,
            ramp: 2.0,
        };
        Some(match kind {
            GaitKind::Sine | GaitKind::Swim | GaitKind::Eel | GaitKind::Sandfish => return None,
            // Measured on robots/ (docs/gaits.md): a yaw-pitch snake's yaw joints are every other
            // module, so it needs a larger yaw amplitude and, on its isotropic friction, the vertical
            // wave at twice the lateral wave's spatial and temporal frequency, which lifts the body
            // at both curvature peaks; without it the robot barely moves (0.04 m in 8 s).
            GaitKind::Lateral if has_pitch => SerpenoidParams {
                amplitude_yaw: 0.9,
                amplitude_pitch: 0.15,
                spatial_yaw: 0.4,
                spatial_pitch: 0.8,
                pitch_rate: 2.0,
                phase: PI / 2.0,
                ..base
            },
            GaitKind::Lateral => SerpenoidParams {
                amplitude_yaw: 0.5,
                spatial_yaw: 0.6,
                ..base
            },
            GaitKind::Sidewind => SerpenoidParams {
                amplitude_yaw: 0.6,
                amplitude_pitch: 0.6,
                spatial_yaw: 0.6,
                spatial_pitch: 0.6,
                phase: PI / 4.0,
                ..base
            },
            GaitKind::Roll => SerpenoidParams {
                amplitude_yaw: 0.2,
                amplitude_pitch: 0.2,
                phase: PI / 2.0,
                ..base
            },
            // The vertical wave runs tail to head (negative spatial frequency), as a caterpillar's
            // hump does, so that the robot moves head first.
            GaitKind::Linear => SerpenoidParams {
                amplitude_pitch: 0.8,
                spatial_pitch: -0.5,
                ..base
            },
            // On a yaw-pitch snake, the lifted lateral wave (above) bent on an arc. Its offset was
            // measured on yaw-pitch-16 (12 s runs, turn rate of the root link): 0.39 rad (pi / its 8
            // yaw joints) turns -19 deg/s, 0.5 rad -28, 0.6 rad -80, 0.7 rad -112, 0.9 rad -90, while
            // the centre of mass drifts about 0.05 m/s; without the lift it turns 3 deg/s.
            GaitKind::Turn if has_pitch => SerpenoidParams {
                amplitude_yaw: 0.9,
                amplitude_pitch: 0.15,
                spatial_yaw: 0.4,
                spatial_pitch: 0.8,
                pitch_rate: 2.0,
                phase: PI / 2.0,
                offset_yaw: 0.7,
                ..base
            },
            GaitKind::Turn => SerpenoidParams {
                amplitude_yaw: 0.6,
                spatial_yaw: 0.6,
                offset_yaw: (PI / yaw_joints).min(GAIT_OFFSET.1),
                ..base
            },
        })
    }

    /// `kind` on a robot with `roles`: its defaults, then `params` (key, value) in order, then `steer`
    /// added to `offset_yaw`. Fails, in one line naming the parameter or the missing joints, when a
    /// value is out of its limits or the robot lacks the joints the gait moves.
    pub fn new(
        kind: GaitKind,
        roles: &JointRoles,
        params: &[(String, f64)],
        steer: f64,
        dt: f64,
    ) -> Result<Self> {
        let mut p = Self::defaults(kind, roles)
            .ok_or_else(|| invalid(format!("gait {kind} is not a gait of the library")))?;
        for (key, value) in params {
            p.set(kind, key, *value)?;
        }
        if !steer.is_finite() {
            return Err(invalid(format!("steering must be finite, got {steer}")));
        }
        p.offset_yaw += steer;
        p.validate()?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(invalid(format!(
                "gait dt must be positive and finite, got {dt}"
            )));
        }
        let (yaw, pitch) = (roles.count(JointRole::Yaw), roles.count(JointRole::Pitch));
        let need_yaw = matches!(
            kind,
            GaitKind::Lateral | GaitKind::Sidewind | GaitKind::Roll | GaitKind::Turn
        );
        let need_pitch = matches!(kind, GaitKind::Sidewind | GaitKind::Roll | GaitKind::Linear);
        let lacks = match (need_yaw && yaw == 0, need_pitch && pitch == 0) {
            (true, true) => Some("yaw and pitch joints"),
            (true, false) => Some("yaw joints (axis along z at rest)"),
            (false, true) => Some("pitch joints (axis horizontal and across the body at rest)"),
            (false, false) => None,
        };
        if let Some(what) = lacks {
            return Err(invalid(format!(
                "gait {kind} needs {what}; this robot has {yaw} yaw and {pitch} pitch joints"
            )));
        }
        Ok(Serpenoid {
            kind,
            params: p,
            dt,
            roles: roles.roles.clone(),
            modules: roles.modules.clone(),
            step: 0,
        })
    }

    /// The targets at time `t` (seconds) into `targets`, one per movable joint.
    pub fn targets_at(&self, t: f64, targets: &mut [f64]) {
        let p = &self.params;
        let w = 2.0 * PI / p.period;
        self.shape(p, w * t, p.pitch_rate * w * t, self.ramp_at(t), targets);
    }

    /// The ramp `r(t)` at `t` seconds.
    pub(crate) fn ramp_at(&self, t: f64) -> f64 {
        let ramp = self.params.ramp;
        if ramp > 0.0 {
            (t / ramp).min(1.0)
        } else {
            1.0
        }
    }

    /// The equation with parameters `p` at the yaw wave's temporal phase `yaw_phase` (`w t`), the pitch
    /// wave's `pitch_phase` (`pitch_rate w t`) and ramp `r`, into `targets` (one per movable joint).
    /// The phases are arguments so that a wave whose frequency changes as it runs
    /// ([`super::SteeredWave`]) can accumulate them.
    pub(crate) fn shape(
        &self,
        p: &SerpenoidParams,
        yaw_phase: f64,
        pitch_phase: f64,
        r: f64,
        targets: &mut [f64],
    ) {
        for ((target, role), module) in targets.iter_mut().zip(&self.roles).zip(&self.modules) {
            let n = module.unwrap_or(0) as f64;
            *target = match role {
                JointRole::Yaw => {
                    r * (p.offset_yaw + p.amplitude_yaw * (yaw_phase - p.spatial_yaw * n).sin())
                }
                JointRole::Pitch => {
                    r * (p.offset_pitch
                        + p.amplitude_pitch * (pitch_phase - p.spatial_pitch * n + p.phase).sin())
                }
                JointRole::Other | JointRole::Passive => 0.0,
            };
        }
    }
}

impl Gait for Serpenoid {
    fn next_targets(&mut self, targets: &mut [f64]) {
        // Time from the step count, not a running sum: no drift over an hour of steps.
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

    fn yaw_pitch(n: usize) -> JointRoles {
        JointRoles::new(
            (0..n)
                .map(|k| {
                    if k % 2 == 0 {
                        JointRole::Yaw
                    } else {
                        JointRole::Pitch
                    }
                })
                .collect(),
        )
    }

    #[test]
    fn cube_snake_takes_lateral_and_turn_only() {
        let roles = JointRoles::all_yaw(5);
        for kind in [GaitKind::Lateral, GaitKind::Turn] {
            Serpenoid::new(kind, &roles, &[], 0.0, 1.0 / 240.0).unwrap();
        }
        for kind in [GaitKind::Sidewind, GaitKind::Roll, GaitKind::Linear] {
            let e = Serpenoid::new(kind, &roles, &[], 0.0, 1.0 / 240.0)
                .unwrap_err()
                .to_string();
            assert!(e.contains("needs pitch joints") && !e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn parameters_are_checked_by_name() {
        let roles = yaw_pitch(6);
        let bad = |k: &str, v: f64| {
            Serpenoid::new(
                GaitKind::Sidewind,
                &roles,
                &[(k.into(), v)],
                0.0,
                1.0 / 240.0,
            )
            .unwrap_err()
            .to_string()
        };
        assert!(bad("amplitude_yaw", 9.0).contains("amplitude_yaw"));
        assert!(bad("period", 0.0).contains("period"));
        assert!(bad("period", f64::NAN).contains("period"));
        assert!(bad("wobble", 1.0).contains("unknown gait parameter 'wobble'"));
    }

    #[test]
    fn the_equation_is_the_one_documented() {
        let roles = yaw_pitch(4);
        let params = [("ramp".to_string(), 0.0)];
        let g = Serpenoid::new(GaitKind::Sidewind, &roles, &params, 0.1, 0.01).unwrap();
        let mut t = [0.0; 4];
        g.targets_at(0.7, &mut t);
        let p = g.params;
        let w = 2.0 * PI / p.period;
        assert_eq!(t[0], p.offset_yaw + p.amplitude_yaw * (w * 0.7).sin());
        assert_eq!(
            t[3],
            p.offset_pitch
                + p.amplitude_pitch
                    * (p.pitch_rate * w * 0.7 - p.spatial_pitch * 3.0 + p.phase).sin()
        );
        assert_eq!(p.offset_yaw, 0.1, "steering adds to the yaw offset");
    }

    #[test]
    fn ramp_starts_straight_and_passive_joints_stay_at_zero() {
        let roles = JointRoles::new(vec![JointRole::Passive, JointRole::Yaw, JointRole::Other]);
        let mut g = Serpenoid::new(GaitKind::Turn, &roles, &[], 0.0, 0.01).unwrap();
        let mut t = [1.0; 3];
        g.next_targets(&mut t);
        assert_eq!(t, [0.0; 3]);
        for _ in 0..500 {
            g.next_targets(&mut t);
            assert_eq!((t[0], t[2]), (0.0, 0.0));
        }
        assert!(t[1] != 0.0);
    }
}
