//! Maladen et al.'s travelling sine wave for sand-swimming (issue 59): the robot sandfish's gait.
//!
//! R. D. Maladen, Y. Ding, P. B. Umbanhowar, D. I. Goldman, "Undulatory swimming in sand: experimental
//! and simulation studies of a robotic sandfish", IJRR 30(7):793-805, 2011, drive the robot so that its
//! body takes the shape of a sine wave travelling from head to tail, `y = A sin(2 pi (x / lambda + f t))`
//! along the body's axis `x` (the head at 0, the body along -x), of amplitude `A`, wavelength `lambda`
//! and frequency `f`; they report its performance as the wave efficiency (forward speed over the wave
//! speed `lambda f`) against `A / lambda`. Each segment (of `segment` metres, the head's first) takes the
//! slope of the wave at its centre, `theta_k = atan(2 pi A / lambda cos(2 pi (x_k / lambda + f t)))`
//! with `x_k = -(k + 1/2) segment`, and joint `k` (between segments `k` and `k + 1`) the difference
//! `theta_(k+1) - theta_k`: the chain follows the curve at its segments' centres. Only yaw joints move;
//! every other joint holds 0.
//!
//! By name: `snake-cli run --gait sandfish --gait-param amplitude=A --gait-param wavelength=L
//! --gait-param frequency=F --gait-param segment=S` ([`PARAM_KEYS`], over [`DEFAULTS`]: the robot
//! sandfish's, `robots/sandfish-robot.yaml`).

use serde::Serialize;

use super::joints::{JointRole, JointRoles};
use super::{Gait, GaitKind};
use crate::error::{invalid, Result};
use crate::limits::{check_range_above, GAIT_LENGTH, GAIT_PERIOD};

/// The `--gait-param` keys of `sandfish`, as Maladen et al. name the wave's parameters (metres, Hz).
pub const PARAM_KEYS: [&str; 4] = ["amplitude", "wavelength", "frequency", "segment"];

/// The wave's defaults: the robot sandfish's (`robots/sandfish-robot.yaml`, docs/media.md): one wave
/// on its 0.455 m body (seven 0.065 m segments), A/lambda 0.2 (where Maladen et al. found the wave
/// efficiency highest), 1 Hz.
pub const DEFAULTS: SandfishWave = SandfishWave {
    amplitude: 0.091,
    wavelength: 0.455,
    frequency: 1.0,
    segment: 0.065,
};

/// Sets one parameter of `wave` by its `--gait-param` key; an unknown key lists the known ones.
pub fn set(wave: &mut SandfishWave, key: &str, value: f64) -> Result<()> {
    let slot = match key {
        "amplitude" => &mut wave.amplitude,
        "wavelength" => &mut wave.wavelength,
        "frequency" => &mut wave.frequency,
        "segment" => &mut wave.segment,
        _ => {
            return Err(invalid(format!(
                "unknown gait parameter '{key}' for gait {} (expected one of: {})",
                GaitKind::Sandfish,
                PARAM_KEYS.join(", ")
            )))
        }
    };
    *slot = value;
    Ok(())
}

/// The wave's parameters as Maladen et al. define them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SandfishWave {
    /// Amplitude `A`, metres.
    pub amplitude: f64,
    /// Wavelength `lambda`, metres.
    pub wavelength: f64,
    /// Frequency `f`, Hz.
    pub frequency: f64,
    /// Length of one segment (the distance between joints), metres.
    pub segment: f64,
}

impl SandfishWave {
    /// Checks the parameters: positive and finite, the period and the lengths within the gait limits.
    pub fn validate(&self) -> Result<()> {
        check_range_above("gait amplitude", self.amplitude, 0.0, GAIT_LENGTH.1)?;
        check_range_above("gait wavelength", self.wavelength, 0.0, GAIT_LENGTH.1)?;
        check_range_above("gait segment", self.segment, 0.0, GAIT_LENGTH.1)?;
        check_range_above("gait frequency", self.frequency, 0.0, 1.0 / GAIT_PERIOD.0)?;
        Ok(())
    }

    /// Every segment's heading (the wave's slope angle at its centre) at time `t`, into `headings`.
    pub fn headings(&self, t: f64, headings: &mut [f64]) {
        use std::f64::consts::TAU;
        let k = TAU / self.wavelength;
        for (i, h) in headings.iter_mut().enumerate() {
            let x = -(i as f64 + 0.5) * self.segment;
            *h = (self.amplitude * k * (k * x + TAU * self.frequency * t).cos()).atan();
        }
    }
}

/// [`SandfishWave`] on a robot's yaw joints, one physics step at a time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SandfishGait {
    /// The wave it drives.
    pub wave: SandfishWave,
    yaw: Vec<usize>,
    joints: usize,
    dt: f64,
    step: u64,
    headings: Vec<f64>,
}

