//! Route geometry on the plane: [`Segment`], [`Disc`] and [`Capsule`], the [`Footprint`]s a task
//! refers to, and the length of the shortest way from a point to the goal around them. It reads
//! no terrain or reward setting: the terrain draws the shapes (env/terrain.rs), the task decides which of them
//! the progress term measures its way around and which end the episode (env/course.rs).

/// A segment on the plane from `a` to `b`, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// One end (x, y).
    pub a: (f64, f64),
    /// The other end (x, y).
    pub b: (f64, f64),
}

impl Segment {
    /// The point of the segment nearest to `p`.
    pub fn nearest(&self, p: (f64, f64)) -> (f64, f64) {
        let (dx, dy) = (self.b.0 - self.a.0, self.b.1 - self.a.1);
        let len2 = dx * dx + dy * dy;
        let t = if len2 > 0.0 {
            (((p.0 - self.a.0) * dx + (p.1 - self.a.1) * dy) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (self.a.0 + t * dx, self.a.1 + t * dy)
    }

    /// The distance from `p` to the nearest point of the segment.
    pub fn distance_to(&self, p: (f64, f64)) -> f64 {
        let s = self.nearest(p);
        (p.0 - s.0).hypot(p.1 - s.1)
    }
}

/// A disc on the plane: centre (x, y) and radius, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Centre x.
    pub x: f64,
    /// Centre y.
    pub y: f64,
    /// Radius.
    pub radius: f64,
}

impl Disc {
    /// (x, y) lies inside.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        (x - self.x).hypot(y - self.y) < self.radius
    }

    /// The length of the shortest way from `p` to `g` that does not cross the disc's inside: the
    /// straight line where that misses the disc, else the tangent from `p`, the arc and the tangent
    /// to `g`. A point inside first leaves the disc radially, to the rim.
    pub fn route_distance(&self, p: (f64, f64), g: (f64, f64)) -> f64 {
        let r = self.radius;
        let (p, dp) = self.onto_rim(p);
        let (g, dg) = self.onto_rim(g);
        let out = (r - dp).max(0.0) + (r - dg).max(0.0);
        let straight = (g.0 - p.0).hypot(g.1 - p.1);
        let (dp, dg) = (dp.max(r), dg.max(r));
        if r <= 0.0 {
            return straight;
        }
        // The line is blocked when p and g lie further apart, seen from the centre, than the
        // angles between each and its tangent point (acos(r / d)); the difference is the arc.
        let between = ((p.0 * g.0 + p.1 * g.1) / (dp * dg))
            .clamp(-1.0, 1.0)
            .acos();
        let arc = between - (r / dp).acos() - (r / dg).acos();
        if arc <= 0.0 {
            return out + straight;
        }
        out + (dp * dp - r * r).sqrt() + r * arc + (dg * dg - r * r).sqrt()
    }

    /// `q` relative to the centre, moved radially out to the rim when inside, and its distance
    /// from the centre before moving.
    fn onto_rim(&self, q: (f64, f64)) -> ((f64, f64), f64) {
        let (x, y) = (q.0 - self.x, q.1 - self.y);
        let d = x.hypot(y);
        if d < self.radius && d > 0.0 {
            ((x * self.radius / d, y * self.radius / d), d)
        } else {
            ((x, y), d)
        }
    }
}

/// The points within `radius` of a segment: a ridge's footprint, widened by its clearance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// The middle line.
    pub segment: Segment,
    /// Radius.
    pub radius: f64,
}

/// Corners of the polygon around each end of a [`Capsule`] that [`Capsule::route_distance`] goes
/// around: the way is at most tan(pi / n) / (pi / n) - 1 = 0.08 % longer than around the round ends.
const CAPSULE_CORNERS: usize = 64;

