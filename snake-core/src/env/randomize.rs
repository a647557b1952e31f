//! Randomized physics ([`Randomize`], the env keyword `randomize`): per-episode draws of the ground's
//! friction, the masses, the motors, the action latency, the observation noise, the skin friction and
//! a water current (the speed and heading of the world's water, docs/media.md), as Isaac Lab's event manager and MuJoCo Playground randomize them for transfer to real robots.
//!
//! ## The stream
//!
//! Every reset draws from the env's *physics stream*, never from its main stream, so the start, the
//! goal and the terrain of a seed are those of the plain env: `reset(Some(seed))` seeds it as
//! `ChaCha12Rng::seed_from_u64(seed)` moved to stream [`PHYSICS_STREAM`] (`set_stream`: the same key,
//! another of ChaCha's 2^64 independent streams); `reset(None)` continues it. The observation noise
//! of the steps comes from a third stream, [`NOISE_STREAM`], seeded and continued alike, so that the
//! physics stream is read at resets only: the same seed draws the same physics for its first
//! episode and for every later one, however many steps the episodes before took (two controllers
//! evaluated on a seed's episodes meet the same physics in each).
//!
//! Each configured key takes one uniform number `u` in [0, 1) in the order of [`Randomize`]'s fields,
//! and the value is `low + (high - low) * u` (`latency_steps`: `low + floor(u * (high - low + 1))`);
//! zero-width ranges give `low` exactly.

use rand::Rng;
use rand_chacha::ChaCha12Rng;
use serde::{Deserialize, Serialize};

use crate::error::{invalid_at, Result};
use crate::limits::{
    check_key_interval, short, MAX_CURRENT, MAX_LATENCY_STEPS, MAX_OBS_NOISE, MAX_PHYSICS_SCALE,
    MAX_WORLD_FRICTION, MAX_YAW, MIN_PHYSICS_SCALE,
};
use crate::Body;

/// The physics stream's number: "RANDOMIZ" in ASCII. Any value other than the main stream's (0) would
/// do; this one is fixed so that a seed's draws never change.
pub const PHYSICS_STREAM: u64 = 0x5241_4e44_4f4d_495a;

/// The observation noise's stream: "OBSNOISE" in ASCII, fixed for the same reason.
pub const NOISE_STREAM: u64 = 0x4f42_534e_4f49_5345;

/// Ranges `[low, high]` of the physics drawn at every reset (the env keyword `randomize`); a key left
/// out is not randomized (nominal physics). Drawn in this order, one number per given key.
///
/// ```yaml
/// randomize:
///   ground_friction: [0.25, 1.0]   # the ground's lateral friction (absolute; the plane's is 0.5)
///   mass_scale: [0.8, 1.2]         # every link's mass times this (inertia follows, as changeDynamics)
///   effort_scale: [0.7, 1.0]       # every motor's force limit times this
///   kp_scale: [0.9, 1.1]           # the position gain times this
///   kd_scale: [0.9, 1.1]           # the velocity gain times this
///   latency_steps: [0, 1]          # actions reach the motors this many env steps late
///   obs_noise: [0.0, 0.01]         # std of the Gaussian noise on the returned observation
///   skin_friction_scale: [0.8, 1.2]   # skin friction coefficients times this (skin bodies only)
///   current_speed: [0.0, 0.3]      # the water's current, m/s (worlds with water only)
///   current_heading: [-3.1416, 3.1416]   # its direction, radians from world +x, counterclockwise
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Randomize {
    /// The ground's lateral friction (`changeDynamics(ground, -1, lateralFriction=...)`), absolute,
    /// in [0, [`MAX_WORLD_FRICTION`]].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ground_friction: Option<[f64; 2]>,
    /// Factor on the mass of the base and every link (massless parts and a fixed base keep theirs):
    /// `changeDynamics(mass=m * scale)`, which also recomputes each part's inertia from its collision
    /// shape, as pybullet does (a robot with `inertia: file` loses its file's inertia then, unless the
    /// drawn factor is exactly 1, which changes nothing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass_scale: Option<[f64; 2]>,
    /// Factor on every motor's force limit (the snake's `motor_force`, a robot's URDF efforts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub effort_scale: Option<[f64; 2]>,
    /// Factor on the motors' position gain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kp_scale: Option<[f64; 2]>,
    /// Factor on the motors' velocity gain.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kd_scale: Option<[f64; 2]>,
    /// Whole env steps an action reaches the motors late, in [0, [`MAX_LATENCY_STEPS`]]: with `k`,
    /// step `t` drives the motors with the action of step `t - k`, and the first `k` steps of an
    /// episode with the zero action (the reset's, as the smoothness term's previous action). The
    /// reward's action terms see the action the motors got.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub latency_steps: Option<[f64; 2]>,
    /// Standard deviation of the Gaussian noise added to every value of the observation returned to
    /// the agent, in [0, [`MAX_OBS_NOISE`]]; the reward and the termination use the noiseless one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obs_noise: Option<[f64; 2]>,
    /// Factor on the skin friction coefficients (forward, backward, transverse) of every part that
    /// has skin friction; only for a body with skin friction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin_friction_scale: Option<[f64; 2]>,
    /// The speed of the current of every water entry of the world, m/s in [0, [`MAX_CURRENT`]]: the
    /// drawn current `(s cos h, s sin h, 0)` with `h` from `current_heading` (0, along world +x,
    /// without it) replaces the world file's; only in a world with water.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub current_speed: Option<[f64; 2]>,
    /// The current's heading, radians from world +x, counterclockwise, within +-[`MAX_YAW`]; only
    /// with `current_speed`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub current_heading: Option<[f64; 2]>,
}

