//! What media see of a link: its collision shapes (box, cylinder, capsule, sphere) posed in the link's
//! centre-of-mass frame, and those shapes' surfaces cut into small elements (a point, the outward
//! normal, an area), all in that frame. Resistive force theory sums a stress over the elements; water
//! reads the shapes (volume, axis, length, cross-section).
//!
//! Surfaces are cut by a target element size `e`: a box face `a x b` into `ceil(a/e) x ceil(b/e)`
//! equal rectangles; a cylinder's side into `ceil(2 pi r / e)` sectors by `ceil(L / e)` rings and each
//! end disc into `ceil(r / e)` annuli of `ceil(2 pi r_mid / e)` sectors; a sphere (and a capsule's ends)
//! into `ceil(pi r / e)` latitude bands of `ceil(2 pi r sin(phi) / e)` sectors, each band's area exact
//! (`2 pi r^2 (cos phi0 - cos phi1)`); a ring has at least 4 sectors. Every element's area is exact
//! for the surface it stands for, so
//! the total area is the shape's area at any size, and its point is the element's centre. Where a
//! link has several shapes, an element inside another of them is dropped (the faces where they meet,
//! or where one overlaps another, are inside the body), as [`hide_inner_elements`] drops those inside
//! another link.

use nalgebra::{UnitQuaternion, Vector3};

use crate::error::{invalid, Result};
use crate::limits::{MAX_MEDIUM_ELEMENTS, MEDIUM_ELEMENT};
use crate::media::INNER_TOLERANCE;
use crate::urdf::Geometry;
use crate::world::Pose;

/// A collision shape's kind and size. Cylinders and capsules lie along their frame's z axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Primitive {
    /// Half extents along x, y, z, metres.
    Box([f64; 3]),
    /// Radius and full length along z, metres.
    Cylinder {
        /// Radius, metres.
        radius: f64,
        /// Length along z, metres.
        length: f64,
    },
    /// Radius and the length of the cylinder part along z, metres (the ends are hemispheres).
    Capsule {
        /// Radius, metres.
        radius: f64,
        /// Length of the cylinder part, metres.
        length: f64,
    },
    /// Radius, metres.
    Sphere(f64),
}

impl Primitive {
    /// The shape as a URDF `<collision>` gives it.
    pub fn from_urdf(g: &Geometry) -> Self {
        match *g {
            Geometry::Box(size) => Primitive::Box([0.5 * size[0], 0.5 * size[1], 0.5 * size[2]]),
            Geometry::Sphere(r) => Primitive::Sphere(r),
            Geometry::Cylinder { radius, length } => Primitive::Cylinder { radius, length },
            Geometry::Capsule { radius, length } => Primitive::Capsule { radius, length },
        }
    }

    /// Volume, m^3.
    pub fn volume(&self) -> f64 {
        use std::f64::consts::PI;
        match *self {
            Primitive::Box([x, y, z]) => 8.0 * x * y * z,
            Primitive::Cylinder { radius, length } => PI * radius * radius * length,
            Primitive::Capsule { radius, length } => {
                PI * radius * radius * length + 4.0 / 3.0 * PI * radius.powi(3)
            }
            Primitive::Sphere(r) => 4.0 / 3.0 * PI * r.powi(3),
        }
    }

    /// Surface area, m^2.
    pub fn area(&self) -> f64 {
        use std::f64::consts::PI;
        match *self {
            Primitive::Box([x, y, z]) => 8.0 * (x * y + y * z + z * x),
            Primitive::Cylinder { radius, length } => {
                2.0 * PI * radius * length + 2.0 * PI * radius * radius
            }
            Primitive::Capsule { radius, length } => {
                2.0 * PI * radius * length + 4.0 * PI * radius * radius
            }
            Primitive::Sphere(r) => 4.0 * PI * r * r,
        }
    }