/// The directions of the corners from each end's centre, (cos, sin) of (k + 1/2) 2 pi / n: the same
/// for every capsule, so computed once rather than at every env step.
fn capsule_corner_directions() -> &'static [(f64, f64); CAPSULE_CORNERS] {
    static DIRECTIONS: std::sync::OnceLock<[(f64, f64); CAPSULE_CORNERS]> =
        std::sync::OnceLock::new();
    DIRECTIONS.get_or_init(|| {
        let step = std::f64::consts::TAU / CAPSULE_CORNERS as f64;
        std::array::from_fn(|k| {
            let t = (k as f64 + 0.5) * step;
            (t.cos(), t.sin())
        })
    })
}

impl Capsule {
    /// (x, y) lies inside.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        self.segment.distance_to((x, y)) < self.radius
    }

    /// The length of the shortest way from `p` to `g` that does not cross the capsule's inside
    /// (rounded to a polygon whose sides touch its round ends): the straight line where that is
    /// clear, else the shorter of the two ways around the convex hull of the capsule, `p` and `g`.
    /// A point inside first leaves the capsule straight away from its middle line.
    pub fn route_distance(&self, p: (f64, f64), g: (f64, f64)) -> f64 {
        if self.radius <= 0.0 {
            return (g.0 - p.0).hypot(g.1 - p.1);
        }
        let n = CAPSULE_CORNERS;
        let step = std::f64::consts::TAU / n as f64;
        let corner = self.radius / (0.5 * step).cos();
        // Points leave to just beyond the corners' radius: outside the polygon, never on a corner.
        let (p, out_p) = self.leave(p, corner * (1.0 + 1e-9));
        let (g, out_g) = self.leave(g, corner * (1.0 + 1e-9));
        let directions = capsule_corner_directions();
        let mut points: Vec<(f64, f64)> = [self.segment.a, self.segment.b]
            .iter()
            .flat_map(|&(cx, cy)| {
                directions
                    .iter()
                    .map(move |&(c, s)| (cx + corner * c, cy + corner * s))
            })
            .collect();
        points.push(p);
        points.push(g);
        let hull = convex_hull(&points);
        let at = |i: usize| hull.iter().position(|&h| h == i);
        let straight = (g.0 - p.0).hypot(g.1 - p.1);
        let around = match (at(2 * n), at(2 * n + 1)) {
            // Both on the hull: the segment between them crosses the polygon unless they are
            // neighbours, where one of the two ways is that segment.
            (Some(i), Some(j)) => {
                let edge = |k: usize| {
                    let (a, b) = (points[hull[k]], points[hull[(k + 1) % hull.len()]]);
                    (b.0 - a.0).hypot(b.1 - a.1)
                };
                let perimeter: f64 = (0..hull.len()).map(edge).sum();
                let one: f64 = (0..(j + hull.len() - i) % hull.len())
                    .map(|k| edge((i + k) % hull.len()))
                    .sum();
                one.min(perimeter - one).max(straight)
            }
            // One lies in the hull of the polygon and the other: the segment between them is clear.
            _ => straight,
        };
        out_p + out_g + around
    }

    /// `q` moved straight away from the middle line to `radius` when nearer, and how far it moved.
    fn leave(&self, q: (f64, f64), radius: f64) -> ((f64, f64), f64) {
        let d = self.segment.distance_to(q);
        if d >= radius {
            return (q, 0.0);
        }
        let s = self.segment.nearest(q);
        let (mut ux, mut uy) = (q.0 - s.0, q.1 - s.1);
        if d > 0.0 {
            (ux, uy) = (ux / d, uy / d);
        } else {
            // On the middle line: leave across it (to its left).
            let (dx, dy) = (
                self.segment.b.0 - self.segment.a.0,
                self.segment.b.1 - self.segment.a.1,
            );
            let len = dx.hypot(dy);
            (ux, uy) = if len > 0.0 {
                (-dy / len, dx / len)
            } else {
                (1.0, 0.0)
            };
        }
        ((s.0 + radius * ux, s.1 + radius * uy), radius - d)
    }
}

