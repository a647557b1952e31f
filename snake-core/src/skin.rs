//! Skin friction (issue 27): friction that differs forward, backward and sideways along a link's axis,
//! as snake scales do (Hu, Nirody, Scott and Shelley 2009, "The mechanics of slithering locomotion",
//! PNAS 106:10081). The law is applied inside Bullet's contact solver by the shim
//! (`ss_set_skin_friction`); docs/friction.md describes it.

use serde::{Deserialize, Serialize};

use crate::error::{invalid, Result};
use crate::limits::MAX_SKIN_FRICTION;

/// A signed axis of a link's frame: the direction its head points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SkinAxis {
    /// +x
    #[serde(rename = "x")]
    X,
    /// -x
    #[serde(rename = "-x")]
    NegX,
    /// +y
    #[serde(rename = "y")]
    Y,
    /// -y
    #[serde(rename = "-y")]
    NegY,
    /// +z
    #[serde(rename = "z")]
    Z,
    /// -z
    #[serde(rename = "-z")]
    NegZ,
}

impl SkinAxis {
    /// All axes, for listings.
    pub const ALL: [SkinAxis; 6] = [
        SkinAxis::X,
        SkinAxis::NegX,
        SkinAxis::Y,
        SkinAxis::NegY,
        SkinAxis::Z,
        SkinAxis::NegZ,
    ];

    /// The name the CLI and files use.
    pub fn name(self) -> &'static str {
        match self {
            SkinAxis::X => "x",
            SkinAxis::NegX => "-x",
            SkinAxis::Y => "y",
            SkinAxis::NegY => "-y",
            SkinAxis::Z => "z",
            SkinAxis::NegZ => "-z",
        }
    }

    /// The unit vector in the link frame.
    pub fn vector(self) -> [f64; 3] {
        match self {
            SkinAxis::X => [1.0, 0.0, 0.0],
            SkinAxis::NegX => [-1.0, 0.0, 0.0],
            SkinAxis::Y => [0.0, 1.0, 0.0],
            SkinAxis::NegY => [0.0, -1.0, 0.0],
            SkinAxis::Z => [0.0, 0.0, 1.0],
            SkinAxis::NegZ => [0.0, 0.0, -1.0],
        }
    }
}

impl std::str::FromStr for SkinAxis {
    type Err = crate::Error;

    fn from_str(s: &str) -> Result<Self> {
        SkinAxis::ALL
            .into_iter()
            .find(|a| a.name() == s)
            .ok_or_else(|| {
                invalid(format!(
                    "unknown skin axis '{s}' (expected one of: x, -x, y, -y, z, -z)"
                ))
            })
    }
}

impl std::fmt::Display for SkinAxis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Skin friction coefficients of a link. Each is multiplied by the other object's lateral friction, as
/// Bullet combines lateral friction: the ground plane of snakesim's worlds (pybullet's
/// `createMultiBody` plane) has Bullet's default 0.5, so on it each acts at half its value; a ground of
/// friction 1 leaves them as they are. A link with skin friction ignores its own lateral and
/// anisotropic friction. docs/friction.md has the law.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkinFriction {
    /// Coefficient against sliding head first (along +axis).
    pub forward: f64,
    /// Coefficient against sliding tail first.
    pub backward: f64,
    /// Coefficient against sliding sideways.
    pub transverse: f64,
    /// The head direction in the link frame; `None`: the body's own (the built-in snake's head
    /// direction -y; a robot's +x).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<SkinAxis>,
}

impl SkinFriction {
    /// Skin of the given coefficients along the body's default axis.
    pub fn new(forward: f64, backward: f64, transverse: f64) -> Self {
        SkinFriction {
            forward,
            backward,
            transverse,
            axis: None,
        }
    }

    /// The first coefficient outside `[0, MAX_SKIN_FRICTION]` (or not finite), by name and value.
    pub fn first_bad(&self) -> Option<(&'static str, f64)> {
        [
            ("forward", self.forward),
            ("backward", self.backward),
            ("transverse", self.transverse),
        ]
        .into_iter()
        .find(|(_, value)| !(value.is_finite() && (0.0..=MAX_SKIN_FRICTION).contains(value)))
    }

    /// Checks the coefficients against `[0, MAX_SKIN_FRICTION]`; the error starts with `what` (a flag
    /// or a file and key).
    pub fn validate(&self, what: &str) -> Result<()> {
        match self.first_bad() {
            Some((name, value)) => Err(invalid(format!(
                "{what}: {name} must be finite and in [0, {MAX_SKIN_FRICTION}], got {value:?}"
            ))),
            None => Ok(()),
        }
    }

    /// The axis vector in the link frame, `default` when none is set.
    pub fn axis_vector(&self, default: SkinAxis) -> [f64; 3] {
        self.axis.unwrap_or(default).vector()
    }
}
