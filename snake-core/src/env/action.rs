//! How an action becomes joint targets: the paper's raw joint targets, a steered lateral-undulation
//! wave, or that wave plus a per-joint correction.

use serde::{Deserialize, Serialize};

use crate::error::{invalid_at, Result};
use crate::gait::{Gait, LateralUndulation, SteeredWave};

/// Largest wave amplitude the gait modes accept, radians: beyond about 90 degrees neighbouring cubes
/// (0.5 m, 0.01 m apart) collide.
pub const MAX_GAIT_AMPLITUDE: f64 = 1.5;
/// Largest wave frequency the gait modes accept, Hz: the 10 N m motors under pybullet's default gains
/// follow the 0.4 rad wave of a 0.06 kg snake up to about 2 Hz; faster waves lose amplitude.
pub const MAX_GAIT_FREQUENCY: f64 = 2.0;
/// Largest steering offset, radians (the wave's squash factor `1 / (1 + |steering|)` needs `< 1`).
pub const MAX_GAIT_STEERING: f64 = 0.8;
/// Largest per-joint correction of the residual mode, radians.
pub const MAX_RESIDUAL_SCALE: f64 = 1.5;
/// What an action sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ActionMode {
    /// The paper's: one value per joint, the joint's target angle `clip(a, -1, 1) * action_scale`.
    #[default]
    Joints,
    /// Three values, each mapped linearly from [-1, 1] onto its range: the lateral-undulation wave's
    /// steering, amplitude and frequency. The wave's phase runs on across steps, and the targets follow
    /// the wave at every physics step. On a robot whose robot file names a `wave` (a gait of the
    /// library), all three are relative, so that action 0 is the gait as named: the amplitude and
    /// frequency over the middle of their ranges multiply the gait's yaw amplitude and its frequency,
    /// and the steering over the largest |steering| of its range, times the wave's `steering`
    /// (radians), is subtracted from its yaw offset, which turns the robot the way a steering of the
    /// sine wave does (positive: clockwise seen from above; [`SteeredWave`]).
    Gait,
    /// One value per joint: the default wave's target (amplitude 0.4 rad, period 1.5 s, as pybullet's
    /// snake.py) plus `clip(a, -1, 1) * residual_scale` radians.
    Residual,
}

impl ActionMode {
    /// The configuration name.
    pub fn name(self) -> &'static str {
        match self {
            ActionMode::Joints => "joints",
            ActionMode::Gait => "gait",
            ActionMode::Residual => "residual",
        }
    }

    /// Whether a wave drives the joints (the gait and residual modes).
    pub fn uses_wave(self) -> bool {
        self != ActionMode::Joints
    }
}

/// The action mode and its parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActionConfig {
    /// What an action sets (`joints`).
    pub mode: ActionMode,
    /// Gait mode: range of the wave's steering offset, radians ([-0.5, 0.5]; see
    /// [`LateralUndulation::steering`]).
    pub steering: [f64; 2],
    /// Gait mode: range of the wave's amplitude, radians ([0.2, 0.6]).
    pub amplitude: [f64; 2],
    /// Gait mode: range of the wave's frequency, Hz ([0.4, 1.0]; pybullet's snake.py: 1 / 1.5 s).
    pub frequency: [f64; 2],
    /// Residual mode: the largest correction added to the wave's target, radians (0.3).
    pub residual_scale: f64,
}

impl Default for ActionConfig {
    fn default() -> Self {
        ActionConfig {
            mode: ActionMode::Joints,
            steering: [-0.5, 0.5],
            amplitude: [0.2, 0.6],
            frequency: [0.4, 1.0],
            residual_scale: 0.3,
        }
    }
}

impl ActionConfig {
    /// Length of an action for a snake of `joints` joints.
    pub fn dim(&self, joints: usize) -> usize {
        match self.mode {
            ActionMode::Gait => 3,
            ActionMode::Joints | ActionMode::Residual => joints,
        }
    }

