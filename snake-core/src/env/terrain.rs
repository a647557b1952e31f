//! Random terrain per episode: a peg field between the start and the goal, and rough ground with
//! hills, craters and ridges, drawn from the episode's random stream at each reset (docs/tasks.md).
//! Geometry only: [`Layout`] is the world and the shapes drawn into it; the settings here that
//! concern the task (`craters.terminate`, `craters.clearance`, `ridges.clearance`) are read, with
//! the reward's, in one place (env/course.rs), and the ways around shapes are env/route.rs.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::route::{Disc, Segment};
use crate::error::{invalid_at, Result};
use crate::limits::{
    check_key_range, check_key_range_above, MAX_CRATERS, MAX_HEIGHTFIELD_SAMPLES,
    MAX_HEIGHTFIELD_SIDE, MAX_OBSTACLES, MAX_OBSTACLE_SIZE, MAX_RIDGES, MAX_TERRAIN_HEIGHT,
    MAX_WORLD_FRICTION,
};
use crate::math::StartPose;
use crate::world_file::{
    rough_heights, smoothstep, Ground, Heightfield, Obstacle, ObstacleShape, WorldSpec,
};

/// What each episode's world adds to the env's world (or to the flat plane): a peg field, rough
/// ground, or both. The env draws one `u64` from its episode stream after the goal and seeds the
/// layout with it (ChaCha8), so a reset seed gives one layout and other seeds other layouts.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TerrainDistribution {
    /// A peg field in a band from the start towards the goal (`None`: no pegs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pegs: Option<PegField>,
    /// Rough ground replacing the ground (`None`: the world's ground). An episode ends (terminated,
    /// unsuccessful) when the head leaves its square: beyond it the body falls off the world.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rough: Option<RoughGround>,
}

/// Upright cylinders on a jittered grid in the frame of the line from the start to the goal: grid
/// points `along = start_clear + i * spacing` (up to the goal's distance less `goal_clear`) and
/// `across = -width / 2 + j * spacing` (up to `width / 2`), each kept with probability `density`
/// and moved by uniform draws in [-jitter, jitter] along and across.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PegField {
    /// Grid spacing, metres (0.3).
    pub spacing: f64,
    /// Peg radius, metres (0.03).
    pub radius: f64,
    /// Peg height, metres (0.3).
    pub height: f64,
    /// Largest move of a peg along and across, metres (0.08).
    pub jitter: f64,
    /// Probability that a grid point holds a peg (0.7).
    pub density: f64,
    /// Width of the band, metres, centred on the start-goal line (3.0).
    pub width: f64,
    /// Free distance after the start, metres (1.0).
    pub start_clear: f64,
    /// Free distance before the goal, metres (1.0).
    pub goal_clear: f64,
    /// Lateral friction of every peg, when given (`None`: Bullet's 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lateral_friction: Option<f64>,
}

impl Default for PegField {
    fn default() -> Self {
        PegField {
            spacing: 0.3,
            radius: 0.03,
            height: 0.3,
            jitter: 0.08,
            density: 0.7,
            width: 3.0,
            start_clear: 1.0,
            goal_clear: 1.0,
            lateral_friction: None,
        }
    }
}

/// Rough ground: the sum of two value-noise octaves (`ground.rough` of docs/worlds.md), bumps
/// (`amplitude`, `wavelength`) and hills (`hills_amplitude`, `hills_wavelength`: the slopes),
/// sampled every `spacing` over a square centred on the origin that reaches `margin` beyond the
/// start and the goal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RoughGround {
    /// Largest height of the bumps, metres (0.08).
    pub amplitude: f64,
    /// Distance between the bumps' lattice values, metres (0.5).
    pub wavelength: f64,
    /// Largest height of the hills, metres (1.2).
    pub hills_amplitude: f64,
    /// Distance between the hills' lattice values, metres (3.0).
    pub hills_wavelength: f64,
    /// Grid spacing, metres (0.125).
    pub spacing: f64,
    /// Ground beyond the start and the goal, metres (3.0).
    pub margin: f64,
    /// Craters sunk into the ground across the straight line from the start to the goal
    /// ([`Craters`]; `count` 0, the default: none, and left out when written).
    #[serde(skip_serializing_if = "Craters::is_empty")]
    pub craters: Craters,
    /// Ridges raised across the straight line from the start to the goal ([`Ridges`]; `count` 0,
    /// the default: none, and left out when written).
    #[serde(skip_serializing_if = "Ridges::is_empty")]
    pub ridges: Ridges,
    /// The ground's lateral friction, when given (`None`: Bullet's 0.5).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
}

