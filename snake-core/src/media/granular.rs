//! A dry granular medium (issue 59): resistive force theory after Li, Zhang and Goldman 2013.
//!
//! Skeleton: the entry's keys and the law are being written (see the issue).

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::media::{Region, RegionFile};

/// A `{medium: granular, ...}` entry as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularFile {
    /// `[x_min, y_min, x_max, y_max]` of the region it fills, metres.
    pub area: [f64; 4],
    /// Height of its surface, metres (default 0: the ground plane's height).
    #[serde(default)]
    pub surface: f64,
    /// How far below the surface it reaches, metres.
    pub depth: f64,
}

/// A checked granular medium.
#[derive(Debug, Clone, PartialEq)]
pub struct Granular {
    /// Where it is.
    pub region: Region,
}

impl GranularFile {
    /// Checks every value.
    pub fn resolve(&self, what: &str) -> Result<Granular> {
        Ok(Granular {
            region: RegionFile {
                area: self.area,
                surface: self.surface,
                depth: self.depth,
            }
            .resolve(what)?,
        })
    }
}
