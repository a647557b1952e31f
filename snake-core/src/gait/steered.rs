//! A gait of the library steered as it runs: the wave that the envs' `gait` and `residual` actions
//! drive on a robot whose robot file names one (`wave: {gait: lateral}`).
//!
//! [`Serpenoid`] is a function of time, right for a gait run open loop; an agent changes the wave's
//! steering, amplitude and frequency every env step, and a changed period in `sin(2 pi t / period)`
//! would jump the phase. So this wave accumulates each wave's phase step by step instead (a changed
//! frequency changes only how fast the phase runs), with the same equation (`Serpenoid::shape`).
//!
//! What the three values set, each relative to the gait as the robot file names it (so that the
//! middle of every action range, action 0, is that gait exactly):
//!
//! - `steering`, radians, is added to `offset_yaw` (Tesch et al.'s beta: the shape bends on an arc,
//!   which turns the robot). Which way depends on how far: measured on yaw-pitch-16's lateral wave
//!   (direction of travel over whole gait cycles), an offset of +0.1 rad turns it counter-clockwise
//!   seen from above as it crawls forward (about 15 degrees/s), while +0.5 rad spins it clockwise in
//!   place (the regime of the `turn` gait); so the envs keep it small (see `ActionMode::Gait`);
//! - `amplitude_factor` multiplies `amplitude_yaw` (the lateral wave; the pitch wave, which lifts the
//!   body, keeps its amplitude);
//! - `frequency_factor` multiplies both waves' temporal frequency.
//!
//! The sums and products are kept inside the library's limits ([`crate::limits::GAIT_OFFSET`],
//! [`crate::limits::GAIT_AMPLITUDE`]).

use std::f64::consts::TAU;

use super::{Gait, Serpenoid};
use crate::limits::{GAIT_AMPLITUDE, GAIT_OFFSET};

/// A library gait whose steering, amplitude and frequency change as it runs (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SteeredWave {
    gait: Serpenoid,
    /// Added to the gait's `offset_yaw`, radians (0).
    pub steering: f64,
    /// Multiplies the gait's `amplitude_yaw` (1).
    pub amplitude_factor: f64,
    /// Multiplies the gait's temporal frequency (1).
    pub frequency_factor: f64,
    /// The yaw wave's temporal phase, radians in [0, 2 pi).
    yaw_phase: f64,
    /// The pitch wave's, radians in [0, 2 pi).
    pitch_phase: f64,
    step: u64,
}

impl SteeredWave {
    /// `gait` unsteered, at its start.
    pub fn new(gait: Serpenoid) -> Self {
        SteeredWave {
            gait,
            steering: 0.0,
            amplitude_factor: 1.0,
            frequency_factor: 1.0,
            yaw_phase: 0.0,
            pitch_phase: 0.0,
            step: 0,
        }
    }

    /// The gait it steers.
    pub fn gait(&self) -> &Serpenoid {
        &self.gait
    }

    /// Sets the physics time step, seconds.
    pub fn set_dt(&mut self, dt: f64) {
        self.gait.dt = dt;
    }

    /// The yaw wave's phase at the head (module 0), radians in [0, 2 pi).
    pub fn phase(&self) -> f64 {
        self.yaw_phase
    }
}

/// `phase + step` wrapped into [0, 2 pi): the phase stays small, so its sine keeps full precision
/// over hours of steps.
fn advance(phase: f64, step: f64) -> f64 {
    (phase + step).rem_euclid(TAU)
}

impl Gait for SteeredWave {
    fn next_targets(&mut self, targets: &mut [f64]) {
        let base = &self.gait.params;
        let mut p = *base;
        p.offset_yaw = (base.offset_yaw + self.steering).clamp(GAIT_OFFSET.0, GAIT_OFFSET.1);
        p.amplitude_yaw =
            (base.amplitude_yaw * self.amplitude_factor).clamp(GAIT_AMPLITUDE.0, GAIT_AMPLITUDE.1);
        let r = self.gait.ramp_at(self.step as f64 * self.gait.dt);
        self.gait
            .shape(&p, self.yaw_phase, self.pitch_phase, r, targets);
        let yaw_step = TAU * self.frequency_factor * self.gait.dt / base.period;
        self.yaw_phase = advance(self.yaw_phase, yaw_step);
        self.pitch_phase = advance(self.pitch_phase, base.pitch_rate * yaw_step);
        self.step += 1;
    }

    fn reset(&mut self) {
        self.yaw_phase = 0.0;
        self.pitch_phase = 0.0;
        self.step = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gait::{GaitKind, JointRole, JointRoles};

    fn lateral() -> Serpenoid {
        let roles = JointRoles::new(
            (0..6)
                .map(|k| {
                    if k % 2 == 0 {
                        JointRole::Yaw
                    } else {
                        JointRole::Pitch
                    }
                })
                .collect(),
        );
        Serpenoid::new(GaitKind::Lateral, &roles, &[], 0.0, 1.0 / 240.0).unwrap()
    }

    #[test]
    fn unsteered_it_is_the_gait() {
        let gait = lateral();
        let mut wave = SteeredWave::new(gait.clone());
        let (mut a, mut b) = ([0.0; 6], [0.0; 6]);
        for k in 0..2000 {
            wave.next_targets(&mut a);
            gait.targets_at(k as f64 / 240.0, &mut b);
            for (x, y) in a.iter().zip(&b) {
                assert!((x - y).abs() < 1e-9, "step {k}: {a:?} against {b:?}");
            }
        }
    }

    #[test]
    fn steering_amplitude_and_frequency_act_as_documented() {
        let gait = lateral();
        let p = gait.params;
        let mut wave = SteeredWave::new(gait.clone());
        (wave.steering, wave.amplitude_factor, wave.frequency_factor) = (0.2, 0.5, 2.0);
        let mut t = [0.0; 6];
        // Past the ramp: 1000 steps at twice the frequency is the gait's phase at 2000 steps.
        for _ in 0..1001 {
            wave.next_targets(&mut t);
        }
        let theta = (2.0 * TAU * 1000.0 / 240.0 / p.period).rem_euclid(TAU);
        let yaw = |n: f64| 0.2 + p.amplitude_yaw * 0.5 * (theta - p.spatial_yaw * n).sin();
        assert!((t[0] - yaw(0.0)).abs() < 1e-9 && (t[2] - yaw(2.0)).abs() < 1e-9);
        let pitch = p.amplitude_pitch * ((p.pitch_rate * theta) - p.spatial_pitch + p.phase).sin();
        assert!((t[1] - pitch).abs() < 1e-9, "{} against {pitch}", t[1]);
        assert!((0.0..TAU).contains(&wave.phase()));
        wave.reset();
        wave.next_targets(&mut t);
        assert_eq!(t, [0.0; 6], "reset: the ramp starts straight again");
    }

    #[test]
    fn sums_and_products_stay_within_the_limits() {
        let mut wave = SteeredWave::new(lateral());
        (wave.steering, wave.amplitude_factor) = (5.0, 10.0);
        let mut t = [0.0; 6];
        for _ in 0..1000 {
            wave.next_targets(&mut t);
            assert!(t
                .iter()
                .all(|v| v.abs() <= GAIT_OFFSET.1 + GAIT_AMPLITUDE.1));
        }
    }
}