impl Default for RoughGround {
    fn default() -> Self {
        RoughGround {
            amplitude: 0.08,
            wavelength: 0.5,
            hills_amplitude: 1.2,
            hills_wavelength: 3.0,
            spacing: 0.125,
            margin: 3.0,
            craters: Craters::default(),
            ridges: Ridges::default(),
            friction: None,
        }
    }
}

/// Flat-bottomed round craters across the straight line from the start to the goal: each centre lies
/// `along` metres from the start, uniform in [`start_clear + radius`, `distance - goal_clear -
/// radius`] (the midpoint where that is empty), and `across` it, uniform in [-`offset`, `offset`];
/// the ground inside `radius - wall` lies `depth` below the rough ground and rises over the `wall`
/// (a smoothstep, steepest in its middle: `1.5 * depth / wall`). Where craters overlap the deeper
/// wins. A crater wider than the body is a trap for a snake that crawls in: its walls are too steep
/// to climb out (docs/tasks.md, "A crater in the way"). With `terminate`, an episode ends there
/// (terminated, unsuccessful) as soon as the head is over a crater's floor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Craters {
    /// How many craters (0).
    pub count: usize,
    /// Radius to the top of the wall, metres (3.0).
    pub radius: f64,
    /// Depth, metres (2.5).
    pub depth: f64,
    /// Width of the wall, metres (0.75).
    pub wall: f64,
    /// Largest distance of a centre from the straight line, metres (1.5).
    pub offset: f64,
    /// Ground free of craters around the start (the base: the cube snake's head), metres (3.0).
    /// The body lies behind the head (5.1 m at 10 joints), so with the goal behind it the tail
    /// may start on the crater's rim.
    pub start_clear: f64,
    /// Ground free of craters before the goal, metres (1.0).
    pub goal_clear: f64,
    /// End the episode (terminated, unsuccessful) once the head is over a crater's floor, within
    /// `radius - wall` of its centre (false: the snake may climb out again). Left out when false.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub terminate: bool,
    /// How far outside the rim the way around a crater keeps, metres (1.0): the way the progress
    /// term measures with `reward.progress_around_craters` goes around a disc this much wider than
    /// the crater, so that it does not lead the body along the edge it slides in from.
    pub clearance: f64,
}

impl Default for Craters {
    fn default() -> Self {
        Craters {
            count: 0,
            radius: 3.0,
            depth: 2.5,
            wall: 0.75,
            offset: 1.5,
            start_clear: 3.0,
            goal_clear: 1.0,
            terminate: false,
            clearance: 1.0,
        }
    }
}

