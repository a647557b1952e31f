//! `sine`: pybullet's `examples/snake.py` wave, kept bit for bit (the paper's gait and the parity
//! tests' drive).

use serde::{Deserialize, Serialize};

use super::Gait;
use crate::error::{invalid, Result};
use crate::limits::{check_range, short, GAIT_AMPLITUDE, GAIT_LENGTH, GAIT_PERIOD};

/// Lateral undulation as pybullet's `examples/snake.py` drives it: a sine wave of joint angles that
/// travels from the head (the base) to the tail.
///
/// For joint `i`: `target_i = A sin(2 pi frac((front - (i + 1) seg) / wave_length))`, scaled by a ramp
/// while the wave front is within the first `ramp_segments` segments, then steered: a positive
/// `steering` squashes the negative half of the wave by `1 / (1 + steering)` (a negative one the
/// positive half by `1 / (1 - steering)`) and adds `steering` to every target. The front advances by
/// `dt / period * wave_length` per step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LateralUndulation {
    /// Wave amplitude A, radians (0.4).
    pub amplitude: f64,
    /// Wave period, seconds (1.5).
    pub period: f64,
    /// Wave length, metres (4).
    pub wave_length: f64,
    /// Segment length, metres (0.5: the cube size).
    pub segment_length: f64,
    /// The amplitude ramps in while the front is within this many segments (4).
    pub ramp_segments: f64,
    /// Steering offset, radians (0 goes straight; snake.py's keys set +-0.2).
    pub steering: f64,
    /// Physics time step, seconds (1/240).
    pub dt: f64,
    /// snakebot-gym's quirk: its ramp scale is never reset to 1, so after the ramp the wave keeps the
    /// last ramp value (about 0.994). Off by default (pybullet's snake.py).
    pub keep_last_ramp_scale: bool,
    #[serde(skip)]
    front: f64,
    #[serde(skip)]
    scale: f64,
}

/// The `--gait-param` keys of `sine`.
pub const PARAM_KEYS: [&str; 5] = [
    "amplitude",
    "period",
    "wave_length",
    "segment_length",
    "ramp_segments",
];

impl Default for LateralUndulation {
    fn default() -> Self {
        LateralUndulation {
            amplitude: 0.4,
            period: 1.5,
            wave_length: 4.0,
            segment_length: 0.25 * 2.0,
            ramp_segments: 4.0,
            steering: 0.0,
            dt: 1.0 / 240.0,
            keep_last_ramp_scale: false,
            front: 0.0,
            scale: 1.0,
        }
    }
}

impl LateralUndulation {
    /// Checks the parameters; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("period", self.period),
            ("wave_length", self.wave_length),
            ("dt", self.dt),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid(format!(
                    "gait {name} must be positive and finite, got {}",
                    short(v)
                )));
            }
        }
        // The same ranges as the library's gaits, where the parameter means the same.
        for (name, v, (lo, hi)) in [
            ("amplitude", self.amplitude, GAIT_AMPLITUDE),
            ("period", self.period, GAIT_PERIOD),
            ("wave_length", self.wave_length, GAIT_LENGTH),
            ("segment_length", self.segment_length, GAIT_LENGTH),
            ("ramp_segments", self.ramp_segments, GAIT_LENGTH),
        ] {
            check_range(&format!("gait {name}"), v, lo, hi)?;
        }
        if !self.steering.is_finite() {
            return Err(invalid(format!(
                "gait steering must be finite, got {}",
                self.steering
            )));
        }
        if self.steering <= -1.0 {
            return Err(invalid(format!(
                "gait steering must be > -1, got {}",
                self.steering
            )));
        }
        Ok(())
    }

    /// Sets one parameter by its `--gait-param` key ([`PARAM_KEYS`]); steering and `dt` come from their
    /// own flags.
    pub fn set(&mut self, key: &str, value: f64) -> Result<()> {
        let field = match key {
            "amplitude" => &mut self.amplitude,
            "period" => &mut self.period,
            "wave_length" => &mut self.wave_length,
            "segment_length" => &mut self.segment_length,
            "ramp_segments" => &mut self.ramp_segments,
            _ => {
                return Err(invalid(format!(
                    "unknown gait parameter '{key}' for gait sine (expected one of: {})",
                    PARAM_KEYS.join(", ")
                )))
            }
        };
        *field = value;
        Ok(())
    }

    /// The default wave with a steering offset (radians, > -1).
    pub fn with_steering(mut self, steering: f64) -> Self {
        self.steering = steering;
        self
    }

    /// Where the wave front is now, metres travelled along the body.
    pub fn wave_front(&self) -> f64 {
        self.front
    }
}

impl Gait for LateralUndulation {
    fn next_targets(&mut self, targets: &mut [f64]) {
        // The operation order follows snake.py exactly so that targets agree to the last bit.
        let ramp_end = self.segment_length * self.ramp_segments;
        if !self.keep_last_ramp_scale {
            self.scale = 1.0;
        }
        if self.front < ramp_end {
            self.scale = self.front / ramp_end;
        }
        for (segment, target) in targets.iter_mut().enumerate() {
            let mut phase =
                (self.front - (segment + 1) as f64 * self.segment_length) / self.wave_length;
            phase -= phase.floor();
            phase *= std::f64::consts::PI * 2.0;
            let mut t = phase.sin() * self.scale * self.amplitude;
            if self.steering > 0.0 && t < 0.0 {
                t *= 1.0 / (1.0 + self.steering);
            }
            if self.steering < 0.0 && t > 0.0 {
                t *= 1.0 / (1.0 - self.steering);
            }
            *target = t + self.steering;
        }
        self.front += self.dt / self.period * self.wave_length;
    }

    fn reset(&mut self) {
        self.front = 0.0;
        self.scale = 1.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_step_is_flat_then_ramps() {
        let mut g = LateralUndulation::default();
        let mut t = [0.0; 3];
        g.next_targets(&mut t);
        assert_eq!(t, [0.0; 3], "front 0: ramp scale 0");
        g.next_targets(&mut t);
        assert!(t.iter().all(|v| v.abs() < 0.4 * 0.01));
    }

    #[test]
    fn steady_wave_has_the_amplitude() {
        let mut g = LateralUndulation::default();
        let mut t = [0.0; 8];
        let mut max: f64 = 0.0;
        for _ in 0..2000 {
            g.next_targets(&mut t);
            max = t.iter().fold(max, |m, v| m.max(v.abs()));
        }
        assert!(max > 0.399 && max <= 0.4, "max {max}");
    }

    #[test]
    fn steering_squashes_one_side() {
        let mut g = LateralUndulation::default().with_steering(0.2);
        let mut t = [0.0; 8];
        let (mut lo, mut hi) = (f64::MAX, f64::MIN);
        for _ in 0..2000 {
            g.next_targets(&mut t);
            for v in t {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        assert!((hi - 0.6).abs() < 1e-3, "hi {hi}");
        assert!((lo - (0.2 - 0.4 / 1.2)).abs() < 1e-3, "lo {lo}");
    }
}
