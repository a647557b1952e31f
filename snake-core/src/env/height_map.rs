//! The `terrain` observation's height map: the ground's height at a square grid of points around the
//! head, in the head's frame, relative to the head. A policy on rough ground without it is blind to
//! the hills it is about to climb or slide into (docs/tasks.md, "What did not work").
//!
//! Heights are read from the episode's world description, not from Bullet's collision shape: a
//! heightfield is interpolated bilinearly between its four nearest samples (Bullet's two triangles per
//! cell differ from that by at most the cell's twist, millimetres on the rough task's 0.125 m grid),
//! and points beyond the grid take its nearest edge. Obstacles are not in the map.

use serde::{Deserialize, Serialize};

use crate::error::{invalid_at, Result};
use crate::world_file::{Ground, WorldSpec};

/// Points per side of the square grid.
pub const HEIGHT_MAP_SIDE: usize = 5;

/// Distance between neighbouring points of the grid, metres: the map reaches
/// `(HEIGHT_MAP_SIDE - 1) / 2 * HEIGHT_MAP_SPACING` = 1.5 m ahead, behind and to each side of the
/// head, half the rough task's hill wavelength, so that a hill's crest or a valley's floor is in
/// view before the head reaches it.
pub const HEIGHT_MAP_SPACING: f64 = 0.75;

/// Values the map adds to the observation.
pub const HEIGHT_MAP_LEN: usize = HEIGHT_MAP_SIDE * HEIGHT_MAP_SIDE;

/// Most points per side a configured map may have (225 values).
pub const MAX_HEIGHT_MAP_SIDE: usize = 15;

/// Largest spacing a configured map may have, metres.
pub const MAX_HEIGHT_MAP_SPACING: f64 = 2.0;

/// The terrain observation's grid (`height_map` in an env configuration): `side` x `side` points
/// `spacing` apart, centred on the head; [`HEIGHT_MAP_SIDE`] and [`HEIGHT_MAP_SPACING`] by default.
/// A larger map sees an obstacle's extent from farther away (docs/tasks.md, "A ridge across the
/// way"), at the cost of a longer observation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HeightMap {
    /// Points per side, odd, so that the head is the middle one (5).
    pub side: usize,
    /// Distance between neighbouring points, metres (0.75).
    pub spacing: f64,
}

impl Default for HeightMap {
    fn default() -> Self {
        HeightMap {
            side: HEIGHT_MAP_SIDE,
            spacing: HEIGHT_MAP_SPACING,
        }
    }
}

impl HeightMap {
    /// Values the map adds to the observation.
    pub fn len(&self) -> usize {
        self.side * self.side
    }

    /// Whether the map has no points (never once validated; `len`'s companion).
    pub fn is_empty(&self) -> bool {
        self.side == 0
    }

    /// Whether this is the default map (left out of written configurations).
    pub fn is_default(&self) -> bool {
        *self == HeightMap::default()
    }

    /// Checks the grid; the error names the field and the allowed values.
    pub fn validate(&self) -> Result<()> {
        if self.side.is_multiple_of(2) || !(1..=MAX_HEIGHT_MAP_SIDE).contains(&self.side) {
            return Err(invalid_at(
                "height_map.side",
                format!(
                    "must be odd, from 1 to {MAX_HEIGHT_MAP_SIDE}, got {}",
                    self.side
                ),
            ));
        }
        let s = self.spacing;
        if !(s.is_finite() && s > 0.0 && s <= MAX_HEIGHT_MAP_SPACING) {
            return Err(invalid_at(
                "height_map.spacing",
                format!("must be in (0, {MAX_HEIGHT_MAP_SPACING}] metres, got {s}"),
            ));
        }
        Ok(())
    }
}

/// The episode's ground, ready to be sampled at any planar point.
#[derive(Debug, Clone, Default)]
pub(crate) enum GroundProbe {
    /// The plane z = 0.
    #[default]
    Plane,
    /// The plane tilted about x: the height is `y * slope`.
    Slope(f64),
    /// A heightfield grid, placed as Bullet places it ([`crate::world_file::Heightfield::point`]).
    Grid {
        rows: usize,
        columns: usize,
        heights: Vec<f32>,
        scale: [f64; 3],
        /// The middle of the lowest and highest sample, Bullet's z = 0 of the grid (found once).
        middle: f64,
    },
}

impl GroundProbe {
    /// The probe of `world`'s ground.
    pub fn of(world: &WorldSpec) -> Self {
        match &world.ground {
            Ground::Plane => GroundProbe::Plane,
            Ground::Slope(degrees) => GroundProbe::Slope(degrees.to_radians().tan()),
            Ground::Heightfield(h) => GroundProbe::Grid {
                rows: h.rows,
                columns: h.columns,
                heights: h.heights.clone(),
                scale: h.scale,
                middle: h.middle(),
            },
        }
    }

