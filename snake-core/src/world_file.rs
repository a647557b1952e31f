//! World files: the ground and the static obstacles a robot moves among, as a pybullet user builds them.
//!
//! A world file is YAML (every key may be left out; the empty file is today's flat plane):
//!
//! ```yaml
//! ground: {plane: {}}                       # or one of:
//! # ground: {heightfield: {file: hills.csv, scale: [0.1, 0.1, 1.0]}}
//! # ground: {rough: {amplitude: 0.02, wavelength: 0.5, seed: 1, size: [6.4, 6.4]}}
//! # ground: {slope: {degrees: 10}}
//! ground_friction: 0.8                      # changeDynamics(ground, -1, lateralFriction=0.8)
//! obstacles:
//!   - {shape: box, half_extents: [0.1, 0.1, 0.1], position: [1, 0, 0.1], yaw: 0.3}
//!   - {shape: cylinder, radius: 0.05, height: 0.3, position: [0, 1, 0.15], lateral_friction: 0.2}
//!   - {shape: sphere, radius: 0.1, position: [-1, 0, 0.1]}
//! pegs: {spacing: 0.5, radius: 0.03, height: 0.2, jitter: 0.1, seed: 7, area: [-2, -2, 2, 2]}
//! ```
//!
//! [`WorldSpec::build`] adds it to a [`World`] in this order, each line a pybullet call:
//!
//! ```python
//! ground = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE))          # plane
//! ground = p.createMultiBody(0, p.createCollisionShape(p.GEOM_PLANE), -1, [0, 0, 0],
//!                            p.getQuaternionFromEuler([math.radians(D), 0, 0]))  # slope
//! ground = p.createMultiBody(0, p.createCollisionShape(p.GEOM_HEIGHTFIELD, meshScale=scale,
//!     heightfieldData=heights, numHeightfieldRows=values_per_line, numHeightfieldColumns=lines))
//! p.changeDynamics(ground, -1, lateralFriction=ground_friction)                 # if given
//! for o in obstacles + pegs:                                                    # file order
//!     body = p.createMultiBody(0, p.createCollisionShape(o.shape, ...), -1, o.position,
//!                              p.getQuaternionFromEuler([0, 0, o.yaw]))
//!     p.changeDynamics(body, -1, lateralFriction=o.lateral_friction)           # if given
//! ```
//!
//! A heightfield file is a CSV of heights in metres before `scale`: one line per grid line along y,
//! one value per grid point along x (pybullet's `heightfieldData` order), read relative to the world
//! file. Bullet centres the grid on the origin in x and y, and in z at the middle of its lowest and
//! highest sample. The `rough` ground writes such a grid itself (value noise, below). docs/worlds.md
//! has the whole schema and its limits.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{invalid, Result};
use crate::limits::MAX_MEDIA;
use crate::limits::{
    check_position, check_range, check_range_above, MAX_HEIGHTFIELD_BYTES, MAX_HEIGHTFIELD_SAMPLES,
    MAX_HEIGHTFIELD_SIDE, MAX_NOISE_LATTICE, MAX_OBSTACLES, MAX_OBSTACLE_SIZE, MAX_SLOPE_DEGREES,
    MAX_TERRAIN_HEIGHT, MAX_WORLD_FRICTION, MAX_YAW,
};
use crate::math::quaternion_from_euler;
use crate::media::{Medium, MediumFile};
use crate::recorded::{FileOrRecord, Reader, RecordedFiles};
use crate::world::{BodyId, Dynamics, StaticShape, World};

/// The ground of a world file: a map of exactly one of `plane`, `heightfield`, `rough`, `slope`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GroundKeys", into = "GroundKeys")]
pub enum GroundFile {
    /// `{plane: {}}`: the plane z = 0 (the default).
    Plane {},
    /// `{heightfield: {file, scale}}`: heights from a CSV file.
    Heightfield {
        /// The CSV, relative to the world file.
        file: PathBuf,
        /// pybullet's `meshScale`: grid spacing along x and y, and the height factor.
        scale: [f64; 3],
    },
    /// `{rough: {amplitude, wavelength, seed, size}}`: a heightfield of value noise.
    Rough {
        /// Largest height above or below the middle, metres.
        amplitude: f64,
        /// Distance between the noise's random lattice values, metres.
        wavelength: f64,
        /// Seed of the lattice values.
        seed: u64,
        /// Extent along x and y, metres.
        size: [f64; 2],
        /// Grid spacing, metres (default: wavelength / 8).
        #[serde(default)]
        spacing: Option<f64>,
    },
    /// `{slope: {degrees}}`: the plane tilted about the x axis (it rises towards +y for positive
    /// degrees).
    Slope {
        /// Tilt in degrees.
        degrees: f64,
    },
}

/// An empty map (`plane: {}`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct Empty {}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct HeightfieldKeys {
    file: PathBuf,
    scale: [f64; 3],
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RoughKeys {
    amplitude: f64,
    wavelength: f64,
    seed: u64,
    size: [f64; 2],
    #[serde(default, skip_serializing_if = "Option::is_none")]
    spacing: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SlopeKeys {
    degrees: f64,
}

/// The YAML form of [`GroundFile`]: serde_norway writes enums as YAML tags, while a world file names
/// its ground by a key, as `ground: {slope: {degrees: 10}}`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct GroundKeys {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    plane: Option<Empty>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    heightfield: Option<HeightfieldKeys>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rough: Option<RoughKeys>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    slope: Option<SlopeKeys>,
}