    /// Extent along the frame's z axis, metres (a cylinder's or capsule's length end to end).
    pub fn length_z(&self) -> f64 {
        match *self {
            Primitive::Box([_, _, z]) => 2.0 * z,
            Primitive::Cylinder { length, .. } => length,
            Primitive::Capsule { radius, length } => length + 2.0 * radius,
            Primitive::Sphere(r) => 2.0 * r,
        }
    }

    /// How many elements [`elements_of`] cuts the surface into at size `e`, in floating point (so that
    /// a size far too small is refused before anything is allocated).
    pub fn element_count(&self, e: f64) -> f64 {
        use std::f64::consts::PI;
        let c = |x: f64| (x / e).ceil().max(4.0);
        let sphere = |r: f64| {
            // Bands times the equator's sectors bounds the count from above.
            c(PI * r) * c(2.0 * PI * r)
        };
        let disc = |r: f64| c(r) * c(2.0 * PI * r);
        match *self {
            Primitive::Box([x, y, z]) => {
                2.0 * (c(2.0 * x) * c(2.0 * y) + c(2.0 * y) * c(2.0 * z) + c(2.0 * z) * c(2.0 * x))
            }
            Primitive::Cylinder { radius, length } => {
                c(2.0 * PI * radius) * c(length) + 2.0 * disc(radius)
            }
            Primitive::Capsule { radius, length } => {
                c(2.0 * PI * radius) * c(length) + sphere(radius)
            }
            Primitive::Sphere(r) => sphere(r),
        }
    }
}

/// A collision shape placed in its link's centre-of-mass frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shape {
    /// Kind and size.
    pub primitive: Primitive,
    /// Pose in the link's centre-of-mass frame.
    pub pose: Pose,
}

/// A small piece of a link's surface, in the link's centre-of-mass frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Element {
    /// Centre of the piece, metres.
    pub point: Vector3<f64>,
    /// Outward unit normal.
    pub normal: Vector3<f64>,
    /// Area, m^2.
    pub area: f64,
}

/// A link's shapes and surface elements, in its centre-of-mass frame.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkGeometry {
    /// Mass of the link, kg (what a medium's forces are weighed against).
    pub mass: f64,
    /// The collision shapes.
    pub shapes: Vec<Shape>,
    /// The surface elements of every shape (empty when no medium asks for them).
    pub elements: Vec<Element>,
    /// Water's coefficients for this link as its robot file gives them (checked), over the water's.
    pub water: Option<crate::media::water::CoefficientsFile>,
}

impl LinkGeometry {
    /// A link of these shapes, its surfaces cut at `element` metres (`None`: no elements), less the
    /// elements that lie inside another of its shapes (within [`INNER_TOLERANCE`]; of two identical
    /// shapes the first keeps its surface). Refuses a size that would cut the link into more than
    /// [`MAX_MEDIUM_ELEMENTS`] elements; `what` names the key in that message.
    pub fn new(mass: f64, shapes: Vec<Shape>, element: Option<f64>, what: &str) -> Result<Self> {
        let mut elements = Vec::new();
        if let Some(e) = element {
            let count: f64 = shapes.iter().map(|s| s.primitive.element_count(e)).sum();
            if count.is_nan() || count > MAX_MEDIUM_ELEMENTS as f64 {
                return Err(invalid(format!(
                    "{what}: {} m cuts a link into about {count:.0} surface elements, more than {MAX_MEDIUM_ELEMENTS}: raise it",
                    crate::limits::short(e)
                )));
            }
            let mut own = Vec::new();
            for (i, s) in shapes.iter().enumerate() {
                own.clear();
                elements_of(&s.primitive, e, &mut own);
                let (r, t) = (s.pose.orientation, s.pose.position);
                for el in &mut own {
                    el.point = r * el.point + t;
                    el.normal = r * el.normal;
                }
                // A link drawn as several shapes (slices of one cylinder, say) is one body: the faces
                // where its shapes meet would otherwise take the medium's stress as outer faces.
                let hides = |j: usize, o: &Shape, p: &Vector3<f64>| {
                    let distinct = j < i || o != s;
                    let local = o.pose.orientation.inverse() * (p - o.pose.position);
                    j != i && distinct && o.primitive.contains(&local, INNER_TOLERANCE)
                };
                elements.extend(own.iter().filter(|el| {
                    !shapes
                        .iter()
                        .enumerate()
                        .any(|(j, o)| hides(j, o, &el.point))
                }));
            }
        }
        Ok(LinkGeometry {
            mass,
            shapes,
            elements,
            water: None,
        })
    }

