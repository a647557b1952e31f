//! Media beyond pybullet's rigid world (issues 59 and 60): a granular medium (resistive force theory) and
//! water (Kelasidi et al.'s link-by-link hydrodynamics), given in a world file's `media` list. Each medium
//! fills a region; in it, every link of a robot gets the medium's forces and torques at every physics
//! step, applied through `World::apply_external_force`/`apply_external_torque` before the step. A world
//! without media builds and steps exactly as before: bit for bit with pybullet, at the same cost.
//!
//! Layout: `region` (where a medium is), `granular` (the granular medium, issue 59), `water` (water,
//! issue 60). Link geometry and the per-step application are added next to them.

pub mod granular;
pub mod region;
pub mod water;

use serde::{Deserialize, Serialize};

use crate::error::Result;

pub use region::{Region, RegionFile};

/// One entry of a world file's `media` list, as written: `{medium: granular, ...}` or
/// `{medium: water, ...}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "medium", rename_all = "lowercase", deny_unknown_fields)]
pub enum MediumFile {
    /// Dry granular media (sand, glass beads, ...), resistive force theory.
    Granular(granular::GranularFile),
    /// Water.
    Water(water::WaterFile),
}

/// A medium checked and ready to act.
#[derive(Debug, Clone, PartialEq)]
pub enum Medium {
    /// See [`granular::Granular`].
    Granular(granular::Granular),
    /// See [`water::Water`].
    Water(water::Water),
}

impl MediumFile {
    /// Checks every value once; `what` names the entry in messages (e.g. `media[0]`).
    pub fn resolve(&self, what: &str) -> Result<Medium> {
        Ok(match self {
            MediumFile::Granular(g) => Medium::Granular(g.resolve(what)?),
            MediumFile::Water(w) => Medium::Water(w.resolve(what)?),
        })
    }
}