impl TryFrom<GroundKeys> for GroundFile {
    type Error = String;

    fn try_from(k: GroundKeys) -> std::result::Result<Self, String> {
        match (k.plane, k.heightfield, k.rough, k.slope) {
            (Some(Empty {}), None, None, None) => Ok(GroundFile::Plane {}),
            (None, Some(h), None, None) => Ok(GroundFile::Heightfield {
                file: h.file,
                scale: h.scale,
            }),
            (None, None, Some(r), None) => Ok(GroundFile::Rough {
                amplitude: r.amplitude,
                wavelength: r.wavelength,
                seed: r.seed,
                size: r.size,
                spacing: r.spacing,
            }),
            (None, None, None, Some(s)) => Ok(GroundFile::Slope { degrees: s.degrees }),
            _ => Err(
                "ground must be one of {plane: {}}, {heightfield: {file, scale}}, \
                      {rough: {amplitude, wavelength, seed, size}}, {slope: {degrees}}"
                    .into(),
            ),
        }
    }
}

impl From<GroundFile> for GroundKeys {
    fn from(g: GroundFile) -> Self {
        match g {
            GroundFile::Plane {} => GroundKeys {
                plane: Some(Empty {}),
                ..GroundKeys::default()
            },
            GroundFile::Heightfield { file, scale } => GroundKeys {
                heightfield: Some(HeightfieldKeys { file, scale }),
                ..GroundKeys::default()
            },
            GroundFile::Rough {
                amplitude,
                wavelength,
                seed,
                size,
                spacing,
            } => GroundKeys {
                rough: Some(RoughKeys {
                    amplitude,
                    wavelength,
                    seed,
                    size,
                    spacing,
                }),
                ..GroundKeys::default()
            },
            GroundFile::Slope { degrees } => GroundKeys {
                slope: Some(SlopeKeys { degrees }),
                ..GroundKeys::default()
            },
        }
    }
}

impl Default for GroundFile {
    fn default() -> Self {
        GroundFile::Plane {}
    }
}

/// A static obstacle's shape and size.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "lowercase", deny_unknown_fields)]
pub enum ObstacleFile {
    /// `GEOM_BOX`.
    Box {
        /// Half extents, metres.
        half_extents: [f64; 3],
        /// Centre, metres.
        position: [f64; 3],
        /// Rotation about z, radians.
        #[serde(default)]
        yaw: f64,
        /// `changeDynamics(lateralFriction=...)`, when given.
        #[serde(default)]
        lateral_friction: Option<f64>,
    },
    /// `GEOM_CYLINDER`, upright.
    Cylinder {
        /// Radius, metres.
        radius: f64,
        /// Full height, metres.
        height: f64,
        /// Centre, metres.
        position: [f64; 3],
        /// Rotation about z, radians.
        #[serde(default)]
        yaw: f64,
        /// `changeDynamics(lateralFriction=...)`, when given.
        #[serde(default)]
        lateral_friction: Option<f64>,
    },
    /// `GEOM_SPHERE`.
    Sphere {
        /// Radius, metres.
        radius: f64,
        /// Centre, metres.
        position: [f64; 3],
        /// Rotation about z, radians.
        #[serde(default)]
        yaw: f64,
        /// `changeDynamics(lateralFriction=...)`, when given.
        #[serde(default)]
        lateral_friction: Option<f64>,
    },
}

/// A field of upright cylinders on a jittered grid, standing on z = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PegsFile {
    /// Grid spacing, metres.
    pub spacing: f64,
    /// Peg radius, metres.
    pub radius: f64,
    /// Peg height, metres.
    pub height: f64,
    /// Each peg moves by up to this much along x and along y (uniform), metres.
    #[serde(default)]
    pub jitter: f64,
    /// Seed of the jitter.
    #[serde(default)]
    pub seed: u64,
    /// `[x_min, y_min, x_max, y_max]`: grid points from the minimum corner in steps of `spacing`.
    pub area: [f64; 4],
    /// No peg whose grid point lies within this distance of the origin (where robots start), metres.
    #[serde(default)]
    pub keep_clear: f64,
    /// `changeDynamics(lateralFriction=...)` of every peg, when given.
    #[serde(default)]
    pub lateral_friction: Option<f64>,
}

/// A world file as written (see the module docs).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WorldFile {
    /// The ground.
    pub ground: GroundFile,
    /// The ground's lateral friction (`changeDynamics`), when given.
    pub ground_friction: Option<f64>,
    /// Obstacles, created in this order after the ground.
    pub obstacles: Vec<ObstacleFile>,
    /// A peg field, created after `obstacles`.
    pub pegs: Option<PegsFile>,
    /// Media (granular, water) and the regions they fill (docs/media.md); none by default.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub media: Vec<MediumFile>,
}

/// A heightfield grid: `rows` values per line along x, `columns` lines along y.
#[derive(Debug, Clone, PartialEq)]
pub struct Heightfield {
    /// Values per grid line (pybullet's `numHeightfieldRows`).
    pub rows: usize,
    /// Grid lines (`numHeightfieldColumns`).
    pub columns: usize,
    /// `heights[y * rows + x]`, metres before scaling, rounded to float32 as pybullet's client does.
    pub heights: Vec<f32>,
    /// `meshScale`.
    pub scale: [f64; 3],
}