    /// Checks the ranges of the chosen mode; the error names the field and the allowed range.
    pub fn validate(&self) -> Result<()> {
        let ranges = [
            (
                "action.steering",
                self.steering,
                -MAX_GAIT_STEERING,
                MAX_GAIT_STEERING,
            ),
            ("action.amplitude", self.amplitude, 0.0, MAX_GAIT_AMPLITUDE),
            ("action.frequency", self.frequency, 0.0, MAX_GAIT_FREQUENCY),
        ];
        for (name, [low, high], min, max) in ranges {
            let inside = |v: f64| v.is_finite() && v >= min && v <= max;
            if !(inside(low) && inside(high) && low <= high) {
                return Err(invalid_at(
                    name,
                    format!(
                    "must be a range [low, high] with {min} <= low <= high <= {max}, got [{low}, {high}]"
                )));
            }
        }
        if self.frequency[0] <= 0.0 {
            return Err(invalid_at(
                "action.frequency",
                format!(
                    "must be above 0 Hz, got [{}, {}]",
                    self.frequency[0], self.frequency[1]
                ),
            ));
        }
        let r = self.residual_scale;
        if !(r.is_finite() && (0.0..=MAX_RESIDUAL_SCALE).contains(&r)) {
            return Err(invalid_at(
                "action.residual_scale",
                format!("must be in [0, {MAX_RESIDUAL_SCALE}], got {r}"),
            ));
        }
        Ok(())
    }
}

/// `low + (high - low) * (a + 1) / 2` for `a` in [-1, 1].
fn lerp([low, high]: [f64; 2], a: f64) -> f64 {
    low + (high - low) * (a + 1.0) * 0.5
}

/// `value / middle of range`, the factor a relative action sets (0 for a range of [0, 0]).
fn relative([low, high]: [f64; 2], value: f64) -> f64 {
    let middle = 0.5 * (low + high);
    if middle > 0.0 {
        value / middle
    } else {
        0.0
    }
}

/// `value / largest |bound|`, in [-1, 1] (0 for a range of [0, 0]).
fn relative_to_bound([low, high]: [f64; 2], value: f64) -> f64 {
    let bound = low.abs().max(high.abs());
    if bound > 0.0 {
        value / bound
    } else {
        0.0
    }
}

/// The wave the gait and residual modes drive.
#[derive(Debug, Clone)]
enum Wave {
    /// pybullet's snake.py wave (the cube snake's, or a robot file's `gait`).
    Sine(LateralUndulation),
    /// A gait of the library, named by a robot file's `wave`, with the yaw offset of a full steering.
    Library(SteeredWave, f64),
}

impl Wave {
    fn as_gait(&mut self) -> &mut dyn Gait {
        match self {
            Wave::Sine(w) => w,
            Wave::Library(w, _) => w,
        }
    }
}

/// Turns each env step's action into joint targets for every physics step.
#[derive(Debug, Clone)]
pub(crate) struct Driver {
    config: ActionConfig,
    action_scale: f64,
    wave: Wave,
    /// The clipped action of the current env step.
    action: Vec<f64>,
}

impl Driver {
    pub fn new(config: &super::EnvConfig) -> Self {
        let (dt, half_extent) = (config.snake.dt, config.snake.half_extent);
        let spec = config.robot.as_ref().map(|r| r.spec());
        let wave = if let Some(robot_wave) = spec.and_then(|s| s.wave.clone()) {
            // A robot file's library gait.
            let mut wave = SteeredWave::new(robot_wave.gait);
            wave.set_dt(dt);
            Wave::Library(wave, robot_wave.steering)
        } else {
            // A robot's own sine wave (its robot file's `gait`), else snake.py's along cubes of the
            // snake's size.
            let robot_wave = spec.and_then(|s| s.gait.clone());
            let has_robot_wave = robot_wave.is_some();
            let mut wave = robot_wave.unwrap_or_default();
            wave.dt = dt;
            if !has_robot_wave {
                wave.segment_length = half_extent * 2.0;
            }
            Wave::Sine(wave)
        };
        Driver {
            config: config.action,
            action_scale: config.action_scale,
            wave,
            // Sized once: stepping stays allocation-free.
            action: Vec::with_capacity(config.action_dim()),
        }
    }

