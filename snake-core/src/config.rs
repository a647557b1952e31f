//! Physical parameters of the snake and the two presets.

use serde::{Deserialize, Serialize};

use crate::error::{invalid, invalid_at, Result};
use crate::limits::MAX_SKIN_FRICTION;
use crate::skin::{SkinAxis, SkinFriction};

/// Most joints a snake may have (defined with every other limit in [`crate::limits`]).
pub use crate::limits::MAX_JOINTS;

/// Joints of the snake when none are asked for (the paper's 5): the env keywords' and a run's default.
pub const DEFAULT_JOINTS: usize = 5;

/// The preset when none is asked for (the paper's masses).
pub const DEFAULT_PRESET: Preset = Preset::Paper;

/// Every physical parameter of the simulated snake, with the paper's defaults.
///
/// The snake is `joints + 1` cubes in a row along +y (the base first, the tail last), joined by
/// revolute joints about z so that it bends in the ground plane.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SnakeConfig {
    /// Number of joints N (the snake has N + 1 cubes). At least 1.
    pub joints: usize,
    /// Half extent of each cube, metres (0.25: 0.5 m cubes).
    pub half_extent: f64,
    /// Gap between neighbouring cubes, metres (0.01: joint frames 0.51 m apart).
    pub link_gap: f64,
    /// Mass of the base (head) cube, kg.
    pub base_mass: f64,
    /// Mass of every other cube, kg.
    pub link_mass: f64,
    /// Lateral friction of every cube (the plane keeps pybullet's 0.5, so contacts use 2.5).
    pub lateral_friction: f64,
    /// Anisotropic friction of every cube, in its own frame.
    pub anisotropic_friction: [f64; 3],
    /// Largest torque of each position-controlled joint motor, N m.
    pub motor_force: f64,
    /// Position gain of the motors (pybullet's default).
    pub position_gain: f64,
    /// Velocity gain of the motors (pybullet's default).
    pub velocity_gain: f64,
    /// Gravity along z, m/s².
    pub gravity: f64,
    /// Physics time step, seconds.
    pub dt: f64,
    /// Skin friction of every cube (issue 27), replacing its lateral and anisotropic friction; `None`
    /// (the default) keeps pybullet's friction. The default axis is the head direction, -y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin_friction: Option<SkinFriction>,
}

impl Default for SnakeConfig {
    fn default() -> Self {
        DEFAULT_PRESET.config(DEFAULT_JOINTS)
    }
}

/// Named parameter sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Preset {
    /// The paper's text: every cube 0.06 kg.
    Paper,
    /// The paper's published code (snakebot-gym): base 0.06 kg, every link 1.0 kg.
    SnakebotGym,
}

impl Preset {
    /// All presets, for listings.
    pub const ALL: [Preset; 2] = [Preset::Paper, Preset::SnakebotGym];

    /// The preset's name as the CLI and Python accept it.
    pub fn name(self) -> &'static str {
        match self {
            Preset::Paper => "paper",
            Preset::SnakebotGym => "snakebot-gym",
        }
    }

    /// The configuration for a snake of `joints` joints.
    pub fn config(self, joints: usize) -> SnakeConfig {
        let link_mass = match self {
            Preset::Paper => 0.06,
            Preset::SnakebotGym => 1.0,
        };
        SnakeConfig {
            joints,
            half_extent: 0.25,
            link_gap: 0.01,
            base_mass: 0.06,
            link_mass,
            lateral_friction: 5.0,
            anisotropic_friction: [1.0, 0.01, 0.01],
            motor_force: 10.0,
            position_gain: 0.1,
            velocity_gain: 1.0,
            gravity: -9.81,
            dt: 1.0 / 240.0,
            skin_friction: None,
        }
    }
}

impl std::str::FromStr for Preset {
    type Err = crate::Error;

    fn from_str(s: &str) -> Result<Self> {
        Preset::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| {
                invalid(format!(
                    "unknown preset '{s}' (expected one of: paper, snakebot-gym)"
                ))
            })
    }
}

impl std::fmt::Display for Preset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl SnakeConfig {
    /// Distance between neighbouring joint frames along the body, metres.
    pub fn link_spacing(&self) -> f64 {
        // Computed as the reference code writes it: half extent * 2.0 + gap.
        self.half_extent * 2.0 + self.link_gap
    }

    /// The head direction of every cube in its own frame: the base is the head and the links follow
    /// along +y, so the head points along -y.
    pub const HEAD_AXIS: SkinAxis = SkinAxis::NegY;

    /// Checks every parameter; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        crate::limits::check_joints(self.joints)?;
        let positive = [
            ("half_extent", self.half_extent),
            ("base_mass", self.base_mass),
            ("link_mass", self.link_mass),
            ("dt", self.dt),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(invalid_at(
                    name,
                    format!("must be positive and finite, got {value}"),
                ));
            }
        }
        let non_negative = [
            ("link_gap", self.link_gap),
            ("lateral_friction", self.lateral_friction),
            ("motor_force", self.motor_force),
            ("position_gain", self.position_gain),
            ("velocity_gain", self.velocity_gain),
        ];
        for (name, value) in non_negative {
            if !(value.is_finite() && value >= 0.0) {
                return Err(invalid_at(
                    name,
                    format!("must be finite and >= 0, got {value}"),
                ));
            }
        }
        if !self.gravity.is_finite() {
            return Err(invalid_at(
                "gravity",
                format!("must be finite, got {}", self.gravity),
            ));
        }
        if !self
            .anisotropic_friction
            .iter()
            .all(|a| a.is_finite() && *a >= 0.0)
        {
            return Err(invalid_at(
                "anisotropic_friction",
                "must be finite and >= 0",
            ));
        }
        // "skin_friction.forward: must be ...": a field path, as env configs name their keys.
        if let Some((name, value)) = self
            .skin_friction
            .as_ref()
            .and_then(SkinFriction::first_bad)
        {
            return Err(invalid_at(
                format!("skin_friction.{name}"),
                format!("must be finite and in [0, {MAX_SKIN_FRICTION}], got {value:?}"),
            ));
        }
        Ok(())
    }
}