impl Heightfield {
    /// Lowest and highest sample (before scaling).
    pub fn min_max(&self) -> (f32, f32) {
        self.heights
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &h| {
                (lo.min(h), hi.max(h))
            })
    }

    /// Half the grid's extent along x and along y, metres: Bullet centres it on the origin.
    pub fn half_extents(&self) -> (f64, f64) {
        (
            0.5 * (self.rows - 1) as f64 * self.scale[0],
            0.5 * (self.columns - 1) as f64 * self.scale[1],
        )
    }

    /// World position of grid point (x, y) as Bullet places it: centred on the origin, in z at the
    /// middle of the lowest and highest sample.
    pub fn point(&self, x: usize, y: usize) -> [f64; 3] {
        self.point_about(x, y, self.middle())
    }

    /// Every grid point, line by line (x fastest), as [`Heightfield::point`] gives them; the middle
    /// height is found once (per point, a scan of the whole grid made drawing and the start height
    /// of a 64 x 64 grid cost 17 million comparisons).
    pub fn points(&self) -> impl Iterator<Item = [f64; 3]> + '_ {
        let mid = self.middle();
        (0..self.columns)
            .flat_map(move |y| (0..self.rows).map(move |x| self.point_about(x, y, mid)))
    }

    /// Middle of the lowest and highest sample, where Bullet puts z = 0 of the grid.
    pub(crate) fn middle(&self) -> f64 {
        let (lo, hi) = self.min_max();
        0.5 * (lo as f64 + hi as f64)
    }

    fn point_about(&self, x: usize, y: usize, mid: f64) -> [f64; 3] {
        let [sx, sy, sz] = self.scale;
        [
            (x as f64 - 0.5 * (self.rows - 1) as f64) * sx,
            (y as f64 - 0.5 * (self.columns - 1) as f64) * sy,
            (self.heights[y * self.rows + x] as f64 - mid) * sz,
        ]
    }

    /// Writes the grid as the CSV a heightfield ground reads.
    pub fn to_csv(&self) -> String {
        let mut out = String::new();
        for line in self.heights.chunks(self.rows) {
            let values: Vec<String> = line.iter().map(|h| format!("{h:?}")).collect();
            out.push_str(&values.join(","));
            out.push('\n');
        }
        out
    }
}

/// The ground, resolved.
#[derive(Debug, Clone, PartialEq)]
pub enum Ground {
    /// The plane z = 0.
    Plane,
    /// The plane tilted about x by this many degrees.
    Slope(f64),
    /// A heightfield grid.
    Heightfield(Heightfield),
}

/// One static obstacle, resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Obstacle {
    /// Shape and size.
    pub shape: ObstacleShape,
    /// Centre, metres.
    pub position: [f64; 3],
    /// Rotation about z, radians.
    pub yaw: f64,
    /// Lateral friction, when set.
    pub lateral_friction: Option<f64>,
}

/// An obstacle's shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ObstacleShape {
    /// A box of these half extents.
    Box([f64; 3]),
    /// An upright cylinder.
    Cylinder {
        /// Radius, metres.
        radius: f64,
        /// Full height, metres.
        height: f64,
    },
    /// A sphere of this radius.
    Sphere(f64),
}

/// A world: its ground, the ground's friction and the obstacles (pegs expanded), ready to build.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldSpec {
    /// The ground.
    pub ground: Ground,
    /// The ground's lateral friction, when set.
    pub ground_friction: Option<f64>,
    /// Every obstacle in creation order.
    pub obstacles: Vec<Obstacle>,
    /// The media, checked (empty: the rigid world of pybullet, built and stepped as before).
    pub media: Vec<Medium>,
}

impl Default for WorldSpec {
    /// The flat plane of every run before worlds: nothing but `createMultiBody(0, GEOM_PLANE)`.
    fn default() -> Self {
        WorldSpec {
            ground: Ground::Plane,
            ground_friction: None,
            obstacles: Vec::new(),
            media: Vec::new(),
        }
    }
}

fn check_friction(what: &str, v: Option<f64>) -> Result<()> {
    match v {
        Some(f) => check_range(what, f, 0.0, MAX_WORLD_FRICTION),
        None => Ok(()),
    }
}

fn check_size(what: &str, v: f64) -> Result<()> {
    check_range_above(what, v, 0.0, MAX_OBSTACLE_SIZE)
}

fn check_point(what: &str, p: [f64; 3]) -> Result<()> {
    check_position(what, p[0], p[1])?;
    check_range(
        &format!("{what} z"),
        p[2],
        -MAX_TERRAIN_HEIGHT,
        MAX_TERRAIN_HEIGHT,
    )
}

impl ObstacleFile {
    fn resolve(&self, what: &str) -> Result<Obstacle> {
        let (shape, position, yaw, lateral_friction) = match *self {
            ObstacleFile::Box {
                half_extents,
                position,
                yaw,
                lateral_friction,
            } => {
                for h in half_extents {
                    check_size(&format!("{what}: half_extents"), h)?;
                }
                (
                    ObstacleShape::Box(half_extents),
                    position,
                    yaw,
                    lateral_friction,
                )
            }
            ObstacleFile::Cylinder {
                radius,
                height,
                position,
                yaw,
                lateral_friction,
            } => {
                check_size(&format!("{what}: radius"), radius)?;
                check_size(&format!("{what}: height"), height)?;
                (
                    ObstacleShape::Cylinder { radius, height },
                    position,
                    yaw,
                    lateral_friction,
                )
            }
            ObstacleFile::Sphere {
                radius,
                position,
                yaw,
                lateral_friction,
            } => {
                check_size(&format!("{what}: radius"), radius)?;
                (
                    ObstacleShape::Sphere(radius),
                    position,
                    yaw,
                    lateral_friction,
                )
            }
        };
        check_point(&format!("{what}: position"), position)?;
        check_range(&format!("{what}: yaw"), yaw, -MAX_YAW, MAX_YAW)?;
        check_friction(&format!("{what}: lateral_friction"), lateral_friction)?;
        Ok(Obstacle {
            shape,
            position,
            yaw,
            lateral_friction,
        })
    }
}