    /// Total volume of the shapes, m^3 (overlaps counted twice).
    pub fn volume(&self) -> f64 {
        self.shapes.iter().map(|s| s.primitive.volume()).sum()
    }
}

impl Primitive {
    /// Whether `p` (in the shape's own frame) lies inside the shape or within `tolerance` of it.
    pub fn contains(&self, p: &Vector3<f64>, tolerance: f64) -> bool {
        match *self {
            Primitive::Box(h) => (0..3).all(|k| p[k].abs() <= h[k] + tolerance),
            Primitive::Cylinder { radius, length } => {
                p.z.abs() <= 0.5 * length + tolerance && p.x.hypot(p.y) <= radius + tolerance
            }
            Primitive::Capsule { radius, length } => {
                let z = p.z.clamp(-0.5 * length, 0.5 * length);
                (p - Vector3::new(0.0, 0.0, z)).norm() <= radius + tolerance
            }
            Primitive::Sphere(r) => p.norm() <= r + tolerance,
        }
    }
}

/// Drops every element that lies inside another link's shape (within `tolerance`) with the body as it
/// stands: the faces where a chain's segments meet are inside the body (a suit covers them, a joint
/// hides them), and as surfaces they would take the grains' full stress head-on. `poses` are the links'
/// centre-of-mass poses (world frame), one per link.
pub fn hide_inner_elements(links: &mut [LinkGeometry], poses: &[Pose], tolerance: f64) {
    let placed: Vec<Vec<(Primitive, Pose)>> = links
        .iter()
        .zip(poses)
        .map(|(l, com)| {
            l.shapes
                .iter()
                .map(|s| {
                    (
                        s.primitive,
                        Pose {
                            position: com.position + com.orientation * s.pose.position,
                            orientation: com.orientation * s.pose.orientation,
                        },
                    )
                })
                .collect()
        })
        .collect();
    for (k, (link, com)) in links.iter_mut().zip(poses).enumerate() {
        link.elements.retain(|el| {
            let at = com.position + com.orientation * el.point;
            !placed.iter().enumerate().any(|(j, shapes)| {
                j != k
                    && shapes.iter().any(|(primitive, pose)| {
                        let local = pose.orientation.inverse() * (at - pose.position);
                        primitive.contains(&local, tolerance)
                    })
            })
        });
    }
}

/// Checks an element size: finite and within [`MEDIUM_ELEMENT`].
pub fn check_element_size(what: &str, e: f64) -> Result<()> {
    crate::limits::check_range(what, e, MEDIUM_ELEMENT.0, MEDIUM_ELEMENT.1)
}

fn push(out: &mut Vec<Element>, point: Vector3<f64>, normal: Vector3<f64>, area: f64) {
    out.push(Element {
        point,
        normal,
        area,
    });
}