/// The indices of `points`' convex hull, counterclockwise, without points on its sides (Andrew's
/// monotone chain).
fn convex_hull(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        let (pa, pb) = (points[a], points[b]);
        pa.0.total_cmp(&pb.0).then(pa.1.total_cmp(&pb.1))
    });
    let cross = |o: usize, a: usize, b: usize| {
        let (o, a, b) = (points[o], points[a], points[b]);
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    // The lower chain left to right, then the upper chain right to left; each drops its last
    // point, the next chain's first.
    let reversed: Vec<usize> = order.iter().rev().copied().collect();
    let mut hull: Vec<usize> = Vec::with_capacity(points.len() + 1);
    for sweep in [&order, &reversed] {
        let floor = hull.len();
        for &i in sweep {
            while hull.len() >= floor + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], i) <= 0.0
            {
                hull.pop();
            }
            hull.push(i);
        }
        hull.pop();
    }
    hull
}

/// The distance from `p` to `g` along the shortest way around the `discs`: exact for one disc (and
/// for discs whose detours do not meet), otherwise the longest single-disc way, a lower bound.
pub fn route_distance(p: (f64, f64), g: (f64, f64), discs: &[Disc]) -> f64 {
    discs
        .iter()
        .map(|d| d.route_distance(p, g))
        .fold((g.0 - p.0).hypot(g.1 - p.1), f64::max)
}

/// A region of the plane that the task refers to, whatever the terrain drew it from: the progress
/// term measures its way around some footprints, and an episode ends inside others.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Footprint {
    /// A disc.
    Disc(Disc),
    /// A capsule.
    Capsule(Capsule),
}

impl Footprint {
    /// (x, y) lies inside.
    pub fn contains(&self, x: f64, y: f64) -> bool {
        match self {
            Footprint::Disc(d) => d.contains(x, y),
            Footprint::Capsule(c) => c.contains(x, y),
        }
    }

    /// The length of the shortest way from `p` to `g` that does not cross the inside
    /// ([`Disc::route_distance`], [`Capsule::route_distance`]).
    pub fn route_distance(&self, p: (f64, f64), g: (f64, f64)) -> f64 {
        match self {
            Footprint::Disc(d) => d.route_distance(p, g),
            Footprint::Capsule(c) => c.route_distance(p, g),
        }
    }
}