impl PegsFile {
    /// The pegs, in grid order (x fastest), each jittered by two uniform draws (x then y).
    pub fn expand(&self) -> Result<Vec<Obstacle>> {
        check_size("pegs: spacing", self.spacing)?;
        check_size("pegs: radius", self.radius)?;
        check_size("pegs: height", self.height)?;
        check_range("pegs: jitter", self.jitter, 0.0, MAX_OBSTACLE_SIZE)?;
        check_range("pegs: keep_clear", self.keep_clear, 0.0, MAX_OBSTACLE_SIZE)?;
        check_friction("pegs: lateral_friction", self.lateral_friction)?;
        let [x0, y0, x1, y1] = self.area;
        check_position("pegs: area minimum", x0, y0)?;
        check_position("pegs: area maximum", x1, y1)?;
        if x1 < x0 || y1 < y0 {
            return Err(invalid(format!(
                "pegs: area must be [x_min, y_min, x_max, y_max] with x_min <= x_max and y_min <= y_max, got {:?}",
                self.area
            )));
        }
        let count = |lo: f64, hi: f64| ((hi - lo) / self.spacing).floor() + 1.0;
        let (nx, ny) = (count(x0, x1), count(y0, y1));
        if nx * ny > MAX_OBSTACLES as f64 {
            return Err(invalid(format!(
                "pegs: {nx} x {ny} grid points, more than the {MAX_OBSTACLES} obstacles a world may have"
            )));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut pegs = Vec::new();
        for j in 0..ny as usize {
            for i in 0..nx as usize {
                let (gx, gy) = (x0 + i as f64 * self.spacing, y0 + j as f64 * self.spacing);
                let (dx, dy) = if self.jitter > 0.0 {
                    (
                        rng.gen_range(-self.jitter..=self.jitter),
                        rng.gen_range(-self.jitter..=self.jitter),
                    )
                } else {
                    (0.0, 0.0)
                };
                if gx.hypot(gy) < self.keep_clear {
                    continue;
                }
                let position = [gx + dx, gy + dy, 0.5 * self.height];
                check_point("pegs: a peg's position", position)?;
                pegs.push(Obstacle {
                    shape: ObstacleShape::Cylinder {
                        radius: self.radius,
                        height: self.height,
                    },
                    position,
                    yaw: 0.0,
                    lateral_friction: self.lateral_friction,
                });
            }
        }
        Ok(pegs)
    }
}

/// The smoothstep weight `3 t^2 - 2 t^3` of `t` clamped to [0, 1].
pub(crate) fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Value noise on a lattice of `wavelength`: uniform values in [-1, 1] at lattice points (drawn row by
/// row from `seed`), blended with the smoothstep weight, times `amplitude`. Only +, *, floor: the same
/// bits on every platform.
pub fn rough_heights(
    amplitude: f64,
    wavelength: f64,
    seed: u64,
    rows: usize,
    columns: usize,
    spacing: f64,
) -> Result<Vec<f32>> {
    // The lattice's size, checked in floating point before anything is allocated.
    let points = |n: usize| ((n.max(1) - 1) as f64 * spacing / wavelength).floor() + 2.0;
    let (px, py) = (points(rows), points(columns));
    if (px * py).is_nan() || px * py > MAX_NOISE_LATTICE as f64 {
        return Err(invalid(format!(
            "wavelength {} m over {rows} x {columns} samples {} m apart needs {} x {} noise values, \
             more than {MAX_NOISE_LATTICE}: raise the wavelength (or the spacing)",
            crate::limits::short(wavelength),
            crate::limits::short(spacing),
            crate::limits::short(px),
            crate::limits::short(py)
        )));
    }
    let lattice = |n: usize| ((n - 1) as f64 * spacing / wavelength).floor() as usize + 2;
    let (lx, ly) = (lattice(rows), lattice(columns));
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let values: Vec<f64> = (0..lx * ly).map(|_| rng.gen_range(-1.0..=1.0)).collect();
    let mut heights = Vec::with_capacity(rows * columns);
    for y in 0..columns {
        let v = y as f64 * spacing / wavelength;
        let (j, fy) = (v.floor() as usize, smoothstep(v - v.floor()));
        for x in 0..rows {
            let u = x as f64 * spacing / wavelength;
            let (i, fx) = (u.floor() as usize, smoothstep(u - u.floor()));
            let at = |i: usize, j: usize| values[j * lx + i];
            let bottom = at(i, j) + fx * (at(i + 1, j) - at(i, j));
            let top = at(i, j + 1) + fx * (at(i + 1, j + 1) - at(i, j + 1));
            heights.push((amplitude * (bottom + fy * (top - bottom))) as f32);
        }
    }
    Ok(heights)
}

/// Parses a heightfield CSV (see the module docs): `shown` names the file in errors. Every line must
/// have as many values as the first; values are finite numbers of at most [`MAX_TERRAIN_HEIGHT`] in
/// magnitude; at least 2 x 2 and at most [`MAX_HEIGHTFIELD_SIDE`] a side and
/// [`MAX_HEIGHTFIELD_SAMPLES`] in all. Returns (values per line, lines, heights).
pub fn parse_heightfield_csv(text: &str, shown: &str) -> Result<(usize, usize, Vec<f32>)> {
    let mut rows = 0;
    let mut heights = Vec::new();
    let mut columns = 0;
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let before = heights.len();
        for (k, field) in line.split(',').enumerate() {
            let field = field.trim();
            let v: f64 = field.parse().map_err(|_| {
                // The value is not quoted: a file that is not a heightfield at all (a secret named
                // by mistake) fails here, and none of it is shown.
                invalid(format!(
                    "{shown}: line {}, value {}: not a number",
                    n + 1,
                    k + 1
                ))
            })?;
            if !(v.is_finite() && v.abs() <= MAX_TERRAIN_HEIGHT) {
                return Err(invalid(format!(
                    "{shown}: line {}, value {}: heights must be finite and at most {MAX_TERRAIN_HEIGHT} m in magnitude, got {}",
                    n + 1,
                    k + 1,
                    crate::files::excerpt(field)
                )));
            }
            if k >= MAX_HEIGHTFIELD_SIDE {
                return Err(invalid(format!(
                    "{shown}: line {}: more than {MAX_HEIGHTFIELD_SIDE} values",
                    n + 1
                )));
            }
            heights.push(v as f32);
        }
        let width = heights.len() - before;
        if columns == 0 {
            rows = width;
        } else if width != rows {
            return Err(invalid(format!(
                "{shown}: line {} has {width} values, the first line {rows} (a heightfield is a full grid)",
                n + 1
            )));
        }
        columns += 1;
        if columns > MAX_HEIGHTFIELD_SIDE || heights.len() > MAX_HEIGHTFIELD_SAMPLES {
            return Err(invalid(format!(
                "{shown}: more than {MAX_HEIGHTFIELD_SIDE} lines or {MAX_HEIGHTFIELD_SAMPLES} values"
            )));
        }
    }
    if columns == 0 {
        return Err(invalid(format!("{shown}: empty heightfield")));
    }
    if rows < 2 || columns < 2 {
        return Err(invalid(format!(
            "{shown}: a heightfield needs at least 2 lines of 2 values, got {columns} of {rows}"
        )));
    }
    Ok((rows, columns, heights))
}

fn check_scale(what: &str, scale: [f64; 3]) -> Result<()> {
    for s in scale {
        check_size(what, s)?;
    }
    Ok(())
}

impl WorldSpec {
    /// Reads and checks a world file; `shown` in every error.
    pub fn load(path: &Path) -> Result<Self> {
        Self::read(&Reader::disk(path))
    }