impl Craters {
    /// No crater.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    fn validate(&self) -> Result<()> {
        if self.count > MAX_CRATERS {
            return Err(invalid_at(
                "terrain.rough.craters.count",
                format!("must be at most {MAX_CRATERS}, got {}", self.count),
            ));
        }
        size("terrain.rough.craters.radius", self.radius)?;
        check_key_range(
            "terrain.rough.craters.depth",
            self.depth,
            0.0,
            MAX_TERRAIN_HEIGHT,
        )?;
        check_key_range("terrain.rough.craters.wall", self.wall, 0.0, self.radius)?;
        for (what, v) in [
            ("terrain.rough.craters.offset", self.offset),
            ("terrain.rough.craters.start_clear", self.start_clear),
            ("terrain.rough.craters.goal_clear", self.goal_clear),
            ("terrain.rough.craters.clearance", self.clearance),
        ] {
            check_key_range(what, v, 0.0, MAX_OBSTACLE_SIZE)?;
        }
        Ok(())
    }

    /// Sinks the craters into the `n` x `n` heights (laid out as [`add_over_grid`] says), drawing
    /// their centres from `rng`; returns the centres.
    fn sink(
        &self,
        heights: &mut [f32],
        n: usize,
        spacing: f64,
        start: &StartPose,
        goal: (f64, f64),
        rng: &mut ChaCha8Rng,
    ) -> Vec<(f64, f64)> {
        if self.is_empty() {
            return Vec::new();
        }
        let centres = along_the_line(
            self.count,
            (
                self.start_clear + self.radius,
                self.goal_clear + self.radius,
            ),
            self.offset,
            start,
            goal,
            rng,
        );
        add_over_grid(heights, n, spacing, |x, y| {
            let sink = centres
                .iter()
                .map(|&(cx, cy)| {
                    let r = (x - cx).hypot(y - cy);
                    let rise = if self.wall > 0.0 {
                        smoothstep((r - (self.radius - self.wall)) / self.wall)
                    } else {
                        f64::from(u8::from(r >= self.radius))
                    };
                    self.depth * (1.0 - rise)
                })
                .fold(0.0, f64::max);
            -sink
        });
        centres
    }
}

/// Straight ridges raised across the straight line from the start to the goal, too steep and too
/// high for the snake to crawl over: each is a crest `length` long, perpendicular to the line, whose
/// middle lies `along` metres from the start, uniform in [`start_clear`, `distance - goal_clear`]
/// (the midpoint where that is empty), and `across` it, uniform in [-`offset`, `offset`]. Within
/// `crest / 2` of the crest line (a segment, so its ends are round) the ground lies `height` above
/// the rough ground; over the next `wall` metres it falls back (a smoothstep, steepest in its
/// middle: `1.5 * height / wall`). Where ridges overlap the higher wins. A ridge is a trap for a
/// controller that heads straight for the goal: pressed against its flat side, the goal's bearing
/// pulls the head back to the middle (docs/tasks.md, "A ridge across the way").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Ridges {
    /// How many ridges (0).
    pub count: usize,
    /// Length of the crest line, metres (6.0).
    pub length: f64,
    /// Height above the rough ground, metres (1.5).
    pub height: f64,
    /// Width of the flat crest, metres (0.5).
    pub crest: f64,
    /// Width of each side, metres (0.5).
    pub wall: f64,
    /// Largest distance of a ridge's middle from the straight line, metres (0.5).
    pub offset: f64,
    /// Least distance of a ridge's crest line from the start (the base: the cube snake's head),
    /// metres (3.0).
    pub start_clear: f64,
    /// Least distance of a ridge's crest line from the goal, metres (2.0).
    pub goal_clear: f64,
    /// How far beyond the ridge's foot the way around it keeps, metres (1.0): the way the progress
    /// term measures with `reward.progress_around_ridges` goes around a capsule this much wider
    /// than the ridge's footprint.
    pub clearance: f64,
}

impl Default for Ridges {
    fn default() -> Self {
        Ridges {
            count: 0,
            length: 6.0,
            height: 1.5,
            crest: 0.5,
            wall: 0.5,
            offset: 0.5,
            start_clear: 3.0,
            goal_clear: 2.0,
            clearance: 1.0,
        }
    }
}

impl Ridges {
    /// No ridge.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// Half the width of a ridge's footprint: from its crest line to the foot of its sides.
    pub fn half_width(&self) -> f64 {
        0.5 * self.crest + self.wall
    }