/// Cuts the primitive's surface (in its own frame) into elements of about `e` metres.
pub fn elements_of(p: &Primitive, e: f64, out: &mut Vec<Element>) {
    use std::f64::consts::PI;
    let n = |x: f64| ((x / e).ceil() as usize).max(1);
    match *p {
        Primitive::Box(h) => {
            // Each face: the axis it faces (k), its sign, and the two axes it spans.
            for k in 0..3 {
                let (a, b) = ((k + 1) % 3, (k + 2) % 3);
                let (na, nb) = (n(2.0 * h[a]), n(2.0 * h[b]));
                let (da, db) = (2.0 * h[a] / na as f64, 2.0 * h[b] / nb as f64);
                for sign in [1.0, -1.0] {
                    let mut normal = Vector3::zeros();
                    normal[k] = sign;
                    for i in 0..na {
                        for j in 0..nb {
                            let mut point = Vector3::zeros();
                            point[k] = sign * h[k];
                            point[a] = -h[a] + (i as f64 + 0.5) * da;
                            point[b] = -h[b] + (j as f64 + 0.5) * db;
                            push(out, point, normal, da * db);
                        }
                    }
                }
            }
        }
        Primitive::Cylinder { radius, length } => {
            side(radius, -0.5 * length, 0.5 * length, e, out);
            for sign in [1.0, -1.0] {
                disc(radius, sign * 0.5 * length, sign, e, out);
            }
        }
        Primitive::Capsule { radius, length } => {
            side(radius, -0.5 * length, 0.5 * length, e, out);
            sphere(radius, 0.5 * length, 0.0, 0.5 * PI, e, out);
            sphere(radius, -0.5 * length, 0.5 * PI, PI, e, out);
        }
        Primitive::Sphere(r) => sphere(r, 0.0, 0.0, PI, e, out),
    }
}

/// Sectors around a circle of circumference `c`: at least 4, so that the normals of every ring cancel
/// (a closed surface takes no net force from a uniform pressure).
fn sectors(c: f64, e: f64) -> usize {
    ((c / e).ceil() as usize).max(4)
}

/// A cylinder's side between heights `z0` and `z1`.
fn side(r: f64, z0: f64, z1: f64, e: f64, out: &mut Vec<Element>) {
    use std::f64::consts::TAU;
    let n = |x: f64| ((x / e).ceil() as usize).max(1);
    let (nt, nz) = (sectors(TAU * r, e), n(z1 - z0));
    let (dt, dz) = (TAU / nt as f64, (z1 - z0) / nz as f64);
    for i in 0..nt {
        let t = (i as f64 + 0.5) * dt;
        let normal = Vector3::new(t.cos(), t.sin(), 0.0);
        for j in 0..nz {
            let z = z0 + (j as f64 + 0.5) * dz;
            push(
                out,
                r * normal + Vector3::new(0.0, 0.0, z),
                normal,
                r * dt * dz,
            );
        }
    }
}

/// A disc of radius `r` at height `z` facing `sign` z.
fn disc(r: f64, z: f64, sign: f64, e: f64, out: &mut Vec<Element>) {
    use std::f64::consts::{PI, TAU};
    let n = |x: f64| ((x / e).ceil() as usize).max(1);
    let nr = n(r);
    let dr = r / nr as f64;
    for i in 0..nr {
        let (r0, r1) = (i as f64 * dr, (i + 1) as f64 * dr);
        let rm = 0.5 * (r0 + r1);
        let nt = sectors(TAU * rm, e);
        let dt = TAU / nt as f64;
        let ring = PI * (r1 * r1 - r0 * r0);
        for j in 0..nt {
            let t = (j as f64 + 0.5) * dt;
            push(
                out,
                Vector3::new(rm * t.cos(), rm * t.sin(), z),
                Vector3::new(0.0, 0.0, sign),
                ring / nt as f64,
            );
        }
    }
}

/// The part of a sphere of radius `r` centred at height `zc` between polar angles `p0` and `p1`.
fn sphere(r: f64, zc: f64, p0: f64, p1: f64, e: f64, out: &mut Vec<Element>) {
    use std::f64::consts::TAU;
    let n = |x: f64| ((x / e).ceil() as usize).max(1);
    let nb = n(r * (p1 - p0));
    let dp = (p1 - p0) / nb as f64;
    for i in 0..nb {
        let (a, b) = (p0 + i as f64 * dp, p0 + (i + 1) as f64 * dp);
        let pm = 0.5 * (a + b);
        let nt = sectors(TAU * r * pm.sin(), e);
        let band = TAU * r * r * (a.cos() - b.cos());
        let dt = TAU / nt as f64;
        for j in 0..nt {
            let t = (j as f64 + 0.5) * dt;
            let normal = Vector3::new(pm.sin() * t.cos(), pm.sin() * t.sin(), pm.cos());
            push(
                out,
                r * normal + Vector3::new(0.0, 0.0, zc),
                normal,
                band / nt as f64,
            );
        }
    }
}