    /// The world of a record of its files ([`RecordedFiles`]), read as if they lay at its path.
    pub fn from_record(record: &RecordedFiles) -> Result<Self> {
        let reader = Reader::record(record);
        let spec = Self::read(&reader)?;
        reader.finish()?;
        Ok(spec)
    }

    fn read(reader: &Reader) -> Result<Self> {
        let shown = reader.path().display().to_string();
        let text = reader.main(MAX_HEIGHTFIELD_BYTES, "world file")?;
        Self::parse_from(&text, &shown, reader)
    }

    /// Parses a world file's text; heightfield files are read relative to `dir`.
    pub fn parse(text: &str, shown: &str, dir: &Path) -> Result<Self> {
        // A main file in `dir`, for the names it gives; never read.
        let main = dir.join("world.yaml");
        Self::parse_from(text, shown, &Reader::disk(&main))
    }

    fn parse_from(text: &str, shown: &str, reader: &Reader) -> Result<Self> {
        let file: WorldFile = if text.trim().is_empty() {
            WorldFile::default()
        } else {
            crate::files::check_yaml_shape(text, shown)?;
            crate::files::from_yaml(text, shown, "a world file")?
        };
        file.resolve_from(shown, reader)
    }
}

impl WorldFile {
    /// Checks every value and reads or generates the ground; `shown` prefixes every error.
    pub fn resolve(&self, shown: &str, dir: &Path) -> Result<WorldSpec> {
        let main = dir.join("world.yaml");
        self.resolve_from(shown, &Reader::disk(&main))
    }