    /// The ground's height at world (x, y), metres.
    pub fn height(&self, x: f64, y: f64) -> f64 {
        match self {
            GroundProbe::Plane => 0.0,
            GroundProbe::Slope(slope) => y * slope,
            GroundProbe::Grid {
                rows,
                columns,
                heights,
                scale,
                middle,
            } => {
                // Grid coordinates of (x, y), clamped to the grid (its edge continues outwards).
                let cell = |v: f64, n: usize, s: f64| {
                    let last = (n - 1) as f64;
                    let u = (v / s + 0.5 * last).clamp(0.0, last);
                    let i = (u.floor() as usize).min(n.saturating_sub(2));
                    (i, u - i as f64)
                };
                let (ix, fx) = cell(x, *rows, scale[0]);
                let (iy, fy) = cell(y, *columns, scale[1]);
                let at = |i: usize, j: usize| {
                    let i = i.min(rows - 1);
                    let j = j.min(columns - 1);
                    heights[j * rows + i] as f64
                };
                let low = at(ix, iy) * (1.0 - fx) + at(ix + 1, iy) * fx;
                let high = at(ix, iy + 1) * (1.0 - fx) + at(ix + 1, iy + 1) * fx;
                (low * (1.0 - fy) + high * fy - middle) * scale[2]
            }
        }
    }

