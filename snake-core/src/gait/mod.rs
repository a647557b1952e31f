//! Open-loop gaits: joint target angles as a function of time.
//!
//! - [`sine`]: [`LateralUndulation`], pybullet's `examples/snake.py` wave, bit for bit (`--gait sine`,
//!   the paper's gait).
//! - [`serpenoid`]: the gait library, Tesch et al.'s compound serpenoid over a robot's yaw and pitch
//!   joints (`lateral`, `sidewind`, `roll`, `linear`, `turn`).
//! - [`joints`]: which joints are yaw and which pitch, from the joint axes at rest.
//! - [`steered`]: [`SteeredWave`], a library gait steered as it runs (the envs' wave on a robot whose
//!   robot file names one).
//! - [`swim`]: [`Swim`], Kelasidi et al.'s swimming gaits for water (`swim`: lateral undulation,
//!   `eel`: eel-like motion), on the yaw joints.
//! - [`sandfish`]: [`SandfishGait`], Maladen et al.'s travelling sine wave for swimming in sand
//!   (`sandfish`), on the yaw joints.
//!
//! [`GaitChoice::new`] makes any of them by name with `KEY=VALUE` parameters, as `snake-cli run --gait
//! NAME --gait-param KEY=VALUE` does.

pub mod joints;
pub mod sandfish;
pub mod serpenoid;
pub mod sine;
pub mod steered;
pub mod swim;

pub use joints::{JointRole, JointRoles};
pub use sandfish::{SandfishGait, SandfishWave};
pub use serpenoid::{Serpenoid, SerpenoidParams};
pub use sine::LateralUndulation;
pub use steered::SteeredWave;
pub use swim::{Swim, SwimParams, SwimPattern};

use crate::error::{invalid, Result};

/// A source of joint targets, called once per physics step.
pub trait Gait {
    /// Writes the targets for the current step into `targets` (one per joint) and advances the gait
    /// by one step.
    fn next_targets(&mut self, targets: &mut [f64]);
    /// Returns the gait to its initial phase.
    fn reset(&mut self);
}

/// The gaits the CLI offers by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GaitKind {
    /// [`LateralUndulation`] (`sine`).
    Sine,
    /// Serpenoid lateral undulation (`lateral`).
    Lateral,
    /// Sidewinding (`sidewind`).
    Sidewind,
    /// Rolling (`roll`).
    Roll,
    /// Linear progression, a vertical travelling wave (`linear`).
    Linear,
    /// Turning in place (`turn`).
    Turn,
    /// Kelasidi et al.'s lateral undulation for swimming (`swim`, [`Swim`]).
    Swim,
    /// Kelasidi et al.'s eel-like motion (`eel`, [`Swim`]).
    Eel,
    /// Maladen et al.'s travelling sine wave for sand (`sandfish`, [`SandfishGait`]).
    Sandfish,
}

impl GaitKind {
    /// Every gait, in the order help and the atlas list them.
    pub const ALL: [GaitKind; 6] = [
        GaitKind::Sine,
        GaitKind::Lateral,
        GaitKind::Sidewind,
        GaitKind::Roll,
        GaitKind::Linear,
        GaitKind::Turn,
    ];

    /// The swimming gaits (for water: docs/media.md), apart from [`GaitKind::ALL`], the gaits the
    /// atlas draws on the ground.
    pub const SWIMMING: [GaitKind; 2] = [GaitKind::Swim, GaitKind::Eel];

    /// The gait for swimming in sand (docs/media.md), apart from [`GaitKind::ALL`] too: its wave is
    /// given in metres along the body, for a robot whose segments it is told (the robot sandfish's by
    /// default).
    pub const SAND: [GaitKind; 1] = [GaitKind::Sandfish];

    /// Every gait by name: [`GaitKind::ALL`], [`GaitKind::SWIMMING`], [`GaitKind::SAND`].
    pub fn named() -> impl Iterator<Item = GaitKind> {
        GaitKind::ALL
            .into_iter()
            .chain(GaitKind::SWIMMING)
            .chain(GaitKind::SAND)
    }