impl SandfishGait {
    /// The wave on the yaw joints of `roles` (head first), stepped every `dt` seconds; fails on bad
    /// parameters or a robot without yaw joints.
    pub fn new(wave: SandfishWave, roles: &JointRoles, dt: f64) -> Result<Self> {
        wave.validate()?;
        let yaw: Vec<usize> = roles
            .roles
            .iter()
            .enumerate()
            .filter(|(_, r)| **r == JointRole::Yaw)
            .map(|(j, _)| j)
            .collect();
        if yaw.is_empty() {
            return Err(invalid(
                "the sandfish wave needs yaw joints; this robot has none",
            ));
        }
        Ok(SandfishGait {
            wave,
            headings: vec![0.0; yaw.len() + 1],
            yaw,
            joints: roles.roles.len(),
            dt,
            step: 0,
        })
    }
}

impl Gait for SandfishGait {
    fn next_targets(&mut self, targets: &mut [f64]) {
        self.step += 1;
        let t = self.step as f64 * self.dt;
        self.wave.headings(t, &mut self.headings);
        for v in targets.iter_mut().take(self.joints) {
            *v = 0.0;
        }
        for (k, &j) in self.yaw.iter().enumerate() {
            targets[j] = self.headings[k + 1] - self.headings[k];
        }
    }

    fn reset(&mut self) {
        self.step = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chain_follows_the_wave_travelling_to_the_tail() {
        let wave = SandfishWave {
            amplitude: 0.091,
            wavelength: 0.455,
            frequency: 1.0,
            segment: 0.065,
        };
        let roles = JointRoles::all_yaw(6);
        let mut gait = SandfishGait::new(wave, &roles, 1.0 / 240.0).unwrap();
        let mut targets = vec![0.0; 6];
        gait.next_targets(&mut targets);
        // Joint 0 at t = dt: the slope difference of segments 1 and 0.
        let mut h = vec![0.0; 7];
        wave.headings(1.0 / 240.0, &mut h);
        assert_eq!(targets[0], h[1] - h[0]);
        // A quarter period later the pattern has moved a quarter wavelength towards the tail: the
        // heading at x then equals the heading at x + lambda/4 now (phase k x + 2 pi f t).
        let mut later = vec![0.0; 7];
        wave.headings(0.25, &mut later);
        let k = std::f64::consts::TAU / wave.wavelength;
        let x = -0.5 * wave.segment;
        let expect = (wave.amplitude * k * (k * (x + wave.wavelength / 4.0)).cos()).atan();
        assert!((later[0] - expect).abs() < 1e-12);
    }

    #[test]
    fn parameters_by_name_over_the_robot_sandfishs_defaults() {
        let mut wave = DEFAULTS;
        set(&mut wave, "frequency", 1.5).unwrap();
        set(&mut wave, "amplitude", 0.05).unwrap();
        assert_eq!(wave.frequency, 1.5);
        assert_eq!(wave.amplitude, 0.05);
        assert_eq!(wave.wavelength, 0.455);
        let e = set(&mut wave, "alpha", 1.0).unwrap_err().to_string();
        assert!(
            e.contains("'alpha'") && e.contains("sandfish") && e.contains("amplitude, wavelength"),
            "{e}"
        );
    }

    #[test]
    fn by_name_it_is_the_same_wave() {
        use crate::gait::{GaitChoice, LateralUndulation};
        let kind: GaitKind = "sandfish".parse().unwrap();
        let roles = JointRoles::all_yaw(6);
        let params = [("frequency".to_string(), 1.5)];
        let dt = 1.0 / 240.0;
        let choice =
            GaitChoice::new(kind, &params, 0.0, &roles, LateralUndulation::default(), dt).unwrap();
        let GaitChoice::Sandfish(mut named) = choice else {
            panic!("sandfish made {choice:?}");
        };
        let wave = SandfishWave {
            frequency: 1.5,
            ..DEFAULTS
        };
        let mut direct = SandfishGait::new(wave, &roles, dt).unwrap();
        let (mut a, mut b) = (vec![0.0; 6], vec![0.0; 6]);
        for _ in 0..100 {
            named.next_targets(&mut a);
            direct.next_targets(&mut b);
            assert_eq!(a, b);
        }
        let steered = GaitChoice::new(kind, &[], 0.2, &roles, LateralUndulation::default(), dt);
        assert!(steered.unwrap_err().to_string().contains("no steering"));
    }

    #[test]
    fn bad_parameters_are_refused() {
        let roles = JointRoles::all_yaw(2);
        let bad = SandfishWave {
            amplitude: -1.0,
            wavelength: 0.4,
            frequency: 1.0,
            segment: 0.06,
        };
        assert!(SandfishGait::new(bad, &roles, 1.0 / 240.0)
            .unwrap_err()
            .to_string()
            .contains("amplitude"));
    }
}