/// The physics one reset drew ([`Randomize`]'s keys that were given, each with its drawn value).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Physics {
    /// The ground's lateral friction.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ground_friction: Option<f64>,
    /// Factor on the masses.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mass_scale: Option<f64>,
    /// Factor on the motor force limits.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub effort_scale: Option<f64>,
    /// Factor on the position gain.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kp_scale: Option<f64>,
    /// Factor on the velocity gain.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kd_scale: Option<f64>,
    /// Env steps of action latency.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub latency_steps: Option<u32>,
    /// Standard deviation of the observation noise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub obs_noise: Option<f64>,
    /// Factor on the skin friction coefficients.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skin_friction_scale: Option<f64>,
    /// The water current's speed, m/s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub current_speed: Option<f64>,
    /// The water current's heading, radians.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub current_heading: Option<f64>,
}

impl Physics {
    /// Every drawn value by its key, in [`Randomize`]'s order (latency as a float).
    pub fn values(&self) -> impl Iterator<Item = (&'static str, f64)> {
        [
            ("ground_friction", self.ground_friction),
            ("mass_scale", self.mass_scale),
            ("effort_scale", self.effort_scale),
            ("kp_scale", self.kp_scale),
            ("kd_scale", self.kd_scale),
            ("latency_steps", self.latency_steps.map(f64::from)),
            ("obs_noise", self.obs_noise),
            ("skin_friction_scale", self.skin_friction_scale),
            ("current_speed", self.current_speed),
            ("current_heading", self.current_heading),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.map(|v| (k, v)))
    }
}

impl Randomize {
    /// Checks every range; the one-line error names the key (`randomize.mass_scale ...`).
    /// `has_skin`: whether the body has skin friction (`skin_friction_scale` needs it); `has_water`:
    /// whether the world has water (`current_speed` needs it).
    pub fn validate(&self, has_skin: bool, has_water: bool) -> Result<()> {
        let scale = (MIN_PHYSICS_SCALE, MAX_PHYSICS_SCALE);
        for (key, range, (low_bound, high_bound)) in [
            (
                "ground_friction",
                self.ground_friction,
                (0.0, MAX_WORLD_FRICTION),
            ),
            ("mass_scale", self.mass_scale, scale),
            ("effort_scale", self.effort_scale, scale),
            ("kp_scale", self.kp_scale, scale),
            ("kd_scale", self.kd_scale, scale),
            (
                "latency_steps",
                self.latency_steps,
                (0.0, f64::from(MAX_LATENCY_STEPS)),
            ),
            ("obs_noise", self.obs_noise, (0.0, MAX_OBS_NOISE)),
            ("skin_friction_scale", self.skin_friction_scale, scale),
            ("current_speed", self.current_speed, (0.0, MAX_CURRENT)),
            ("current_heading", self.current_heading, (-MAX_YAW, MAX_YAW)),
        ] {
            let Some([low, high]) = range else { continue };
            check_key_interval(
                &format!("randomize.{key}"),
                [low, high],
                low_bound,
                high_bound,
            )?;
            if key == "latency_steps" && (low.fract() != 0.0 || high.fract() != 0.0) {
                return Err(invalid_at(
                    "randomize.latency_steps",
                    format!(
                        "must be whole env steps, got [{}, {}]",
                        short(low),
                        short(high)
                    ),
                ));
            }
        }
        if self.skin_friction_scale.is_some() && !has_skin {
            return Err(invalid_at(
                "randomize.skin_friction_scale",
                "needs a body with skin friction (snake.skin_friction, or a robot file's skin_friction)",
            ));
        }
        if self.current_speed.is_some() && !has_water {
            return Err(invalid_at(
                "randomize.current_speed",
                "needs a world with water (a world file's media: [{medium: water, ...}], docs/media.md)",
            ));
        }
        if self.current_heading.is_some() && self.current_speed.is_none() {
            return Err(invalid_at(
                "randomize.current_heading",
                "needs randomize.current_speed (the heading of which current?)",
            ));
        }
        Ok(())
    }