    fn resolve_from(&self, shown: &str, reader: &Reader) -> Result<WorldSpec> {
        let e = |err: crate::Error| invalid(format!("{shown}: {}", err.message()));
        let ground = match &self.ground {
            GroundFile::Plane {} => Ground::Plane,
            GroundFile::Slope { degrees } => {
                check_range(
                    "ground: slope: degrees",
                    *degrees,
                    -MAX_SLOPE_DEGREES,
                    MAX_SLOPE_DEGREES,
                )
                .map_err(e)?;
                Ground::Slope(*degrees)
            }
            GroundFile::Heightfield { file, scale } => {
                check_scale("ground: heightfield: scale", *scale).map_err(e)?;
                let path = reader.dir().join(file);
                let csv_shown = path.display().to_string();
                let text = reader
                    .named(file.as_ref(), MAX_HEIGHTFIELD_BYTES, "heightfield")
                    .map_err(|err| {
                        invalid(format!(
                            "{shown}: ground: heightfield: file: {}",
                            err.message()
                        ))
                    })?;
                let (rows, columns, heights) =
                    parse_heightfield_csv(&text, &csv_shown).map_err(|err| {
                        invalid(format!(
                            "{shown}: ground: heightfield: file: {}",
                            err.message()
                        ))
                    })?;
                Ground::Heightfield(Heightfield {
                    rows,
                    columns,
                    heights,
                    scale: *scale,
                })
            }
            GroundFile::Rough {
                amplitude,
                wavelength,
                seed,
                size,
                spacing,
            } => {
                check_range(
                    "ground: rough: amplitude",
                    *amplitude,
                    0.0,
                    MAX_TERRAIN_HEIGHT,
                )
                .map_err(e)?;
                check_size("ground: rough: wavelength", *wavelength).map_err(e)?;
                let spacing = spacing.unwrap_or(wavelength / 8.0);
                check_size("ground: rough: spacing", spacing).map_err(e)?;
                for s in size {
                    check_range(
                        "ground: rough: size",
                        *s,
                        0.0,
                        2.0 * crate::limits::MAX_POSITION,
                    )
                    .map_err(e)?;
                }
                let samples = |s: f64| (s / spacing).floor() + 1.0;
                let (rows, columns) = (samples(size[0]), samples(size[1]));
                if rows < 2.0
                    || columns < 2.0
                    || rows > MAX_HEIGHTFIELD_SIDE as f64
                    || columns > MAX_HEIGHTFIELD_SIDE as f64
                    || rows * columns > MAX_HEIGHTFIELD_SAMPLES as f64
                {
                    return Err(invalid(format!(
                        "{shown}: ground: rough: size / spacing gives {rows} x {columns} samples; \
                         a heightfield has 2 to {MAX_HEIGHTFIELD_SIDE} a side and at most \
                         {MAX_HEIGHTFIELD_SAMPLES}"
                    )));
                }
                let (rows, columns) = (rows as usize, columns as usize);
                Ground::Heightfield(Heightfield {
                    rows,
                    columns,
                    heights: rough_heights(*amplitude, *wavelength, *seed, rows, columns, spacing)
                        .map_err(|err| {
                            invalid(format!("{shown}: ground: rough: {}", err.message()))
                        })?,
                    scale: [spacing, spacing, 1.0],
                })
            }
        };
        check_friction("ground_friction", self.ground_friction).map_err(e)?;
        if self.obstacles.len() > MAX_OBSTACLES {
            return Err(invalid(format!(
                "{shown}: obstacles: {} obstacles, at most {MAX_OBSTACLES}",
                self.obstacles.len()
            )));
        }
        let mut obstacles = Vec::with_capacity(self.obstacles.len());
        for (k, o) in self.obstacles.iter().enumerate() {
            obstacles.push(o.resolve(&format!("obstacles[{k}]")).map_err(e)?);
        }
        if let Some(pegs) = &self.pegs {
            obstacles.extend(pegs.expand().map_err(e)?);
        }
        if obstacles.len() > MAX_OBSTACLES {
            return Err(invalid(format!(
                "{shown}: {} obstacles with the pegs, at most {MAX_OBSTACLES}",
                obstacles.len()
            )));
        }
        if self.media.len() > MAX_MEDIA {
            return Err(invalid(format!(
                "{shown}: media: {} media, at most {MAX_MEDIA}",
                self.media.len()
            )));
        }
        let media = self
            .media
            .iter()
            .enumerate()
            .map(|(k, m)| m.resolve(&format!("media[{k}]")).map_err(e))
            .collect::<Result<Vec<_>>>()?;
        if !matches!(ground, Ground::Plane)
            && media.iter().any(|m| matches!(m, Medium::Granular(_)))
        {
            return Err(invalid(format!(
                "{shown}: media: a granular medium needs the plane ground (ground: {{plane: {{}}}}): \
                 the ground gives way inside its area"
            )));
        }
        crate::media::water::check_overlap(&media).map_err(e)?;
        Ok(WorldSpec {
            ground,
            ground_friction: self.ground_friction,
            obstacles,
            media,
        })
    }
}

impl Obstacle {
    /// The obstacle's collision shape for [`World::add_static`].
    pub fn static_shape(&self) -> StaticShape<'static> {
        match self.shape {
            ObstacleShape::Box(half_extents) => StaticShape::Box { half_extents },
            ObstacleShape::Cylinder { radius, height } => StaticShape::Cylinder { radius, height },
            ObstacleShape::Sphere(radius) => StaticShape::Sphere { radius },
        }
    }

    /// Orientation (x, y, z, w): `getQuaternionFromEuler([0, 0, yaw])`.
    pub fn orientation(&self) -> [f64; 4] {
        quaternion_from_euler(0.0, 0.0, self.yaw)
    }
}

impl WorldSpec {
    /// True when a granular medium makes the ground give way (docs/media.md).
    pub fn has_granular(&self) -> bool {
        self.media.iter().any(|m| matches!(m, Medium::Granular(_)))
    }

    /// True for the plain flat plane (what every run used before world files).
    pub fn is_flat_plane(&self) -> bool {
        *self == WorldSpec::default()
    }