    fn validate(&self) -> Result<()> {
        if self.count > MAX_RIDGES {
            return Err(invalid_at(
                "terrain.rough.ridges.count",
                format!("must be at most {MAX_RIDGES}, got {}", self.count),
            ));
        }
        check_key_range(
            "terrain.rough.ridges.height",
            self.height,
            0.0,
            MAX_TERRAIN_HEIGHT,
        )?;
        for (what, v) in [
            ("terrain.rough.ridges.length", self.length),
            ("terrain.rough.ridges.crest", self.crest),
            ("terrain.rough.ridges.wall", self.wall),
            ("terrain.rough.ridges.offset", self.offset),
            ("terrain.rough.ridges.start_clear", self.start_clear),
            ("terrain.rough.ridges.goal_clear", self.goal_clear),
            ("terrain.rough.ridges.clearance", self.clearance),
        ] {
            check_key_range(what, v, 0.0, MAX_OBSTACLE_SIZE)?;
        }
        Ok(())
    }

    /// Raises the ridges on the `n` x `n` heights (laid out as [`add_over_grid`] says), drawing
    /// their middles from `rng`; returns each crest line's two ends.
    fn raise(
        &self,
        heights: &mut [f32],
        n: usize,
        spacing: f64,
        start: &StartPose,
        goal: (f64, f64),
        rng: &mut ChaCha8Rng,
    ) -> Vec<Segment> {
        if self.is_empty() {
            return Vec::new();
        }
        let (_, (ux, uy)) = line_to_goal(start, goal);
        let half = 0.5 * self.length;
        let middles = along_the_line(
            self.count,
            (self.start_clear, self.goal_clear),
            self.offset,
            start,
            goal,
            rng,
        );
        // Each crest runs across the line: along its left, (-uy, ux).
        let crests: Vec<Segment> = middles
            .into_iter()
            .map(|(mx, my)| Segment {
                a: (mx + half * uy, my - half * ux),
                b: (mx - half * uy, my + half * ux),
            })
            .collect();
        add_over_grid(heights, n, spacing, |x, y| {
            crests
                .iter()
                .map(|s| {
                    let d = s.distance_to((x, y)) - 0.5 * self.crest;
                    let fall = if self.wall > 0.0 {
                        smoothstep(d / self.wall)
                    } else {
                        f64::from(u8::from(d > 0.0))
                    };
                    self.height * (1.0 - fall)
                })
                .fold(0.0, f64::max)
        });
        crests
    }
}

/// `count` points drawn from `rng` `along` the straight line from the start to the goal, uniform in
/// [`clear.0`, `distance - clear.1`] (the midpoint where that is empty), and `across` it, uniform in
/// [-`offset`, `offset`] (to its left), in that order for each point.
fn along_the_line(
    count: usize,
    clear: (f64, f64),
    offset: f64,
    start: &StartPose,
    goal: (f64, f64),
    rng: &mut ChaCha8Rng,
) -> Vec<(f64, f64)> {
    let (distance, (ux, uy)) = line_to_goal(start, goal);
    let (first, last) = (clear.0, distance - clear.1);
    (0..count)
        .map(|_| {
            let along = if last > first {
                rng.gen_range(first..=last)
            } else {
                0.5 * (first + last)
            };
            let across = rng.gen_range(-1.0..=1.0) * offset;
            (
                start.x + along * ux - across * uy,
                start.y + along * uy + across * ux,
            )
        })
        .collect()
}

/// Adds `f(x, y)` to each of the `n` x `n` heights: sample (i, j) at index `j * n + i` lies at
/// ((i - c) * spacing, (j - c) * spacing), c = (n - 1) / 2 (Bullet centres the grid on the origin).
fn add_over_grid(heights: &mut [f32], n: usize, spacing: f64, f: impl Fn(f64, f64) -> f64) {
    let c = 0.5 * (n - 1) as f64;
    for j in 0..n {
        let y = (j as f64 - c) * spacing;
        for i in 0..n {
            let x = (i as f64 - c) * spacing;
            heights[j * n + i] += f(x, y) as f32;
        }
    }
}