/// A pose at the origin with no rotation.
pub fn identity_pose() -> Pose {
    Pose {
        position: Vector3::zeros(),
        orientation: UnitQuaternion::identity(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn total(p: Primitive, e: f64) -> (f64, Vector3<f64>, usize) {
        let mut out = Vec::new();
        elements_of(&p, e, &mut out);
        let area = out.iter().map(|el| el.area).sum();
        let closed = out.iter().map(|el| el.area * el.normal).sum();
        (area, closed, out.len())
    }

    #[test]
    fn element_areas_sum_to_the_shape_area_and_the_surface_is_closed() {
        for p in [
            Primitive::Box([0.05, 0.02, 0.01]),
            Primitive::Cylinder {
                radius: 0.02,
                length: 0.1,
            },
            Primitive::Capsule {
                radius: 0.02,
                length: 0.1,
            },
            Primitive::Sphere(0.03),
        ] {
            for e in [0.005, 0.01, 0.1] {
                let (area, closed, count) = total(p, e);
                assert!(((area - p.area()) / p.area()).abs() < 1e-12, "{p:?} {e}");
                // A closed surface: the area-weighted normals cancel (to the cut's symmetry).
                assert!(closed.norm() < 1e-12, "{p:?} {e} {closed}");
                assert!(count as f64 <= p.element_count(e), "{p:?} {e}");
            }
        }
    }

    #[test]
    fn a_link_of_several_shapes_shows_only_their_outer_surface() {
        // A cylinder cut into seven coaxial slices end to end (robots/sandfish-robot.urdf): the faces
        // where the slices meet are inside the link, so what is left is the whole cylinder's surface,
        // 2 pi r L + 2 pi r^2, and closed; a shape given twice counts once.
        let (radius, length, n) = (0.0175, 0.065, 7);
        let slice = |k: usize| Shape {
            primitive: Primitive::Cylinder {
                radius,
                length: length / n as f64,
            },
            pose: Pose {
                position: Vector3::new(
                    0.0,
                    0.0,
                    -0.5 * length + (k as f64 + 0.5) * length / n as f64,
                ),
                orientation: UnitQuaternion::identity(),
            },
        };
        let whole = 2.0 * std::f64::consts::PI * radius * (length + radius);
        for shapes in [
            (0..n).map(slice).collect::<Vec<_>>(),
            vec![slice(3), slice(3)],
        ] {
            let expected = if shapes.len() == 2 {
                shapes[0].primitive.area()
            } else {
                whole
            };
            let link = LinkGeometry::new(1.0, shapes, Some(0.01), "element").unwrap();
            let area: f64 = link.elements.iter().map(|el| el.area).sum();
            let closed: Vector3<f64> = link.elements.iter().map(|el| el.area * el.normal).sum();
            assert!(
                (area - expected).abs() < 1e-12 * expected,
                "{area} {expected}"
            );
            assert!(closed.norm() < 1e-12, "{closed}");
        }
    }

    #[test]
    fn a_size_that_cuts_too_many_elements_is_refused() {
        let shapes = vec![Shape {
            primitive: Primitive::Box([1.0, 1.0, 1.0]),
            pose: identity_pose(),
        }];
        let err = LinkGeometry::new(1.0, shapes, Some(1e-4), "media[0]: element")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("media[0]: element") && err.contains("more than"),
            "{err}"
        );
    }
}