    /// The gait's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            GaitKind::Sine => "sine",
            GaitKind::Lateral => "lateral",
            GaitKind::Sidewind => "sidewind",
            GaitKind::Roll => "roll",
            GaitKind::Linear => "linear",
            GaitKind::Turn => "turn",
            GaitKind::Swim => "swim",
            GaitKind::Eel => "eel",
            GaitKind::Sandfish => "sandfish",
        }
    }

    /// The `--gait-param` keys this gait takes.
    pub fn param_keys(self) -> &'static [&'static str] {
        match self {
            GaitKind::Sine => &sine::PARAM_KEYS,
            GaitKind::Swim | GaitKind::Eel => &swim::PARAM_KEYS,
            GaitKind::Sandfish => &sandfish::PARAM_KEYS,
            _ => &serpenoid::PARAM_KEYS,
        }
    }
}

impl std::fmt::Display for GaitKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for GaitKind {
    type Err = crate::Error;

    fn from_str(s: &str) -> Result<Self> {
        crate::keys::by_name(
            &GaitKind::named().collect::<Vec<_>>(),
            GaitKind::name,
            s,
            "gait",
        )
    }
}

/// Parses one `KEY=VALUE` gait parameter (the value a finite number; its range is checked with the
/// gait).
pub fn parse_param(text: &str) -> Result<(String, f64)> {
    let (key, value) = text
        .split_once('=')
        .ok_or_else(|| invalid(format!("gait parameter '{text}' is not KEY=VALUE")))?;
    let key = key.trim();
    let v: f64 = value.trim().parse().map_err(|_| {
        invalid(format!(
            "gait parameter {key}: '{}' is not a number",
            value.trim()
        ))
    })?;
    if !v.is_finite() {
        return Err(invalid(format!(
            "gait parameter {key} must be finite, got {v}"
        )));
    }
    Ok((key.to_string(), v))
}

/// A gait made by name: `sine` (on the robot's actuated joints, as before) or one of the library.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(untagged)]
pub enum GaitChoice {
    /// pybullet's snake.py wave; on a URDF robot it runs over the actuated joints in order
    /// ([`crate::RobotGait`]).
    Sine(LateralUndulation),
    /// A gait of the library, over all movable joints.
    Library(Serpenoid),
    /// A swimming gait, over the yaw joints.
    Swim(Swim),
    /// Maladen et al.'s wave for sand, over the yaw joints.
    Sandfish(SandfishGait),
}

impl GaitChoice {
    /// `kind` with `params` (`KEY=VALUE` pairs, applied in order over the gait's defaults) and `steer`,
    /// on a robot with `roles`; `sine` starts from `sine_base` (a robot file's wave, or snake.py's).
    pub fn new(
        kind: GaitKind,
        params: &[(String, f64)],
        steer: f64,
        roles: &JointRoles,
        sine_base: LateralUndulation,
        dt: f64,
    ) -> Result<Self> {
        match kind {
            GaitKind::Sine => {
                let mut g = sine_base.with_steering(steer);
                for (key, value) in params {
                    g.set(key, *value)?;
                }
                g.dt = dt;
                g.validate()?;
                Ok(GaitChoice::Sine(g))
            }
            GaitKind::Swim | GaitKind::Eel => {
                let pattern = if kind == GaitKind::Eel {
                    SwimPattern::Eel
                } else {
                    SwimPattern::Lateral
                };
                let mut p = swim::DEFAULTS;
                for (key, value) in params {
                    swim::set(&mut p, kind, key, *value)?;
                }
                if !steer.is_finite() {
                    return Err(invalid(format!("steering must be finite, got {steer}")));
                }
                p.offset += steer;
                Ok(GaitChoice::Swim(Swim::new(pattern, p, roles)?.with_dt(dt)?))
            }
            GaitKind::Sandfish => {
                let mut wave = sandfish::DEFAULTS;
                for (key, value) in params {
                    sandfish::set(&mut wave, key, *value)?;
                }
                // The wave is a shape in the body's frame; steering it would bend that frame.
                if steer != 0.0 {
                    return Err(invalid(format!(
                        "gait sandfish takes no steering (Maladen et al.'s wave is straight), got {steer}"
                    )));
                }
                Ok(GaitChoice::Sandfish(SandfishGait::new(wave, roles, dt)?))
            }
            _ => Ok(GaitChoice::Library(Serpenoid::new(
                kind, roles, params, steer, dt,
            )?)),
        }
    }

    /// Seconds per gait cycle.
    pub fn period(&self) -> f64 {
        match self {
            GaitChoice::Sine(g) => g.period,
            GaitChoice::Library(g) => g.params.period,
            GaitChoice::Swim(g) => std::f64::consts::TAU / g.params.omega.max(f64::MIN_POSITIVE),
            GaitChoice::Sandfish(g) => 1.0 / g.wave.frequency,
        }
    }
}