    /// The ground's orientation (x, y, z, w): the slope's `getQuaternionFromEuler([radians(D), 0, 0])`,
    /// else the identity.
    pub fn ground_orientation(&self) -> [f64; 4] {
        match self.ground {
            Ground::Slope(degrees) => quaternion_from_euler(degrees.to_radians(), 0.0, 0.0),
            _ => [0.0, 0.0, 0.0, 1.0],
        }
    }

    /// Adds the ground, its friction and the obstacles to `world` in the module docs' order; returns
    /// the ground's body and the obstacles' bodies.
    pub fn build(&self, world: &mut World) -> Result<(BodyId, Vec<BodyId>)> {
        // The slabs and floors around and under granular media (none without them).
        let mut slabs = Vec::new();
        let ground = match &self.ground {
            Ground::Plane if self.has_granular() => {
                slabs = crate::media::ground::build(&self.media, world)?;
                slabs[0]
            }
            // The exact calls of every run before world files.
            Ground::Plane => world.add_plane()?,
            Ground::Slope(_) => {
                world.add_static(&StaticShape::Plane, [0.0; 3], self.ground_orientation())?
            }
            Ground::Heightfield(h) => world.add_static(
                &StaticShape::Heightfield {
                    rows: h.rows,
                    columns: h.columns,
                    heights: &h.heights,
                    scale: h.scale,
                },
                [0.0; 3],
                [0.0, 0.0, 0.0, 1.0],
            )?,
        };
        if let Some(mu) = self.ground_friction {
            let d = Dynamics {
                lateral_friction: Some(mu),
                ..Dynamics::default()
            };
            world.change_dynamics(ground, None, &d)?;
            // The slabs and floors around and under a granular medium are the ground too.
            for &body in slabs.iter().skip(1) {
                world.change_dynamics(body, None, &d)?;
            }
        }
        let mut bodies = Vec::with_capacity(self.obstacles.len());
        for o in &self.obstacles {
            let body = world.add_static(&o.static_shape(), o.position, o.orientation())?;
            if let Some(mu) = o.lateral_friction {
                let d = Dynamics {
                    lateral_friction: Some(mu),
                    ..Dynamics::default()
                };
                world.change_dynamics(body, None, &d)?;
            }
            bodies.push(body);
        }
        Ok((ground, bodies))
    }

    /// Highest point of the ground within `radius` of the origin (in x and y), metres: where a body
    /// placed for the flat plane would start inside the ground, its default start is raised by this.
    pub fn ground_top(&self, radius: f64) -> f64 {
        match &self.ground {
            Ground::Plane => 0.0,
            Ground::Slope(degrees) => radius * degrees.to_radians().tan().abs(),
            Ground::Heightfield(h) => {
                let mut top = f64::NEG_INFINITY;
                for [px, py, pz] in h.points() {
                    if px.hypot(py) <= radius + h.scale[0].max(h.scale[1]) {
                        top = top.max(pz);
                    }
                }
                if top.is_finite() {
                    top.max(0.0)
                } else {
                    0.0
                }
            }
        }
    }
}

/// The ground as a viewer draws it.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum GroundDrawing {
    /// A plane through the origin with this orientation (x, y, z, w): z = 0 turned by it.
    Plane {
        /// The ground body's orientation.
        orientation: [f64; 4],
    },
    /// A grid of `rows` points along x by `columns` along y; `points` holds x, y, z of each point,
    /// line by line, where Bullet placed them (centred, see [`Heightfield::point`]).
    Heightfield {
        /// Points per grid line.
        rows: usize,
        /// Grid lines.
        columns: usize,
        /// x, y, z per point.
        points: Vec<f64>,
    },
}

/// A world as a viewer draws it (the metadata of a run's trace, for Rerun).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorldDrawing {
    /// The ground.
    pub ground: GroundDrawing,
    /// Each obstacle: box (full extents), sphere (radius, 0, 0) or cylinder (radius, height, 0), with
    /// its pose, as a robot's shapes are described.
    pub obstacles: Vec<crate::drawing::ShapeDrawing>,
    /// Each water region as the box it fills: `[x_min, y_min, z_min, x_max, y_max, z_max]`, `z_max` its
    /// surface (docs/media.md); left out when there is none, so a dry world's drawing is as before.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub water: Vec<[f64; 6]>,
}

impl WorldSpec {
    /// What a viewer needs to draw the world.
    pub fn drawing(&self) -> WorldDrawing {
        let ground = match &self.ground {
            Ground::Heightfield(h) => GroundDrawing::Heightfield {
                rows: h.rows,
                columns: h.columns,
                points: h.points().flatten().collect(),
            },
            _ => GroundDrawing::Plane {
                orientation: self.ground_orientation(),
            },
        };
        let obstacles = self
            .obstacles
            .iter()
            .map(|o| {
                let (kind, size) = match o.shape {
                    ObstacleShape::Box(h) => ("box", [2.0 * h[0], 2.0 * h[1], 2.0 * h[2]]),
                    ObstacleShape::Cylinder { radius, height } => {
                        ("cylinder", [radius, height, 0.0])
                    }
                    ObstacleShape::Sphere(r) => ("sphere", [r, 0.0, 0.0]),
                };
                let [x, y, z] = o.position;
                let [qx, qy, qz, qw] = o.orientation();
                crate::drawing::ShapeDrawing {
                    kind,
                    size,
                    pose: [x, y, z, qx, qy, qz, qw],
                }
            })
            .collect();
        let water = self
            .media
            .iter()
            .filter_map(|m| match m {
                Medium::Water(w) => {
                    let (lo, hi) = (w.region.min, w.region.max);
                    Some([lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]])
                }
                _ => None,
            })
            .collect();
        WorldDrawing {
            ground,
            obstacles,
            water,
        }
    }
}