/// The distance from the start to the goal and the unit vector towards it (-y, the start heading's
/// ahead, when they coincide): the frame the pegs and the craters are laid out in.
fn line_to_goal(start: &StartPose, goal: (f64, f64)) -> (f64, (f64, f64)) {
    let (dx, dy) = (goal.0 - start.x, goal.1 - start.y);
    let distance = dx.hypot(dy);
    if distance > 0.0 {
        (distance, (dx / distance, dy / distance))
    } else {
        (distance, (0.0, -1.0))
    }
}

fn size(what: &str, v: f64) -> Result<()> {
    check_key_range_above(what, v, 0.0, MAX_OBSTACLE_SIZE)
}

fn friction(what: &str, v: Option<f64>) -> Result<()> {
    v.map_or(Ok(()), |f| {
        check_key_range(what, f, 0.0, MAX_WORLD_FRICTION)
    })
}

impl TerrainDistribution {
    /// Checks every field; the one-line error names it (`terrain.pegs.spacing ...`).
    pub fn validate(&self) -> Result<()> {
        if let Some(p) = &self.pegs {
            size("terrain.pegs.spacing", p.spacing)?;
            size("terrain.pegs.radius", p.radius)?;
            size("terrain.pegs.height", p.height)?;
            size("terrain.pegs.width", p.width)?;
            check_key_range("terrain.pegs.jitter", p.jitter, 0.0, MAX_OBSTACLE_SIZE)?;
            check_key_range("terrain.pegs.density", p.density, 0.0, 1.0)?;
            check_key_range(
                "terrain.pegs.start_clear",
                p.start_clear,
                0.0,
                MAX_OBSTACLE_SIZE,
            )?;
            check_key_range(
                "terrain.pegs.goal_clear",
                p.goal_clear,
                0.0,
                MAX_OBSTACLE_SIZE,
            )?;
            friction("terrain.pegs.lateral_friction", p.lateral_friction)?;
        }
        if let Some(r) = &self.rough {
            check_key_range(
                "terrain.rough.amplitude",
                r.amplitude,
                0.0,
                MAX_TERRAIN_HEIGHT,
            )?;
            check_key_range(
                "terrain.rough.hills_amplitude",
                r.hills_amplitude,
                0.0,
                MAX_TERRAIN_HEIGHT,
            )?;
            size("terrain.rough.wavelength", r.wavelength)?;
            size("terrain.rough.hills_wavelength", r.hills_wavelength)?;
            size("terrain.rough.spacing", r.spacing)?;
            check_key_range("terrain.rough.margin", r.margin, 0.0, MAX_OBSTACLE_SIZE)?;
            r.craters.validate()?;
            r.ridges.validate()?;
            friction("terrain.rough.friction", r.friction)?;
        }
        Ok(())
    }

    /// The episode's world: `base` with the rough ground and the pegs for a start at `start` and a
    /// goal at `goal`, laid out from `seed`. Errors (too many pegs, too large a grid) are one line.
    pub fn world(
        &self,
        base: &WorldSpec,
        start: &StartPose,
        goal: (f64, f64),
        seed: u64,
    ) -> Result<WorldSpec> {
        self.layout(base, start, goal, seed).map(|l| l.world)
    }