    /// Writes `map` (`map.len()` values) for a head at `position` with planar heading `yaw`
    /// (see [`super::observation::rolled_frame`]): point (i, j), at index `i * side + j`, lies
    /// `(j - c) * spacing` along the head frame's x and `(i - c) * spacing` along its y (c = the
    /// middle index; the head frame's -y points ahead and +x to the left, or to the right when
    /// `mirror` is -1: the head upside down), and holds the ground's height there minus the
    /// head's z.
    pub fn write(
        &self,
        map: &HeightMap,
        position: [f64; 3],
        yaw: f64,
        mirror: f64,
        out: &mut [f32],
    ) {
        let (s, c) = yaw.sin_cos();
        let (side, spacing) = (map.side, map.spacing);
        let middle = (side / 2) as f64;
        for i in 0..side {
            let hy = (i as f64 - middle) * spacing;
            for j in 0..side {
                // `mirror` -1 (the head upside down): the frame's +x, the map's columns, is mirrored.
                let hx = mirror * (j as f64 - middle) * spacing;
                // Head frame to world: rotation by +yaw about z.
                let (x, y) = (position[0] + c * hx - s * hy, position[1] + s * hx + c * hy);
                out[i * side + j] = (self.height(x, y) - position[2]) as f32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world_file::Heightfield;

    fn grid() -> Heightfield {
        // 3 x 2 samples, spacing 0.5 along x and 2 along y, heights doubled.
        Heightfield {
            rows: 3,
            columns: 2,
            heights: vec![0.0, 1.0, 2.0, 4.0, 5.0, 6.0],
            scale: [0.5, 2.0, 2.0],
        }
    }

    #[test]
    fn grid_points_give_bullets_heights_and_between_them_the_bilinear_mean() {
        let h = grid();
        let world = WorldSpec {
            ground: Ground::Heightfield(h.clone()),
            ..WorldSpec::default()
        };
        let probe = GroundProbe::of(&world);
        for y in 0..2 {
            for x in 0..3 {
                let [px, py, pz] = h.point(x, y);
                assert!((probe.height(px, py) - pz).abs() < 1e-12, "({x}, {y})");
            }
        }
        // Halfway between the four samples 0, 1, 4, 5: 2.5, less the middle 3, times 2.
        let [x0, y0, _] = h.point(0, 0);
        assert!((probe.height(x0 + 0.25, y0 + 1.0) - (-1.0)).abs() < 1e-12);
        // Beyond the grid: its nearest edge.
        let [x2, y1, z21] = h.point(2, 1);
        assert!((probe.height(x2 + 10.0, y1 + 10.0) - z21).abs() < 1e-12);
    }

    #[test]
    fn a_head_resting_on_bullets_heightfield_is_its_half_extent_above_the_probed_ground() {
        // A ramp rising along x by 0.2 per metre (samples 0.05 apart on a 0.25 m grid), centred by
        // Bullet at its middle height; the snake lies along y, on the ramp's contour, so that its
        // stiff vertical plane rests every cube on the ground. Reading the grid transposed misses
        // the head's height by 9 cm; mirrored, the map's slope has the wrong sign.
        let n = 41;
        let heights: Vec<f32> = (0..n * n).map(|k| 0.05 * (k % n) as f32).collect();
        let world = WorldSpec {
            ground: Ground::Heightfield(Heightfield {
                rows: n,
                columns: n,
                heights,
                scale: [0.25, 0.25, 1.0],
            }),
            ..WorldSpec::default()
        };
        let start = crate::math::StartPose {
            x: 0.3,
            y: -0.2,
            z: 0.5,
            yaw: 0.0,
        };
        let config = crate::Preset::Paper.config(5);
        let mut snake = crate::Snake::in_world(&config, start, &world).unwrap();
        for _ in 0..480 {
            crate::robot::Simulation::step(&mut snake).unwrap();
        }
        let base = crate::robot::Simulation::base_state(&snake).unwrap();
        let p = base.pose.position;
        let mut map = [0.0_f32; HEIGHT_MAP_LEN];
        GroundProbe::of(&world).write(&HeightMap::default(), [p.x, p.y, p.z], 0.0, 1.0, &mut map);
        // The cube's centre stands 0.25 / cos(slope) above the ground below it.
        let expected = -0.25 / 0.2_f64.atan().cos();
        let c = HEIGHT_MAP_SIDE / 2;
        let under = map[c * HEIGHT_MAP_SIDE + c] as f64;
        assert!((under - expected).abs() < 5e-3, "{under} {expected}");
        // Each point to the left (+x) is 0.2 * spacing higher.
        for j in 1..HEIGHT_MAP_SIDE {
            let rise = (map[c * HEIGHT_MAP_SIDE + j] - map[c * HEIGHT_MAP_SIDE + j - 1]) as f64;
            assert!((rise - 0.2 * HEIGHT_MAP_SPACING).abs() < 1e-5, "{map:?}");
        }
    }

    #[test]
    fn planes_and_the_map_in_the_head_frame() {
        assert_eq!(
            GroundProbe::of(&WorldSpec::default()).height(3.0, -2.0),
            0.0
        );
        let slope = GroundProbe::of(&WorldSpec {
            ground: Ground::Slope(45.0),
            ..WorldSpec::default()
        });
        assert!((slope.height(7.0, 2.0) - 2.0).abs() < 1e-12);
        // Heading 90 degrees: the head frame's x is world y, its -y world x (ahead).
        let mut out = [0.0_f32; HEIGHT_MAP_LEN];
        slope.write(
            &HeightMap::default(),
            [1.0, 0.0, 0.25],
            std::f64::consts::FRAC_PI_2,
            1.0,
            &mut out,
        );
        let c = HEIGHT_MAP_SIDE / 2;
        assert_eq!(out[c * HEIGHT_MAP_SIDE + c], -0.25);
        // One point to the left (+x of the head frame) is world y = +spacing: higher by spacing.
        let left = out[c * HEIGHT_MAP_SIDE + c + 1] as f64;
        assert!((left - (HEIGHT_MAP_SPACING - 0.25)).abs() < 1e-6, "{left}");
        // One point behind (+y of the head frame) is world x - spacing: the same height.
        let behind = out[(c + 1) * HEIGHT_MAP_SIDE + c] as f64;
        assert!((behind + 0.25).abs() < 1e-6, "{behind}");
    }

    #[test]
    fn a_configured_map_samples_its_grid_in_the_head_frame() {
        // A 9 x 9 grid 0.5 m apart on a 45-degree slope (height = world y), the head at heading
        // 30 degrees, upright and then upside down (mirrored columns): each point against the
        // plane's height at its offset turned into the world by hand.
        let slope = GroundProbe::of(&WorldSpec {
            ground: Ground::Slope(45.0),
            ..WorldSpec::default()
        });
        let map = HeightMap {
            side: 9,
            spacing: 0.5,
        };
        let (yaw, head) = (30f64.to_radians(), [2.0, -1.0, 0.4]);
        for mirror in [1.0, -1.0] {
            let mut out = vec![0.0_f32; map.len()];
            slope.write(&map, head, yaw, mirror, &mut out);
            for i in 0..9 {
                for j in 0..9 {
                    // Column j lies (j - 4) * 0.5 along the head frame's x (mirrored upside down),
                    // row i (i - 4) * 0.5 along its y; world y of that point is the plane's height.
                    let (hx, hy) = (mirror * (j as f64 - 4.0) * 0.5, (i as f64 - 4.0) * 0.5);
                    let world_y = head[1] + yaw.sin() * hx + yaw.cos() * hy;
                    let want = world_y - head[2];
                    let got = out[i * 9 + j] as f64;
                    assert!(
                        (got - want).abs() < 1e-5,
                        "({i}, {j}) mirror {mirror}: {got} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn bad_maps_name_the_field() {
        for (map, field) in [
            (
                HeightMap {
                    side: 4,
                    spacing: 0.75,
                },
                "height_map.side",
            ),
            (
                HeightMap {
                    side: 0,
                    spacing: 0.75,
                },
                "height_map.side",
            ),
            (
                HeightMap {
                    side: 17,
                    spacing: 0.75,
                },
                "height_map.side",
            ),
            (
                HeightMap {
                    side: 5,
                    spacing: 0.0,
                },
                "height_map.spacing",
            ),
            (
                HeightMap {
                    side: 5,
                    spacing: f64::NAN,
                },
                "height_map.spacing",
            ),
            (
                HeightMap {
                    side: 5,
                    spacing: 2.5,
                },
                "height_map.spacing",
            ),
        ] {
            let m = map.validate().unwrap_err().to_string();
            assert!(m.contains(field), "{m}");
        }
        assert!(HeightMap::default().validate().is_ok());
        assert!(HeightMap {
            side: 15,
            spacing: 2.0
        }
        .validate()
        .is_ok());
    }
}