    /// This reset's physics: one uniform number from `rng` per given key, in field order.
    pub fn draw(&self, rng: &mut ChaCha12Rng) -> Physics {
        Physics {
            ground_friction: uniform(rng, self.ground_friction),
            mass_scale: uniform(rng, self.mass_scale),
            effort_scale: uniform(rng, self.effort_scale),
            kp_scale: uniform(rng, self.kp_scale),
            kd_scale: uniform(rng, self.kd_scale),
            latency_steps: self.latency_steps.map(|[low, high]| {
                let u = rng.gen::<f64>();
                (low + (u * (high - low + 1.0)).floor()).min(high) as u32
            }),
            obs_noise: uniform(rng, self.obs_noise),
            skin_friction_scale: uniform(rng, self.skin_friction_scale),
            current_speed: uniform(rng, self.current_speed),
            current_heading: uniform(rng, self.current_heading),
        }
    }
}

/// `low + (high - low) * u` for one uniform `u` from `rng` (exactly `low` for a zero-width range).
fn uniform(rng: &mut ChaCha12Rng, range: Option<[f64; 2]>) -> Option<f64> {
    range.map(|[low, high]| {
        let u = rng.gen::<f64>();
        if low == high {
            low
        } else {
            (low + (high - low) * u).clamp(low, high)
        }
    })
}

impl Physics {
    /// Sets these physics on a freshly built body and its world, before the reset's physics step.
    /// A factor of exactly 1 (and a latency or noise of 0) changes nothing.
    pub fn apply(&self, body: &mut Body) -> Result<()> {
        if let Some(mu) = self.ground_friction {
            let ground = body.ground();
            let d = crate::world::Dynamics {
                lateral_friction: Some(mu),
                ..Default::default()
            };
            body.world_mut().change_dynamics(ground, None, &d)?;
        }
        let id = body.id();
        let links = body.world().num_joints(id)?;
        let parts = || std::iter::once(None).chain((0..links).map(Some));
        if let Some(scale) = self.mass_scale.filter(|&s| s != 1.0) {
            for part in parts() {
                let mass = body.world().dynamics_info(id, part)?.mass;
                if mass > 0.0 {
                    body.world_mut().set_mass(id, part, mass * scale)?;
                }
            }
        }
        if self.effort_scale.is_some() || self.kp_scale.is_some() || self.kd_scale.is_some() {
            body.scale_motors(
                self.effort_scale.unwrap_or(1.0),
                self.kp_scale.unwrap_or(1.0),
                self.kd_scale.unwrap_or(1.0),
            );
        }
        if let Some(scale) = self.skin_friction_scale.filter(|&s| s != 1.0) {
            let mut any = false;
            for part in parts() {
                any |= body.world_mut().scale_skin_friction(id, part, scale)?;
            }
            if !any {
                return Err(invalid_at(
                    "randomize.skin_friction_scale",
                    "needs a body with skin friction",
                ));
            }
        }
        if let Some(speed) = self.current_speed {
            let heading = self.current_heading.unwrap_or(0.0);
            let current = nalgebra::Vector3::new(speed * heading.cos(), speed * heading.sin(), 0.0);
            if !body.set_water_current(current) {
                return Err(invalid_at(
                    "randomize.current_speed",
                    "needs a world with water",
                ));
            }
        }
        Ok(())
    }
}

/// Adds Gaussian noise of standard deviation `std` to every value of `obs` (Box-Muller, two values
/// per pair of uniform numbers from `rng`). Nothing is drawn when `std` is 0.
pub(crate) fn add_noise(obs: &mut [f32], std: f64, rng: &mut ChaCha12Rng) {
    if std == 0.0 {
        return;
    }
    for pair in obs.chunks_mut(2) {
        // 1 - u lies in (0, 1], so the logarithm is finite.
        let u1 = 1.0 - rng.gen::<f64>();
        let u2 = rng.gen::<f64>();
        let r = std * (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        pair[0] += (r * c) as f32;
        if let Some(second) = pair.get_mut(1) {
            *second += (r * s) as f32;
        }
    }
}