    /// [`TerrainDistribution::world`], with the shapes of its craters and ridges: geometry only.
    /// What the task makes of them (a way measured around them, an episode ending in them) is the
    /// env's to decide, from its reward and terrain settings.
    pub fn layout(
        &self,
        base: &WorldSpec,
        start: &StartPose,
        goal: (f64, f64),
        seed: u64,
    ) -> Result<Layout> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut world = base.clone();
        let mut craters = Vec::new();
        let mut ridges = Vec::new();
        if let Some(r) = &self.rough {
            // The lattice seeds first, so that the pegs' draws do not move them.
            let (bumps, hills) = (rng.gen::<u64>(), rng.gen::<u64>());
            let reach = start
                .x
                .abs()
                .max(start.y.abs())
                .max(goal.0.abs())
                .max(goal.1.abs());
            let half = reach + r.margin;
            let side = (2.0 * half / r.spacing).ceil() + 1.0;
            if side > MAX_HEIGHTFIELD_SIDE as f64 || side * side > MAX_HEIGHTFIELD_SAMPLES as f64 {
                return Err(invalid_at(
                    "terrain.rough",
                    format!("{side} x {side} samples for start and goal {reach:.1} m from the origin, more than {MAX_HEIGHTFIELD_SIDE} a side or {MAX_HEIGHTFIELD_SAMPLES} in all: raise spacing"),
                ));
            }
            let n = side as usize;
            let key = |name: &'static str| {
                move |e: crate::Error| invalid_at(format!("terrain.rough.{name}"), e.message())
            };
            let a = rough_heights(r.amplitude, r.wavelength, bumps, n, n, r.spacing)
                .map_err(key("wavelength"))?;
            let b = rough_heights(
                r.hills_amplitude,
                r.hills_wavelength,
                hills,
                n,
                n,
                r.spacing,
            )
            .map_err(key("hills_wavelength"))?;
            let mut heights: Vec<f32> = a.iter().zip(&b).map(|(x, y)| x + y).collect();
            // The craters draw from the hills' seed on a stream of its own: adding them moves no
            // hill and no peg.
            let mut crater_rng = ChaCha8Rng::seed_from_u64(hills);
            crater_rng.set_stream(1);
            let centres = r
                .craters
                .sink(&mut heights, n, r.spacing, start, goal, &mut crater_rng);
            craters.extend(centres.into_iter().map(|(x, y)| Disc {
                x,
                y,
                radius: r.craters.radius,
            }));
            // The ridges on a third stream: they move no hill, crater or peg.
            let mut ridge_rng = ChaCha8Rng::seed_from_u64(hills);
            ridge_rng.set_stream(2);
            ridges = r
                .ridges
                .raise(&mut heights, n, r.spacing, start, goal, &mut ridge_rng);
            world.ground = Ground::Heightfield(Heightfield {
                rows: n,
                columns: n,
                heights,
                scale: [r.spacing, r.spacing, 1.0],
            });
            if r.friction.is_some() {
                world.ground_friction = r.friction;
            }
        }
        if let Some(p) = &self.pegs {
            let (distance, (ux, uy)) = line_to_goal(start, goal);
            let end = distance - p.goal_clear;
            let along = if end >= p.start_clear {
                ((end - p.start_clear) / p.spacing).floor() + 1.0
            } else {
                0.0
            };
            let across = (p.width / p.spacing).floor() + 1.0;
            if along * across + world.obstacles.len() as f64 > MAX_OBSTACLES as f64 {
                return Err(invalid_at(
                    "terrain.pegs",
                    format!("{along} x {across} grid points, more than the {MAX_OBSTACLES} obstacles a world may have"),
                ));
            }
            for i in 0..along as usize {
                for j in 0..across as usize {
                    let keep = rng.gen::<f64>() < p.density;
                    let ja = rng.gen_range(-p.jitter..=p.jitter);
                    let jc = rng.gen_range(-p.jitter..=p.jitter);
                    if !keep {
                        continue;
                    }
                    let s = p.start_clear + i as f64 * p.spacing + ja;
                    let c = -0.5 * p.width + j as f64 * p.spacing + jc;
                    // `c` to the left of the direction (ux, uy): the direction turned by +90 deg.
                    let x = start.x + s * ux - c * uy;
                    let y = start.y + s * uy + c * ux;
                    crate::limits::check_position("terrain.pegs: a peg's position", x, y)?;
                    world.obstacles.push(Obstacle {
                        shape: ObstacleShape::Cylinder {
                            radius: p.radius,
                            height: p.height,
                        },
                        position: [x, y, 0.5 * p.height],
                        yaw: 0.0,
                        lateral_friction: p.lateral_friction,
                    });
                }
            }
        }
        Ok(Layout {
            world,
            craters,
            ridges,
        })
    }
}

