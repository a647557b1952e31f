//! Where a medium is: a box aligned with the world's axes, given by its footprint, its surface height and
//! its depth below the surface.

use serde::{Deserialize, Serialize};

use crate::error::{invalid, Result};
use crate::limits::MAX_POSITION;

/// A medium's region as written: `area: [x_min, y_min, x_max, y_max]` (metres), `surface` (the height
/// of its top, metres) and `depth` (how far below the surface it reaches, metres).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionFile {
    /// `[x_min, y_min, x_max, y_max]`, metres.
    pub area: [f64; 4],
    /// Height of the medium's surface, metres.
    #[serde(default)]
    pub surface: f64,
    /// Depth below the surface, metres.
    pub depth: f64,
}

/// A checked region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Region {
    /// Lower corner (x, y, z).
    pub min: [f64; 3],
    /// Upper corner (x, y, z); `max[2]` is the surface.
    pub max: [f64; 3],
}

impl RegionFile {
    /// Checks the region: finite, within the world's position limit, non-empty, not inverted.
    pub fn resolve(&self, what: &str) -> Result<Region> {
        let [x0, y0, x1, y1] = self.area;
        for (name, v) in [
            ("area", x0),
            ("area", y0),
            ("area", x1),
            ("area", y1),
            ("surface", self.surface),
            ("depth", self.depth),
        ] {
            if !v.is_finite() || v.abs() > MAX_POSITION {
                return Err(invalid(format!(
                    "{what}: {name}: must be a finite number within +-{MAX_POSITION} m, got {v}"
                )));
            }
        }
        if x1 <= x0 || y1 <= y0 {
            return Err(invalid(format!(
                "{what}: area: [x_min, y_min, x_max, y_max] must have x_min < x_max and y_min < y_max, got {:?}",
                self.area
            )));
        }
        if self.depth <= 0.0 {
            return Err(invalid(format!(
                "{what}: depth: must be > 0 m, got {}",
                self.depth
            )));
        }
        Ok(Region {
            min: [x0, y0, self.surface - self.depth],
            max: [x1, y1, self.surface],
        })
    }
}

impl Region {
    /// The surface height.
    pub fn surface(&self) -> f64 {
        self.max[2]
    }

    /// Whether the point's footprint lies in the region (any height).
    pub fn covers(&self, x: f64, y: f64) -> bool {
        x >= self.min[0] && x <= self.max[0] && y >= self.min[1] && y <= self.max[1]
    }

    /// Whether the point lies in the region: over its area, below its surface and above its bottom.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        self.covers(p[0], p[1]) && p[2] <= self.max[2] && p[2] >= self.min[2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverted_or_empty_regions_are_refused() {
        let r = RegionFile {
            area: [1.0, 0.0, 0.0, 1.0],
            surface: 0.0,
            depth: 0.2,
        };
        let err = r.resolve("media[0]").unwrap_err().to_string();
        assert!(err.contains("x_min < x_max"), "{err}");
        let r = RegionFile {
            area: [0.0, 0.0, 1.0, 1.0],
            surface: 0.0,
            depth: 0.0,
        };
        let err = r.resolve("media[0]").unwrap_err().to_string();
        assert!(err.contains("depth: must be > 0"), "{err}");
        let r = RegionFile {
            area: [0.0, 0.0, 1.0, f64::NAN],
            surface: 0.0,
            depth: 0.1,
        };
        assert!(r.resolve("media[0]").is_err());
    }

    #[test]
    fn contains_is_the_box_below_the_surface() {
        let r = RegionFile {
            area: [-1.0, -2.0, 1.0, 2.0],
            surface: 0.1,
            depth: 0.3,
        }
        .resolve("m")
        .unwrap();
        assert!(r.contains([0.0, 0.0, 0.0]));
        assert!(!r.contains([0.0, 0.0, 0.2]));
        assert!(!r.contains([0.0, 0.0, -0.3]));
        assert!(!r.contains([1.5, 0.0, 0.0]));
    }
}