    /// Back to the wave's start (an episode's first step ramps the wave in again).
    pub fn reset(&mut self) {
        self.wave.as_gait().reset();
        self.action.clear();
    }

    /// Takes this env step's action, clipped to [-1, 1] (finite values; checked by the caller).
    pub fn set_action(&mut self, action: impl Iterator<Item = f64>) {
        self.action.clear();
        self.action.extend(action.map(|a| a.clamp(-1.0, 1.0)));
        if self.config.mode == ActionMode::Gait {
            let c = &self.config;
            let [steering_action, amplitude_action, frequency_action] =
                [self.action[0], self.action[1], self.action[2]];
            let steering = lerp(c.steering, steering_action);
            let amplitude = lerp(c.amplitude, amplitude_action);
            let frequency = lerp(c.frequency, frequency_action);
            match &mut self.wave {
                Wave::Sine(w) => {
                    w.steering = steering;
                    w.amplitude = amplitude;
                    w.period = 1.0 / frequency;
                }
                Wave::Library(w, full_steering) => {
                    // Minus: a positive yaw offset turns a crawling robot counter-clockwise.
                    w.steering = -relative_to_bound(c.steering, steering) * *full_steering;
                    w.amplitude_factor = relative(c.amplitude, amplitude);
                    w.frequency_factor = relative(c.frequency, frequency);
                }
            }
        }
    }

    /// The clipped action of the current step.
    pub fn action(&self) -> &[f64] {
        &self.action
    }

    /// Whether the targets change within an env step (the wave modes), so that they are set before
    /// every physics step rather than once per env step.
    pub fn per_physics_step(&self) -> bool {
        self.config.mode.uses_wave()
    }

    /// Writes the targets of the next physics step (advancing the wave).
    pub fn next_targets(&mut self, targets: &mut [f64]) {
        match self.config.mode {
            ActionMode::Joints => {
                for (t, a) in targets.iter_mut().zip(&self.action) {
                    *t = a * self.action_scale;
                }
            }
            ActionMode::Gait => self.wave.as_gait().next_targets(targets),
            ActionMode::Residual => {
                self.wave.as_gait().next_targets(targets);
                for (t, a) in targets.iter_mut().zip(&self.action) {
                    *t += a * self.config.residual_scale;
                }
            }
        }
    }