/// An episode's terrain: its world, and the shapes drawn into its ground.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// The world (ground, obstacles).
    pub world: WorldSpec,
    /// The craters sunk into the rough ground (each to the top of its wall).
    pub craters: Vec<Disc>,
    /// The ridges' crest lines.
    pub ridges: Vec<Segment>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn start() -> StartPose {
        StartPose {
            x: 0.1,
            y: -0.2,
            z: 0.5,
            yaw: 0.0,
        }
    }

    #[test]
    fn a_seed_gives_one_layout_and_other_seeds_others() {
        let t = TerrainDistribution {
            pegs: Some(PegField::default()),
            rough: Some(RoughGround::default()),
        };
        let base = WorldSpec::default();
        let a = t.world(&base, &start(), (1.0, -5.0), 7).unwrap();
        assert_eq!(a, t.world(&base, &start(), (1.0, -5.0), 7).unwrap());
        assert_ne!(a, t.world(&base, &start(), (1.0, -5.0), 8).unwrap());
        assert!(!a.obstacles.is_empty());
        // Every peg lies in the band between start and goal.
        for o in &a.obstacles {
            let (x, y) = (o.position[0] - 0.1, o.position[1] + 0.2);
            let d = x.hypot(y);
            assert!(d > 0.9 && d < 5.1_f64.hypot(1.6), "{:?}", o.position);
        }
        let Ground::Heightfield(h) = &a.ground else {
            panic!("rough ground expected")
        };
        // The square reaches 3 m beyond the goal's 5 m.
        assert!(h.rows as f64 * h.scale[0] >= 16.0);
    }

    #[test]
    fn a_crater_lies_across_the_straight_line_clear_of_start_and_goal() {
        let craters = Craters {
            count: 1,
            ..Craters::default()
        };
        let t = TerrainDistribution {
            pegs: None,
            rough: Some(RoughGround {
                amplitude: 0.0,
                hills_amplitude: 0.0,
                craters,
                ..RoughGround::default()
            }),
        };
        let start = StartPose {
            x: 0.0,
            y: 0.0,
            z: 0.5,
            yaw: 0.0,
        };
        for seed in 0..20 {
            let w = t
                .world(&WorldSpec::default(), &start, (0.0, -12.0), seed)
                .unwrap();
            let Ground::Heightfield(h) = &w.ground else {
                panic!("rough ground expected")
            };
            let n = h.rows;
            let c = (n - 1) / 2;
            // The samples on the line x = 0, from the start (y = 0) to the goal (y = -12).
            let on_line: Vec<(f64, f32)> = (0..=c)
                .map(|k| (k as f64 * h.scale[1], h.heights[(c - k) * n + c]))
                .filter(|&(d, _)| d <= 12.0)
                .collect();
            let deepest = on_line.iter().map(|&(_, z)| z).fold(f32::MAX, f32::min);
            // The line crosses the crater's flat bottom: its centre is at most `offset` (1.5 m)
            // off the line and the bottom reaches `radius - wall` (2.25 m) from it.
            assert_eq!(deepest, -craters.depth as f32, "seed {seed}");
            for &(d, z) in &on_line {
                if d <= craters.start_clear || d >= 12.0 - craters.goal_clear {
                    assert_eq!(z, 0.0, "seed {seed}: {z} m at {d} m along");
                }
            }
        }
    }

    #[test]
    fn a_ridge_lies_across_the_straight_line_clear_of_start_and_goal() {
        let ridges = Ridges {
            count: 1,
            ..Ridges::default()
        };
        let t = TerrainDistribution {
            pegs: None,
            rough: Some(RoughGround {
                amplitude: 0.0,
                hills_amplitude: 0.0,
                ridges,
                ..RoughGround::default()
            }),
        };
        let start = StartPose {
            x: 0.0,
            y: 0.0,
            z: 0.5,
            yaw: 0.0,
        };
        let foot = 0.5 * ridges.crest + ridges.wall;
        for seed in 0..20 {
            let layout = t
                .layout(&WorldSpec::default(), &start, (0.0, -12.0), seed)
                .unwrap();
            let Ground::Heightfield(h) = &layout.world.ground else {
                panic!("rough ground expected")
            };
            let [s] = layout.ridges[..] else {
                panic!("one ridge expected")
            };
            // The crest runs across the line (along x), `length` long, its middle at most `offset`
            // off the line, between `start_clear` and 12 m - `goal_clear` along it (-y).
            assert!((s.a.1 - s.b.1).abs() < 1e-12, "seed {seed}: {s:?}");
            assert!(((s.a.0 - s.b.0).abs() - ridges.length).abs() < 1e-12);
            assert!((0.5 * (s.a.0 + s.b.0)).abs() <= ridges.offset);
            let along = -s.a.1;
            assert!(along >= ridges.start_clear && along <= 12.0 - ridges.goal_clear);
            let n = h.rows;
            let c = 0.5 * (n - 1) as f64;
            let mut top = 0;
            for j in 0..n {
                for i in 0..n {
                    let p = ((i as f64 - c) * h.scale[0], (j as f64 - c) * h.scale[1]);
                    let (d, z) = (s.distance_to(p), f64::from(h.heights[j * n + i]));
                    if d <= 0.5 * ridges.crest {
                        assert_eq!(z, ridges.height as f32 as f64, "seed {seed} at {p:?}");
                        top += 1;
                    } else if d >= foot {
                        assert_eq!(z, 0.0, "seed {seed} at {p:?}");
                    } else {
                        assert!(z > 0.0 && z < ridges.height, "seed {seed} at {p:?}: {z}");
                    }
                }
            }
            // The crest's samples: 6.5 m x 0.5 m at 0.125 m spacing, about 53 x 4 of them.
            assert!(
                (150..=300).contains(&top),
                "seed {seed}: {top} samples on the crest"
            );
        }
    }

    #[test]
    fn bad_values_are_one_line_naming_the_field() {
        let mut t = TerrainDistribution {
            pegs: Some(PegField {
                density: 1.5,
                ..PegField::default()
            }),
            rough: None,
        };
        let e = t.validate().unwrap_err().to_string();
        assert!(e.contains("terrain.pegs.density"), "{e}");
        assert!(!e.contains('\n'));
        t.pegs = Some(PegField {
            spacing: 0.001,
            width: 100.0,
            ..PegField::default()
        });
        let e = t
            .world(&WorldSpec::default(), &start(), (0.0, -50.0), 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("terrain.pegs") && e.contains("obstacles"), "{e}");
        let craters = [
            Craters {
                count: MAX_CRATERS + 1,
                ..Craters::default()
            },
            Craters {
                wall: 4.0,
                ..Craters::default()
            },
            Craters {
                depth: f64::NAN,
                ..Craters::default()
            },
            Craters {
                clearance: -1.0,
                ..Craters::default()
            },
        ]
        .map(|craters| RoughGround {
            craters,
            ..RoughGround::default()
        });
        let ridges = [
            Ridges {
                count: MAX_RIDGES + 1,
                ..Ridges::default()
            },
            Ridges {
                height: f64::INFINITY,
                ..Ridges::default()
            },
            Ridges {
                wall: -0.5,
                ..Ridges::default()
            },
        ]
        .map(|ridges| RoughGround {
            ridges,
            ..RoughGround::default()
        });
        let bad = craters.into_iter().map(|r| (r, "craters"));
        for (rough, key) in bad.chain(ridges.into_iter().map(|r| (r, "ridges"))) {
            let t = TerrainDistribution {
                pegs: None,
                rough: Some(rough),
            };
            let e = t.validate().unwrap_err().to_string();
            assert!(e.contains(&format!("terrain.rough.{key}.")), "{e}");
            assert!(!e.contains('\n'));
        }
    }
}