/// The distance from `p` to `g` around the `footprints`: the longest of the straight line and each
/// footprint's own way around ([`Footprint::route_distance`], in order). Exact for one footprint
/// (and for footprints whose detours do not meet), otherwise a lower bound; [`route_distance`] for
/// footprints of any shape.
pub fn route_distance_around(p: (f64, f64), g: (f64, f64), footprints: &[Footprint]) -> f64 {
    footprints
        .iter()
        .map(|f| f.route_distance(p, g))
        .fold((g.0 - p.0).hypot(g.1 - p.1), f64::max)
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// The shortest way from `p` to `g` around the disc, by Dijkstra over a visibility graph: `p`,
    /// `g` and the `n` corners of a polygon whose sides touch the rim, joined where the segment
    /// between two of them keeps out of the disc. An independent, numerical reference for
    /// `route_distance` (longer by at most a factor tan(pi / n) / (pi / n) along the rim).
    fn dijkstra_around(d: &Disc, p: (f64, f64), g: (f64, f64), n: usize) -> f64 {
        let r = d.radius / (std::f64::consts::PI / n as f64).cos() * (1.0 + 1e-12);
        let corners = (0..n).map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            (d.x + r * a.cos(), d.y + r * a.sin())
        });
        let centre = Segment {
            a: (d.x, d.y),
            b: (d.x, d.y),
        };
        dijkstra(p, g, corners.collect(), |a, b| {
            segments_apart(Segment { a, b }, centre) >= d.radius * (1.0 - 1e-12)
        })
    }

    /// The same for a capsule: the corners of a polygon whose sides touch each round end.
    fn dijkstra_around_capsule(c: &Capsule, p: (f64, f64), g: (f64, f64), n: usize) -> f64 {
        let r = c.radius / (std::f64::consts::PI / n as f64).cos() * (1.0 + 1e-12);
        let corners = [c.segment.a, c.segment.b].into_iter().flat_map(|(x, y)| {
            (0..n).map(move |k| {
                let a = std::f64::consts::TAU * k as f64 / n as f64;
                (x + r * a.cos(), y + r * a.sin())
            })
        });
        dijkstra(p, g, corners.collect(), |a, b| {
            segments_apart(Segment { a, b }, c.segment) >= c.radius * (1.0 - 1e-12)
        })
    }

    /// The least distance between two segments (0 where they cross).
    fn segments_apart(s: Segment, t: Segment) -> f64 {
        let side = |p: (f64, f64), q: (f64, f64), r: (f64, f64)| {
            (q.0 - p.0) * (r.1 - p.1) - (q.1 - p.1) * (r.0 - p.0)
        };
        let crosses = side(s.a, s.b, t.a) * side(s.a, s.b, t.b) < 0.0
            && side(t.a, t.b, s.a) * side(t.a, t.b, s.b) < 0.0;
        if crosses {
            return 0.0;
        }
        [
            s.distance_to(t.a),
            s.distance_to(t.b),
            t.distance_to(s.a),
            t.distance_to(s.b),
        ]
        .into_iter()
        .fold(f64::INFINITY, f64::min)
    }

    /// Dijkstra from `p` to `g` over `p`, `g` and `corners`, joined where `clear`.
    fn dijkstra(
        p: (f64, f64),
        g: (f64, f64),
        corners: Vec<(f64, f64)>,
        clear: impl Fn((f64, f64), (f64, f64)) -> bool,
    ) -> f64 {
        let mut pts = vec![p, g];
        pts.extend(corners);
        let mut best = vec![f64::INFINITY; pts.len()];
        let mut done = vec![false; pts.len()];
        best[0] = 0.0;
        for _ in 0..pts.len() {
            let Some(i) = (0..pts.len())
                .filter(|&i| !done[i])
                .min_by(|&a, &b| best[a].total_cmp(&best[b]))
            else {
                break;
            };
            done[i] = true;
            for j in 0..pts.len() {
                if !done[j] && clear(pts[i], pts[j]) {
                    let w = (pts[j].0 - pts[i].0).hypot(pts[j].1 - pts[i].1);
                    best[j] = best[j].min(best[i] + w);
                }
            }
        }
        best[1]
    }

    #[test]
    fn the_way_around_a_disc_is_the_shortest_one() {
        let d = Disc {
            x: 1.0,
            y: -6.0,
            radius: 2.0,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut blocked = 0;
        for _ in 0..40 {
            let mut outside = || loop {
                let q = (rng.gen_range(-6.0..8.0), rng.gen_range(-13.0..1.0));
                if !d.contains(q.0, q.1) {
                    return q;
                }
            };
            let (p, g) = (outside(), outside());
            let want = dijkstra_around(&d, p, g, 1440);
            let got = d.route_distance(p, g);
            assert!(
                got <= want + 1e-9 && want - got < 1e-4,
                "{p:?} {g:?}: {got} vs {want}"
            );
            blocked += usize::from(got > (g.0 - p.0).hypot(g.1 - p.1) + 1e-9);
            assert!((route_distance(p, g, &[d]) - got).abs() < 1e-12);
            assert_eq!(route_distance(p, g, &[]), (g.0 - p.0).hypot(g.1 - p.1));
        }
        assert!((10..35).contains(&blocked), "{blocked} of 40 went around");
        // Straight through the middle: two tangents and the arc between them.
        let (p, g) = ((1.0, -1.0), (1.0, -11.0));
        let want = 2.0 * 21.0f64.sqrt() + 2.0 * (std::f64::consts::PI - 2.0 * (0.4f64).acos());
        assert!((d.route_distance(p, g) - want).abs() < 1e-12);
        // From inside, radially out first: 0.5 m to the rim, then around.
        let inside = d.route_distance((1.0, -4.5), g);
        let want = 0.5 + 2.0 * (std::f64::consts::PI - (0.4f64).acos()) + 21.0f64.sqrt();
        assert!((inside - want).abs() < 1e-12, "{inside} {want}");
    }

    #[test]
    fn the_way_around_a_capsule_is_the_shortest_one() {
        let c = Capsule {
            segment: Segment {
                a: (-2.0, -5.0),
                b: (3.0, -7.0),
            },
            radius: 1.5,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut blocked = 0;
        for _ in 0..40 {
            let mut outside = || loop {
                let q = (rng.gen_range(-8.0..9.0), rng.gen_range(-14.0..2.0));
                if !c.contains(q.0, q.1) {
                    return q;
                }
            };
            let (p, g) = (outside(), outside());
            let want = dijkstra_around_capsule(&c, p, g, 720);
            let got = c.route_distance(p, g);
            // Around 64-cornered ends the way is at most 0.08 % of an arc (< 8 m here) longer.
            assert!(
                got >= want - 1e-6 && got - want < 6e-3,
                "{p:?} {g:?}: {got} vs {want}"
            );
            blocked += usize::from(got > (g.0 - p.0).hypot(g.1 - p.1) + 1e-9);
        }
        assert!((10..35).contains(&blocked), "{blocked} of 40 went around");
        // Straight through the middle of a ridge across the way: around either end, each a tangent,
        // the arc outside the end and a tangent.
        let ridge = Capsule {
            segment: Segment {
                a: (-3.0, -6.0),
                b: (3.0, -6.0),
            },
            radius: 1.5,
        };
        let (p, g) = ((0.0, -1.0), (0.0, -11.0));
        let d = 34.0f64.sqrt();
        let outer = std::f64::consts::TAU - 2.0 * (5.0f64 / 3.0).atan();
        let want = 2.0 * (d * d - 2.25).sqrt() + 1.5 * (outer - 2.0 * (1.5 / d).acos());
        let got = ridge.route_distance(p, g);
        assert!(got >= want - 1e-9 && got - want < 4e-3, "{got} {want}");
        // From inside, straight out first: 0.5 m from the middle line, out to the polygon's corners'
        // radius (1 m and a little), then around.
        let corner = 1.5 / (std::f64::consts::PI / CAPSULE_CORNERS as f64).cos();
        let inside = ridge.route_distance((0.0, -5.5), g);
        let want = (corner - 0.5) + dijkstra_around_capsule(&ridge, (0.0, -6.0 + corner), g, 720);
        assert!(
            inside >= want - 1e-6 && inside - want < 4e-3,
            "{inside} {want}"
        );
    }

    #[test]
    fn the_way_around_footprints_is_the_longest_single_way() {
        let d = Disc {
            x: 0.0,
            y: -6.0,
            radius: 2.0,
        };
        let c = Capsule {
            segment: Segment {
                a: (-3.0, -3.0),
                b: (3.0, -3.0),
            },
            radius: 0.5,
        };
        let both = [Footprint::Disc(d), Footprint::Capsule(c)];
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..40 {
            let p = (rng.gen_range(-6.0..6.0), rng.gen_range(-12.0..2.0));
            let g = (rng.gen_range(-6.0..6.0), rng.gen_range(-12.0..2.0));
            // Discs then capsules, as the env measured them before footprints: the same bits.
            let want = route_distance(p, g, &[d]).max(c.route_distance(p, g));
            assert_eq!(route_distance_around(p, g, &both).to_bits(), want.to_bits());
            assert_eq!(
                route_distance_around(p, g, &both[..1]).to_bits(),
                route_distance(p, g, &[d]).to_bits()
            );
            assert_eq!(both[0].contains(p.0, p.1), d.contains(p.0, p.1));
            assert_eq!(both[1].contains(p.0, p.1), c.contains(p.0, p.1));
        }
        assert_eq!(route_distance_around((0.0, 0.0), (3.0, 4.0), &[]), 5.0);
    }
}