    /// The wave's phase at the head, radians in [0, 2 pi).
    pub fn wave_phase(&self) -> f64 {
        match &self.wave {
            Wave::Sine(w) => {
                let turns = w.wave_front() / w.wave_length;
                (turns - turns.floor()) * std::f64::consts::TAU
            }
            Wave::Library(w, _) => w.phase(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gait_actions_map_onto_the_ranges() {
        let mut d = Driver::new(&super::super::EnvConfig {
            action: ActionConfig {
                mode: ActionMode::Gait,
                ..ActionConfig::default()
            },
            ..Default::default()
        });
        let sine = |d: &Driver| match &d.wave {
            Wave::Sine(w) => w.clone(),
            Wave::Library(..) => panic!("the cube snake's wave is the sine"),
        };
        d.set_action([-1.0, 1.0, 0.0].into_iter());
        assert_eq!(sine(&d).steering, -0.5);
        assert_eq!(sine(&d).amplitude, 0.6);
        assert_eq!(sine(&d).period, 1.0 / 0.7);
        d.set_action([5.0, -5.0, 1.0].into_iter());
        assert_eq!(d.action(), &[1.0, -1.0, 1.0]);
        assert_eq!((sine(&d).steering, sine(&d).amplitude), (0.5, 0.2));
    }

    #[test]
    fn residual_adds_the_correction_to_the_default_wave() {
        let mut d = Driver::new(&super::super::EnvConfig {
            snake: crate::Preset::Paper.config(4),
            action: ActionConfig {
                mode: ActionMode::Residual,
                ..ActionConfig::default()
            },
            ..Default::default()
        });
        let mut wave = LateralUndulation::default();
        let (mut t, mut w) = ([0.0; 4], [0.0; 4]);
        for _ in 0..500 {
            d.set_action([0.5, -0.5, 2.0, 0.0].into_iter());
            d.next_targets(&mut t);
            wave.next_targets(&mut w);
            let expected = [w[0] + 0.15, w[1] - 0.15, w[2] + 0.3, w[3]];
            assert_eq!(t, expected);
        }
        assert!(d.wave_phase() >= 0.0 && d.wave_phase() < std::f64::consts::TAU);
    }

    #[test]
    fn a_robot_files_wave_is_steered_relative_to_the_gait() {
        use crate::gait::Serpenoid;
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/yaw-pitch-16.yaml");
        let robot = crate::RobotRef::load(&path).unwrap();
        let wave = robot
            .spec()
            .wave
            .clone()
            .expect("yaw-pitch-16 names a wave");
        let config = super::super::EnvConfig {
            robot: Some(robot),
            ..super::super::EnvConfig::goal_task(crate::Preset::Paper, 5)
        };
        let joints = config.joints();
        let targets = |action: [f64; 3], steps: usize| {
            let mut d = Driver::new(&config);
            let mut t = vec![0.0; joints];
            for _ in 0..steps {
                d.set_action(action.into_iter());
                d.next_targets(&mut t);
            }
            t
        };
        // Action 0 is the gait as the robot file names it.
        let mut expected = vec![0.0; joints];
        let steps = 1000;
        wave.gait
            .targets_at((steps - 1) as f64 * config.snake.dt, &mut expected);
        for (a, b) in targets([0.0; 3], steps).iter().zip(&expected) {
            assert!((a - b).abs() < 1e-9, "{a} against {b}");
        }
        // A full steering subtracts the wave's steering from every yaw joint (the ramp is over).
        let gait: &Serpenoid = &wave.gait;
        let steered = targets([1.0, 0.0, 0.0], steps);
        for ((s, e), role) in steered.iter().zip(&expected).zip(&gait.roles) {
            let shift = if *role == crate::gait::JointRole::Yaw {
                -wave.steering
            } else {
                0.0
            };
            assert!((s - e - shift).abs() < 1e-9, "{s} against {e} + {shift}");
        }
        // Amplitude and frequency at the top of their ranges: 0.6 / 0.4 and 1.0 / 0.7 of the gait's.
        let mut fast = Serpenoid::clone(gait);
        fast.params.amplitude_yaw *= 0.6 / 0.4;
        fast.params.period /= 1.0 / 0.7;
        let mut expected_fast = vec![0.0; joints];
        fast.targets_at((steps - 1) as f64 * config.snake.dt, &mut expected_fast);
        for (a, b) in targets([0.0, 1.0, 1.0], steps).iter().zip(&expected_fast) {
            assert!((a - b).abs() < 1e-9, "{a} against {b}");
        }
    }

    #[test]
    fn bad_ranges_name_the_field() {
        for (config, field) in [
            (
                ActionConfig {
                    frequency: [0.0, 1.0],
                    ..ActionConfig::default()
                },
                "action.frequency",
            ),
            (
                ActionConfig {
                    amplitude: [0.5, 0.2],
                    ..ActionConfig::default()
                },
                "action.amplitude",
            ),
            (
                ActionConfig {
                    steering: [-0.9, 0.0],
                    ..ActionConfig::default()
                },
                "action.steering",
            ),
            (
                ActionConfig {
                    residual_scale: f64::NAN,
                    ..ActionConfig::default()
                },
                "action.residual_scale",
            ),
        ] {
            let message = config.validate().unwrap_err().to_string();
            assert!(message.contains(field), "{message}");
        }
    }
}