/// A world named by its file, as an [`EnvConfig`](crate::EnvConfig) holds it, with the texts it was
/// read from ([`WorldRef::files`]); serialised as its path, or as its record when made from one
/// (see [`RobotRef`](crate::RobotRef)), and deserialised from either, loaded and checked.
#[derive(Debug, Clone)]
pub struct WorldRef {
    path: PathBuf,
    spec: Arc<WorldSpec>,
    files: Arc<RecordedFiles>,
    recorded: bool,
}

impl WorldRef {
    /// Reads and checks a world file.
    pub fn load(path: &Path) -> Result<Self> {
        let reader = Reader::disk(path);
        let spec = WorldSpec::read(&reader)?;
        Ok(WorldRef {
            path: path.to_path_buf(),
            spec: Arc::new(spec),
            files: Arc::new(reader.finish()?),
            recorded: false,
        })
    }

    /// The world of a record of its files, checked as [`WorldRef::load`] checks a file.
    pub fn from_record(record: &RecordedFiles) -> Result<Self> {
        Ok(WorldRef {
            path: record.path.clone(),
            spec: Arc::new(WorldSpec::from_record(record)?),
            files: Arc::new(record.clone()),
            recorded: true,
        })
    }

    /// The texts it was read from: the world file and its heightfield file, if any.
    pub fn files(&self) -> &RecordedFiles {
        &self.files
    }

    /// True when it was made from a record rather than read from its path.
    pub fn is_recorded(&self) -> bool {
        self.recorded
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The world.
    pub fn spec(&self) -> &WorldSpec {
        &self.spec
    }
}

impl PartialEq for WorldRef {
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path && self.spec == other.spec
    }
}

impl Serialize for WorldRef {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        if self.recorded {
            self.files.serialize(s)
        } else {
            self.path.serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for WorldRef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        match FileOrRecord::deserialize(d)? {
            FileOrRecord::Path(path) => WorldRef::load(&path),
            FileOrRecord::Record(record) => WorldRef::from_record(&record),
        }
        .map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_file_is_the_plane() {
        let w = WorldSpec::parse("", "w.yaml", Path::new(".")).unwrap();
        assert!(w.is_flat_plane());
        let w = WorldSpec::parse("ground: {plane: {}}\n", "w.yaml", Path::new(".")).unwrap();
        assert!(w.is_flat_plane());
    }

    #[test]
    fn unknown_keys_and_shapes_are_refused() {
        for bad in [
            "grund: {plane: {}}",
            "ground: {moon: {}}",
            "obstacles: [{shape: cone, radius: 1, position: [0, 0, 0]}]",
            "obstacles: [{shape: box, half_extents: [1, 1, 1], position: [0, 0, 0], colour: red}]",
            "obstacles: [{shape: box, half_extents: [-1, 1, 1], position: [0, 0, 0]}]",
            "obstacles: [{shape: sphere, radius: 1, position: [1e9, 0, 0]}]",
            "ground: {slope: {degrees: 95}}",
            "ground_friction: -1",
        ] {
            let err = WorldSpec::parse(bad, "w.yaml", Path::new(".")).unwrap_err();
            let text = err.to_string();
            assert!(
                text.contains("w.yaml") && !text.contains('\n'),
                "{bad}: {text}"
            );
        }
    }

    #[test]
    fn csv_errors_name_the_line() {
        assert!(parse_heightfield_csv("", "h.csv").is_err());
        let e = parse_heightfield_csv("1,2\n3\n", "h.csv").unwrap_err();
        assert!(e.to_string().contains("line 2"), "{e}");
        let e = parse_heightfield_csv("1,x\n3,4\n", "h.csv").unwrap_err();
        assert!(e.to_string().contains("not a number"), "{e}");
        assert!(parse_heightfield_csv("1,inf\n3,4\n", "h.csv").is_err());
        assert!(parse_heightfield_csv("1,NaN\n3,4\n", "h.csv").is_err());
        let (r, c, h) = parse_heightfield_csv("0, 0.5, 1\n1,2,3\n", "h.csv").unwrap();
        assert_eq!((r, c, h.len()), (3, 2, 6));
    }

    #[test]
    fn pegs_expand_on_their_grid() {
        let pegs = PegsFile {
            spacing: 1.0,
            radius: 0.05,
            height: 0.2,
            jitter: 0.0,
            seed: 0,
            area: [-1.0, -1.0, 1.0, 1.0],
            keep_clear: 0.5,
            lateral_friction: None,
        };
        let p = pegs.expand().unwrap();
        assert_eq!(p.len(), 8);
        assert_eq!(p[0].position, [-1.0, -1.0, 0.1]);
    }

    #[test]
    fn rough_is_deterministic_and_bounded() {
        let a = rough_heights(0.1, 0.5, 3, 17, 9, 0.0625).unwrap();
        assert_eq!(a, rough_heights(0.1, 0.5, 3, 17, 9, 0.0625).unwrap());
        assert!(a.iter().all(|h| h.abs() <= 0.1));
        assert_ne!(a, rough_heights(0.1, 0.5, 4, 17, 9, 0.0625).unwrap());
    }
}
