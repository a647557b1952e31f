//! Water (issue 60): Kelasidi et al.'s hydrodynamic model of a swimming snake robot, link by link,
//! extended from the plane to 3D, with buoyancy from each link's submerged volume.
//!
//! The model (E. Kelasidi, K. Y. Pettersen, J. T. Gravdahl, P. Liljebäck, "Modeling of underwater snake
//! robots", ICRA 2014; restated in Kelasidi et al., "Innovation in underwater robots: biologically
//! inspired swimming snake robots", IEEE Robotics & Automation Magazine, March 2016, eqs. 5-9): each
//! link is a slender cylinder of length `2 l` and cross-section semi-axes `a`, `b`. Relative to the
//! current, with `v_t` the velocity along the link and `v_n` across it,
//!
//! - drag along the link `f_t = -c_t v_t - c_t sgn(v_t) v_t^2`, across it `f_n = -c_n v_n - c_n
//!   sgn(v_n) v_n^2` (linear and nonlinear drag, eqs. 7-8: the same coefficient for both terms, the
//!   linear one taken per 1 m/s),
//! - added mass across the link `f_A = -mu_n dv_n/dt` (eq. 6; the current is constant here, so the
//!   relative acceleration is the link's own),
//! - fluid moments `tau = -lambda_1 dw/dt - lambda_2 w - lambda_3 w |w|` about the axis normal to the
//!   link,
//!
//! with the Morison-type relations for an elliptic cylinder (ICRA 2014, after Fossen and Morison):
//! `c_t = 1/2 rho pi C_f (a + b) 2 l`, `c_n = 1/2 rho C_D 2a 2l`, `mu_n = rho pi C_A a^2 2l`,
//! `lambda_1 = 1/12 rho pi C_M (a^2 - b^2)^2 l^3`, `lambda_2 = 1/6 rho pi C_f (a + b) l^3`,
//! `lambda_3 = 1/8 rho pi C_f (a + b) l^4`.
//!
//! **From the plane to 3D.** Kelasidi's links swim in a plane, so "across" is one direction. Here the
//! cross-section has two axes (`e2`, `e3`) and each gets the planar law on its own: the relative velocity
//! across the link is resolved on both, with `c_n`, `mu_n` of that axis (the projected width is the
//! extent along the *other* cross axis: a flat link moving broadside meets more water), and the fluid
//! moment about each cross axis uses that axis's `lambda`s. Nonlinear drag is taken component-wise, as
//! the paper writes it. Spin about the link's own axis, which the planar model cannot have, gets the
//! skin-friction torque of a rotating cylinder, `tau = -rho pi C_f r^4 (2l) w |w|` (shear `1/2 rho C_f
//! (w r)^2` on the wetted side). This is strip theory for a slender body as in Morison's equation:
//! no wake, no vortex shedding, no free-surface waves, no interaction between links.
//!
//! **Buoyancy** is `rho g V` against the world's gravity (`World::gravity`, read at every step: one
//! value for the bodies' weight and the water's lift) at the centre of the submerged volume, computed from the link's
//! collision primitives: a sphere exactly (a spherical cap), a box and a cylinder as slices whose
//! submerged fraction is linear in their depth (exact for a box with vertical or horizontal faces,
//! within a few per cent for a tilted or horizontal cylinder), a capsule as its cylinder and two
//! half spheres. A link partly out of the water gets drag and added mass scaled by its submerged
//! fraction.
//!
//! **Added mass, explicitly.** Bullet integrates applied forces explicitly, so `-mu_n a` from the
//! previous step's acceleration feeds back with gain `mu_n / m` and oscillates without bound when the
//! added mass reaches the link's mass (a neutrally buoyant cylinder with `C_A = 1` has `mu_n = m`).
//! The acceleration is therefore relaxed: `a_f <- a_f + k (a - a_f)` with `k = 1 / (1 + mu_n / m)`,
//! which makes the loop's gain `1 - k (1 + mu_n / m) = 0`: under a steady force the link reaches
//! `F / (m + mu_n)`, the implicit answer, one step late (see docs/media.md for the study that shows
//! the steady swimming speed does not depend on it).

use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{invalid, Result};
use crate::media::{Region, RegionFile};

/// Fresh water at 20 degrees C, kg/m^3.
pub const WATER_DENSITY: f64 = 998.2;

/// Kelasidi et al.'s coefficients (ICRA 2014 and RAM 2016: C_f 0.03, C_D 2, C_A 1, C_M 1).
pub const DEFAULT_COEFFICIENTS: Coefficients = Coefficients {
    skin_friction: 0.03,
    drag: 2.0,
    added_mass: 1.0,
    added_inertia: 1.0,
    linear: 1.0,
};

/// The hydrodynamic coefficients of a link (dimensionless, but `linear`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Coefficients {
    /// `C_f`: skin friction (drag along the link, fluid moments).
    pub skin_friction: f64,
    /// `C_D`: drag across the link.
    pub drag: f64,
    /// `C_A`: added mass across the link.
    pub added_mass: f64,
    /// `C_M`: added moment of inertia (zero effect on a circular cross-section).
    pub added_inertia: f64,
    /// Weight of the linear drag term, s/m: Kelasidi's model uses the quadratic term's coefficient
    /// per 1 m/s (1); 0 leaves the quadratic law alone.
    pub linear: f64,
}

impl Default for Coefficients {
    fn default() -> Self {
        DEFAULT_COEFFICIENTS
    }
}

/// Coefficients as a robot file or a world file gives them: any subset, over the ones below them.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CoefficientsFile {
    /// See [`Coefficients::skin_friction`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skin_friction: Option<f64>,
    /// See [`Coefficients::drag`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub drag: Option<f64>,
    /// See [`Coefficients::added_mass`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub added_mass: Option<f64>,
    /// See [`Coefficients::added_inertia`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub added_inertia: Option<f64>,
    /// See [`Coefficients::linear`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linear: Option<f64>,
}

impl CoefficientsFile {
    /// These values over `base`, already checked ([`CoefficientsFile::over`] checked them when the
    /// file was read).
    pub fn apply(&self, base: Coefficients) -> Coefficients {
        Coefficients {
            skin_friction: self.skin_friction.unwrap_or(base.skin_friction),
            drag: self.drag.unwrap_or(base.drag),
            added_mass: self.added_mass.unwrap_or(base.added_mass),
            added_inertia: self.added_inertia.unwrap_or(base.added_inertia),
            linear: self.linear.unwrap_or(base.linear),
        }
    }

    /// `self`'s keys over `base`'s (a link's over its robot's).
    pub fn merged_over(&self, base: &CoefficientsFile) -> CoefficientsFile {
        CoefficientsFile {
            skin_friction: self.skin_friction.or(base.skin_friction),
            drag: self.drag.or(base.drag),
            added_mass: self.added_mass.or(base.added_mass),
            added_inertia: self.added_inertia.or(base.added_inertia),
            linear: self.linear.or(base.linear),
        }
    }

    /// These values over `base`, each checked: finite, >= 0 and at most
    /// [`crate::limits::MAX_HYDRO_COEFFICIENT`]; `what` names the key in messages.
    pub fn over(&self, base: Coefficients, what: &str) -> Result<Coefficients> {
        let mut c = base;
        for (name, value, slot) in [
            ("skin_friction", self.skin_friction, &mut c.skin_friction),
            ("drag", self.drag, &mut c.drag),
            ("added_mass", self.added_mass, &mut c.added_mass),
            ("added_inertia", self.added_inertia, &mut c.added_inertia),
            ("linear", self.linear, &mut c.linear),
        ] {
            if let Some(v) = value {
                let high = crate::limits::MAX_HYDRO_COEFFICIENT;
                if !(v.is_finite() && (0.0..=high).contains(&v)) {
                    return Err(invalid(format!(
                        "{what}: {name}: must be a finite number in [0, {high}], got {v}"
                    )));
                }
                *slot = v;
            }
        }
        Ok(c)
    }
}

/// A `{medium: water, ...}` entry as written.
///
/// ```yaml
/// media:
///   - {medium: water, area: [-5, -5, 5, 5], surface: 0.5, depth: 1.0,
///      density: 998.2, current: [0.1, 0, 0], coefficients: {drag: 2.0, added_mass: 1.0}}
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaterFile {
    /// `[x_min, y_min, x_max, y_max]` of the region it fills, metres.
    pub area: [f64; 4],
    /// Height of its surface, metres (default 0: the ground plane's height).
    #[serde(default)]
    pub surface: f64,
    /// How far below the surface it reaches, metres.
    pub depth: f64,
    /// Density, kg/m^3 (default [`WATER_DENSITY`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f64>,
    /// The current: a constant velocity (m/s, world frame) over the whole region; a current that
    /// differs by place is one water entry per region.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub current: Option<[f64; 3]>,
    /// Coefficients over [`DEFAULT_COEFFICIENTS`]; a robot file's `water` keys override them per link.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coefficients: Option<CoefficientsFile>,
}

/// A checked water medium.
#[derive(Debug, Clone, PartialEq)]
pub struct Water {
    /// Where it is.
    pub region: Region,
    /// Density, kg/m^3.
    pub density: f64,
    /// Current velocity, m/s, world frame.
    pub current: Vector3<f64>,
    /// The medium's coefficients (links may override them).
    pub coefficients: Coefficients,
    /// Scale of the added mass's relaxation gain (1: the gain that makes the loop dead-beat; stable
    /// below 2). Not a file key: it is there for the study that shows steady swimming does not
    /// depend on it (tests/water.rs, docs/media.md).
    pub relaxation: f64,
}

impl WaterFile {
    /// Checks every value.
    pub fn resolve(&self, what: &str) -> Result<Water> {
        let region = RegionFile {
            area: self.area,
            surface: self.surface,
            depth: self.depth,
        }
        .resolve(what)?;
        let density = self.density.unwrap_or(WATER_DENSITY);
        let high = crate::limits::MAX_FLUID_DENSITY;
        if !(density.is_finite() && density > 0.0 && density <= high) {
            return Err(invalid(format!(
                "{what}: density: must be a finite number in (0, {high}] kg/m^3, got {density}"
            )));
        }
        let current = self.current.unwrap_or([0.0; 3]);
        let high = crate::limits::MAX_CURRENT;
        if current.iter().any(|v| !v.is_finite() || v.abs() > high) {
            return Err(invalid(format!(
                "{what}: current: must be finite velocities within +-{high} m/s, got {current:?}"
            )));
        }
        let coefficients = self
            .coefficients
            .unwrap_or_default()
            .over(DEFAULT_COEFFICIENTS, &format!("{what}: coefficients"))?;
        Ok(Water {
            region,
            density,
            current: Vector3::from(current),
            coefficients,
            relaxation: 1.0,
        })
    }
}

/// A solid primitive of a link, in the link's centre-of-mass frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Solid {
    /// A box of these half extents along its own x, y, z.
    Box {
        /// Half extents, metres.
        half: [f64; 3],
    },
    /// A cylinder along its own z.
    Cylinder {
        /// Radius, metres.
        radius: f64,
        /// Length, metres.
        length: f64,
    },
    /// A capsule along its own z: a cylinder of `length` with half spheres on its ends.
    Capsule {
        /// Radius, metres.
        radius: f64,
        /// Length of the cylinder between the half spheres, metres.
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius, metres.
        radius: f64,
    },
}

impl Solid {
    /// Volume, m^3.
    pub fn volume(&self) -> f64 {
        use std::f64::consts::PI;
        match *self {
            Solid::Box { half } => 8.0 * half[0] * half[1] * half[2],
            Solid::Cylinder { radius, length } => PI * radius * radius * length,
            Solid::Capsule { radius, length } => {
                PI * radius * radius * length + 4.0 / 3.0 * PI * radius.powi(3)
            }
            Solid::Sphere { radius } => 4.0 / 3.0 * PI * radius.powi(3),
        }
    }

    /// Half extents of the box that bounds it, in its own frame.
    fn half_extents(&self) -> [f64; 3] {
        match *self {
            Solid::Box { half } => half,
            Solid::Cylinder { radius, length } => [radius, radius, length / 2.0],
            Solid::Capsule { radius, length } => [radius, radius, length / 2.0 + radius],
            Solid::Sphere { radius } => [radius; 3],
        }
    }
}

/// Refuses two water entries whose regions overlap (a link in both would float twice as high): a
/// current that differs by place is written as regions side by side. Names both entries.
pub fn check_overlap(media: &[crate::media::Medium]) -> Result<()> {
    let waters: Vec<(usize, &Region)> = media
        .iter()
        .enumerate()
        .filter_map(|(k, m)| match m {
            crate::media::Medium::Water(w) => Some((k, &w.region)),
            _ => None,
        })
        .collect();
    for (i, &(a, ra)) in waters.iter().enumerate() {
        for &(b, rb) in &waters[i + 1..] {
            let apart = (0..3).any(|d| ra.max[d] <= rb.min[d] || rb.max[d] <= ra.min[d]);
            if !apart {
                return Err(invalid(format!(
                    "media[{a}] and media[{b}]: two water regions overlap; give each place one water \
                     entry (regions side by side, each with its current)"
                )));
            }
        }
    }
    Ok(())
}

/// Refuses links without volume (no box, cylinder, capsule or sphere collision shape) in a world with
/// water: water acts on a link through its volume, and one without would sink through it unseen.
/// `shapes` are each link's collision shapes (the base first); `name(k)` names link `k` in the message
/// (a robot's: its file and the link's name).
pub fn check_volumes(
    shapes: &[Vec<crate::media::geometry::Primitive>],
    name: impl Fn(usize) -> String,
) -> Result<()> {
    for (k, link) in shapes.iter().enumerate() {
        let volume: f64 = link.iter().map(|p| p.volume()).sum();
        if volume.is_nan() || volume <= 0.0 {
            return Err(invalid(format!(
                "{}: has no volume (no box, cylinder, capsule or sphere collision shape), so the \
                 world's water cannot act on it",
                name(k)
            )));
        }
    }
    Ok(())
}

/// A media shape as water's primitive.
fn placed(s: &crate::media::geometry::Shape) -> PlacedSolid {
    use crate::media::geometry::Primitive;
    let solid = match s.primitive {
        Primitive::Box(half) => Solid::Box { half },
        Primitive::Cylinder { radius, length } => Solid::Cylinder { radius, length },
        Primitive::Capsule { radius, length } => Solid::Capsule { radius, length },
        Primitive::Sphere(radius) => Solid::Sphere { radius },
    };
    PlacedSolid {
        solid,
        pose: Isometry3::from_parts(s.pose.position.into(), s.pose.orientation),
    }
}

/// A primitive placed in the link's centre-of-mass frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlacedSolid {
    /// The shape.
    pub solid: Solid,
    /// Its pose in the link's centre-of-mass frame.
    pub pose: Isometry3<f64>,
}

/// What the law needs of a link, computed once from its primitives and its mass: its axis, length,
/// cross-section, and the Kelasidi coefficients that follow from them and the water's.
#[derive(Debug, Clone, PartialEq)]
pub struct Hydro {
    /// Total volume, m^3.
    pub volume: f64,
    /// The link's mass, kg (for the added mass's relaxation).
    pub mass: f64,
    /// Link frame (COM frame) rotation whose x is the link's axis and y, z its cross axes.
    pub frame: UnitQuaternion<f64>,
    /// Length `2 l` along the axis, metres.
    pub length: f64,
    /// Half widths of the cross-section along the frame's y and z, metres.
    pub half_width: [f64; 2],
    /// `c_t` (along), N s^2/m^2.
    pub c_t: f64,
    /// `c_n` for motion along the frame's y and z.
    pub c_n: [f64; 2],
    /// `mu_n` for acceleration along the frame's y and z, kg.
    pub mu_n: [f64; 2],
    /// `lambda_1, lambda_2, lambda_3` about the frame's y and z.
    pub lambda: [[f64; 3]; 2],
    /// Spin damping about the axis: `rho pi C_f r^4 2l`.
    pub spin: f64,
    /// Linear drag weight (s/m).
    pub linear: f64,
}

impl Hydro {
    /// The link's hydrodynamic description: the axis is the side of its largest primitive (by volume)
    /// along which all its primitives reach furthest (a single primitive's longest side), the length
    /// is the extent of all primitives along it, the cross-section that of the largest primitive
    /// across it. `what` names the link in messages: a link with no volume cannot be in water.
    pub fn new<I: Iterator<Item = PlacedSolid> + Clone>(
        solids: I,
        mass: f64,
        density: f64,
        c: Coefficients,
        what: &str,
    ) -> Result<Hydro> {
        use std::f64::consts::PI;
        let volume: f64 = solids.clone().map(|s| s.solid.volume()).sum();
        let largest = solids
            .clone()
            .filter(|s| s.solid.volume() > 0.0)
            .max_by(|a, b| a.solid.volume().total_cmp(&b.solid.volume()));
        let Some(largest) = largest.filter(|_| volume.is_finite() && volume > 0.0) else {
            return Err(invalid(format!(
                "{what}: has no volume (no box, cylinder, capsule or sphere collision shape), so water \
                 cannot act on it"
            )));
        };
        let half = largest.solid.half_extents();
        // The primitive's sides, longest first.
        let mut order = [0usize, 1, 2];
        order.sort_by(|&i, &j| half[j].total_cmp(&half[i]));
        let rot = largest.pose.rotation;
        // The link's axis is the side along which all its primitives reach furthest; its other two
        // sides are the cross axes. For one primitive that is its longest side (the margin keeps
        // rounding from choosing another where sides are equal); a body cut into coaxial slices
        // (robots/sandfish-robot.urdf) has slices wider than long, and is long along the body.
        let span = |k: usize| {
            let (lo, hi) = reach(solids.clone(), &(rot * Vector3::ith(k, 1.0)));
            hi - lo
        };
        let mut along = 0;
        for i in 1..3 {
            if span(order[i]) > span(order[along]) * (1.0 + 1e-9) {
                along = i;
            }
        }
        order[..=along].rotate_right(1);
        let axis = rot * Vector3::ith(order[0], 1.0);
        let e2 = rot * Vector3::ith(order[1], 1.0);
        let e3 = axis.cross(&e2);
        let frame =
            UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_basis_unchecked(&[
                axis, e2, e3,
            ]));
        let (lo, hi) = reach(solids, &axis);
        let length = hi - lo;
        let (w2, w3) = (half[order[1]], half[order[2]]);
        let l = length / 2.0;
        let rho = density;
        let r_mean = (w2 + w3) / 2.0;
        // Kelasidi's relations, with (a, b) the semi-axes: for motion along e2 the projected width is
        // 2 w3 and the added mass rho pi w3^2 per length (and the other way round).
        let c_t = 0.5 * rho * PI * c.skin_friction * (w2 + w3) * length;
        let c_n = [
            0.5 * rho * c.drag * 2.0 * w3 * length,
            0.5 * rho * c.drag * 2.0 * w2 * length,
        ];
        let mu_n = [
            rho * PI * c.added_mass * w3 * w3 * length,
            rho * PI * c.added_mass * w2 * w2 * length,
        ];
        let lambda1 = rho * PI * c.added_inertia * (w2 * w2 - w3 * w3).powi(2) * l.powi(3) / 12.0;
        let lambda2 = rho * PI * c.skin_friction * (w2 + w3) * l.powi(3) / 6.0;
        let lambda3 = rho * PI * c.skin_friction * (w2 + w3) * l.powi(4) / 8.0;
        Ok(Hydro {
            volume,
            mass,
            frame,
            length,
            half_width: [w2, w3],
            c_t,
            c_n,
            mu_n,
            lambda: [[lambda1, lambda2, lambda3]; 2],
            spin: rho * PI * c.skin_friction * r_mean.powi(4) * length,
            linear: c.linear,
        })
    }
}

/// The interval the primitives cover along `axis` (a unit vector of the link's centre-of-mass
/// frame): each one's bounding box projected on it.
fn reach<I: Iterator<Item = PlacedSolid>>(solids: I, axis: &Vector3<f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for s in solids {
        let h = s.solid.half_extents();
        let c0 = s.pose.translation.vector.dot(axis);
        let r = s.pose.rotation.to_rotation_matrix();
        let reach: f64 = (0..3)
            .map(|k| h[k] * (r.matrix().column(k).dot(axis)).abs())
            .sum();
        lo = lo.min(c0 - reach);
        hi = hi.max(c0 + reach);
    }
    (lo, hi)
}

/// A link's state, world frame: its COM pose and velocities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// COM pose.
    pub pose: Isometry3<f64>,
    /// COM linear velocity, m/s.
    pub linear: Vector3<f64>,
    /// Angular velocity, rad/s.
    pub angular: Vector3<f64>,
}

/// What water keeps of a link between steps: the previous velocities and the relaxed accelerations
/// of the added mass and added inertia.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Memory {
    /// The previous step's linear and angular velocity (none before the first step in water).
    pub previous: Option<(Vector3<f64>, Vector3<f64>)>,
    /// Relaxed linear acceleration, world frame.
    pub accel: Vector3<f64>,
    /// Relaxed angular acceleration, world frame.
    pub angular_accel: Vector3<f64>,
}

/// Force (world frame, at the COM) and torque (world frame, about the COM).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Force {
    /// Force, N.
    pub force: Vector3<f64>,
    /// Torque about the COM, N m.
    pub torque: Vector3<f64>,
}

/// Submerged volume (m^3) and the centre of that volume (world frame) of one placed primitive with
/// the world pose `pose`, below the plane z = `surface`.
pub fn submerged(solid: &Solid, pose: &Isometry3<f64>, surface: f64) -> (f64, Point3<f64>) {
    let center = pose.translation.vector;
    let rot = pose.rotation.to_rotation_matrix();
    let m = rot.matrix();
    let half = solid.half_extents();
    // Vertical half extent of the bounding box: every point lies within it.
    let reach: f64 = (0..3).map(|k| half[k] * m[(2, k)].abs()).sum();
    let volume = solid.volume();
    if center.z + reach <= surface {
        return (volume, Point3::from(center));
    }
    if center.z - reach >= surface {
        return (0.0, Point3::from(center));
    }
    match *solid {
        Solid::Sphere { radius } => sphere_cap(radius, center, surface),
        Solid::Box { half } => {
            // Cells of a 4 x 4 x 4 split, each with its submerged fraction linear in depth: exact
            // when the faces are vertical or horizontal.
            const N: usize = 4;
            let cell = [half[0] / N as f64, half[1] / N as f64, half[2] / N as f64];
            let cell_reach: f64 = (0..3).map(|k| cell[k] * m[(2, k)].abs()).sum();
            let cell_volume = volume / (N * N * N) as f64;
            let mut acc = Accumulator::default();
            for i in 0..N {
                for j in 0..N {
                    for k in 0..N {
                        let local = Vector3::new(
                            -half[0] + (2 * i + 1) as f64 * cell[0],
                            -half[1] + (2 * j + 1) as f64 * cell[1],
                            -half[2] + (2 * k + 1) as f64 * cell[2],
                        );
                        acc.add_linear(center + m * local, cell_reach, cell_volume, surface);
                    }
                }
            }
            acc.finish(center)
        }
        Solid::Cylinder { radius, length } => {
            let mut acc = Accumulator::default();
            cylinder_slices(&mut acc, radius, length, center, m, surface);
            acc.finish(center)
        }
        Solid::Capsule { radius, length } => {
            let mut acc = Accumulator::default();
            cylinder_slices(&mut acc, radius, length, center, m, surface);
            // The two half spheres as one sphere's worth, split between the ends.
            let axis = m.column(2).into_owned();
            for end in [-1.0, 1.0] {
                let c = center + axis * (end * length / 2.0);
                let (v, p) = sphere_cap(radius, c, surface);
                acc.volume += v / 2.0;
                acc.moment += p.coords * (v / 2.0);
            }
            acc.finish(center)
        }
    }
}

#[derive(Default)]
struct Accumulator {
    volume: f64,
    moment: Vector3<f64>,
}

impl Accumulator {
    /// A piece of `volume` centred at `c` reaching `reach` above and below it, its submerged fraction
    /// linear in its depth; the submerged part's centre at the middle of its submerged height.
    fn add_linear(&mut self, c: Vector3<f64>, reach: f64, volume: f64, surface: f64) {
        let bottom = c.z - reach;
        let top = (c.z + reach).min(surface);
        if top <= bottom {
            return;
        }
        let fraction = if reach > 0.0 {
            (top - bottom) / (2.0 * reach)
        } else {
            1.0
        };
        let v = volume * fraction;
        self.volume += v;
        self.moment += Vector3::new(c.x, c.y, (bottom + top) / 2.0) * v;
    }

    fn finish(self, center: Vector3<f64>) -> (f64, Point3<f64>) {
        if self.volume > 0.0 {
            (self.volume, Point3::from(self.moment / self.volume))
        } else {
            (0.0, Point3::from(center))
        }
    }
}

/// A spherical cap: the part of a sphere below the plane, exactly.
fn sphere_cap(radius: f64, center: Vector3<f64>, surface: f64) -> (f64, Point3<f64>) {
    use std::f64::consts::PI;
    let s = (surface - (center.z - radius)).clamp(0.0, 2.0 * radius);
    let volume = PI * s * s * (3.0 * radius - s) / 3.0;
    if volume <= 0.0 {
        return (0.0, Point3::from(center));
    }
    // Centroid of a cap of height s lies 3 (2r - s)^2 / (4 (3r - s)) from the sphere's centre.
    let offset = 3.0 * (2.0 * radius - s).powi(2) / (4.0 * (3.0 * radius - s));
    (volume, Point3::new(center.x, center.y, center.z - offset))
}

/// A cylinder as 8 slices along its axis, each a disc whose submerged fraction is linear in its depth
/// (a vertical disc's exact fraction is the circular segment's; the linear one is within 5 % of it).
fn cylinder_slices(
    acc: &mut Accumulator,
    radius: f64,
    length: f64,
    center: Vector3<f64>,
    m: &nalgebra::Matrix3<f64>,
    surface: f64,
) {
    use std::f64::consts::PI;
    const N: usize = 8;
    let axis = m.column(2).into_owned();
    let uz = axis.z.abs().min(1.0);
    let t = length / N as f64;
    let reach = uz * t / 2.0 + radius * (1.0 - uz * uz).sqrt();
    let v = PI * radius * radius * t;
    for i in 0..N {
        let c = center + axis * (-length / 2.0 + (i as f64 + 0.5) * t);
        acc.add_segment(
            c,
            reach,
            v,
            surface,
            radius * (1.0 - uz * uz).sqrt() / reach.max(1e-300),
        );
    }
}

impl Accumulator {
    /// As [`Accumulator::add_linear`], with the fraction blended towards a circular segment's by
    /// `round` (the share of the piece's height that a round cross-section makes).
    fn add_segment(&mut self, c: Vector3<f64>, reach: f64, volume: f64, surface: f64, round: f64) {
        if reach <= 0.0 {
            return self.add_linear(c, reach, volume, surface);
        }
        let h = ((surface - (c.z - reach)) / (2.0 * reach)).clamp(0.0, 1.0);
        if h <= 0.0 {
            return;
        }
        // Circular segment of relative height h: (theta - sin theta) / 2 pi, theta = 2 acos(1 - 2h).
        let theta = 2.0 * (1.0 - 2.0 * h).clamp(-1.0, 1.0).acos();
        let segment = (theta - theta.sin()) / std::f64::consts::TAU;
        let round = round.clamp(0.0, 1.0);
        let fraction = (1.0 - round) * h + round * segment;
        let bottom = c.z - reach;
        let top = (c.z + reach).min(surface);
        let v = volume * fraction;
        self.volume += v;
        self.moment += Vector3::new(c.x, c.y, (bottom + top) / 2.0) * v;
    }
}

impl Water {
    /// Water's force and torque on a link (the media's common interface, [`crate::media`]): the
    /// link's primitives and mass from `link`, its state, the step `dt`, the world's `gravity` (m/s^2,
    /// what buoyancy works against); `memory` keeps the previous
    /// velocities (`previous_linear`, `previous_angular`) and the relaxed linear and angular
    /// accelerations of the added mass (`elements[0]`, `elements[1]`). A link with no volume feels
    /// nothing (robots with water are checked for such links when they are built).
    pub fn wrench(
        &self,
        link: &crate::media::geometry::LinkGeometry,
        state: &crate::media::LinkState,
        dt: f64,
        gravity: Vector3<f64>,
        memory: &mut crate::media::LinkMemory,
    ) -> crate::media::Wrench {
        let solids = link.shapes.iter().map(placed);
        let Ok(hydro) = Hydro::new(
            solids.clone(),
            link.mass,
            self.density,
            link.water
                .map_or(self.coefficients, |c| c.apply(self.coefficients)),
            "link",
        ) else {
            return crate::media::Wrench::default();
        };
        let mut mem = Memory {
            previous: memory.previous_linear.zip(memory.previous_angular),
            accel: memory.elements.first().copied().unwrap_or_default(),
            angular_accel: memory.elements.get(1).copied().unwrap_or_default(),
        };
        let s = State {
            pose: Isometry3::from_parts(state.pose.position.into(), state.pose.orientation),
            linear: state.linear,
            angular: state.angular,
        };
        let f = self.wrench_of(&hydro, solids, &s, dt, gravity, &mut mem);
        memory.previous_linear = mem.previous.map(|p| p.0);
        memory.previous_angular = mem.previous.map(|p| p.1);
        memory.elements.clear();
        memory.elements.extend([mem.accel, mem.angular_accel]);
        crate::media::Wrench {
            force: f.force,
            torque: f.torque,
        }
    }

    /// The force and torque water puts on a link of `hydro` in `state` over a step of `dt` seconds,
    /// with gravity `gravity` (m/s^2, world frame), and updates the link's `memory`. A link whose
    /// centre of mass is outside the region's footprint, or below its bottom, feels nothing.
    pub fn wrench_of<I: Iterator<Item = PlacedSolid>>(
        &self,
        hydro: &Hydro,
        solids: I,
        state: &State,
        dt: f64,
        gravity: Vector3<f64>,
        memory: &mut Memory,
    ) -> Force {
        let p = state.pose.translation.vector;
        if !self.region.covers(p.x, p.y) || p.z < self.region.min[2] {
            memory.previous = None;
            return Force::default();
        }
        let surface = self.region.surface();
        let mut volume = 0.0;
        let mut moment = Vector3::zeros();
        for s in solids {
            let pose = state.pose * s.pose;
            let (v, c) = submerged(&s.solid, &pose, surface);
            volume += v;
            moment += c.coords * v;
        }
        if volume <= 0.0 {
            memory.previous = None;
            return Force::default();
        }
        let wet = (volume / hydro.volume).min(1.0);
        let mut out = Force::default();
        // Buoyancy at the centre of the submerged volume.
        let buoyancy = -gravity * (self.density * volume);
        out.force += buoyancy;
        out.torque += (moment / volume - p).cross(&buoyancy);

        // Relative velocity in the link's frame (x along, y and z across).
        let frame = state.pose.rotation * hydro.frame;
        let v = frame.inverse_transform_vector(&(state.linear - self.current));
        let w = frame.inverse_transform_vector(&state.angular);
        let lin = hydro.linear;
        // Drag and moments, each component at most what stops the link's relative motion in one
        // step: applied explicitly, a drag of `c` on a link of mass `m` reverses the motion (and grows)
        // once `c dt / m > 2`, which a light, large link (a 60 g, 0.5 m cube) reaches. The limit
        // uses the link's own mass and inertia (a chained link moves more mass, so it is the
        // conservative side); on mamba-10 (`c dt / m` about 0.07) it never binds.
        let (m, dt_ok) = (hydro.mass.max(f64::MIN_POSITIVE), dt > 0.0);
        let limit = |f: f64, u: f64, inertia: f64| {
            if dt_ok {
                let most = inertia * u.abs() / dt;
                f.clamp(-most, most)
            } else {
                f
            }
        };
        let drag = |c: f64, u: f64| limit(-c * (lin * u + u.abs() * u) * wet, u, m);
        let (r, l) = (
            (hydro.half_width[0] + hydro.half_width[1]) / 2.0,
            hydro.length,
        );
        let (spin_inertia, cross_inertia) = (m * r * r / 2.0, m * (3.0 * r * r + l * l) / 12.0);
        let moment = |l2: f64, l3: f64, u: f64| {
            limit(-(l2 * lin * u + l3 * u.abs() * u) * wet, u, cross_inertia)
        };
        let mut f = Vector3::new(
            drag(hydro.c_t, v.x),
            drag(hydro.c_n[0], v.y),
            drag(hydro.c_n[1], v.z),
        );
        let mut t = Vector3::new(
            limit(-hydro.spin * w.x.abs() * w.x * wet, w.x, spin_inertia),
            moment(hydro.lambda[0][1], hydro.lambda[0][2], w.y),
            moment(hydro.lambda[1][1], hydro.lambda[1][2], w.z),
        );
        // Added mass and inertia from the relaxed accelerations (see the module's notes).
        if let Some((v0, w0)) = memory.previous {
            if dt > 0.0 {
                let mass = hydro.mass.max(f64::MIN_POSITIVE);
                let ratio = hydro.mu_n[0].max(hydro.mu_n[1]) / mass;
                let k = self.relaxation / (1.0 + ratio);
                memory.accel += ((state.linear - v0) / dt - memory.accel) * k;
                memory.angular_accel += ((state.angular - w0) / dt - memory.angular_accel) * k;
            }
        }
        memory.previous = Some((state.linear, state.angular));
        let a = frame.inverse_transform_vector(&memory.accel);
        let alpha = frame.inverse_transform_vector(&memory.angular_accel);
        f.y -= hydro.mu_n[0] * a.y * wet;
        f.z -= hydro.mu_n[1] * a.z * wet;
        t.y -= hydro.lambda[0][0] * alpha.y * wet;
        t.z -= hydro.lambda[1][0] * alpha.z * wet;
        out.force += frame * f;
        out.torque += frame * t;
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn water(current: [f64; 3]) -> Water {
        WaterFile {
            area: [-100.0, -100.0, 100.0, 100.0],
            surface: 0.0,
            depth: 100.0,
            density: Some(1000.0),
            current: Some(current),
            coefficients: None,
        }
        .resolve("media[0]")
        .unwrap()
    }

    fn cylinder_link(
        radius: f64,
        length: f64,
        mass: f64,
        c: Coefficients,
    ) -> (Hydro, Vec<PlacedSolid>) {
        // A cylinder along the link's x (its own z turned onto x).
        let pose = Isometry3::from_parts(
            Default::default(),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI / 2.0),
        );
        let solids = vec![PlacedSolid {
            solid: Solid::Cylinder { radius, length },
            pose,
        }];
        let hydro = Hydro::new(solids.iter().copied(), mass, 1000.0, c, "link").unwrap();
        (hydro, solids)
    }

    fn at(z: f64, v: Vector3<f64>) -> State {
        State {
            pose: Isometry3::translation(0.0, 0.0, z),
            linear: v,
            angular: Vector3::zeros(),
        }
    }

    #[test]
    fn archimedes_fully_and_half_submerged() {
        let w = water([0.0; 3]);
        let g = Vector3::new(0.0, 0.0, -9.81);
        // A 0.2 x 0.2 x 0.2 box: 8 litres, 78.48 N when under, 39.24 N half under.
        let solids = [PlacedSolid {
            solid: Solid::Box { half: [0.1; 3] },
            pose: Isometry3::identity(),
        }];
        let hydro = Hydro::new(
            solids.iter().copied(),
            1.0,
            1000.0,
            Coefficients::default(),
            "box",
        )
        .unwrap();
        let mut m = Memory::default();
        let f = w.wrench_of(
            &hydro,
            solids.iter().copied(),
            &at(-1.0, Vector3::zeros()),
            1.0 / 240.0,
            g,
            &mut m,
        );
        assert!(
            (f.force.z - 1000.0 * 9.81 * 0.008).abs() < 1e-9,
            "{}",
            f.force.z
        );
        let mut m = Memory::default();
        let f = w.wrench_of(
            &hydro,
            solids.iter().copied(),
            &at(0.0, Vector3::zeros()),
            1.0 / 240.0,
            g,
            &mut m,
        );
        assert!(
            (f.force.z - 1000.0 * 9.81 * 0.004).abs() < 1e-9,
            "{}",
            f.force.z
        );
        // 3 cm under: draft 0.13 m of 0.2.
        let mut m = Memory::default();
        let f = w.wrench_of(
            &hydro,
            solids.iter().copied(),
            &at(0.03, Vector3::zeros()),
            1.0 / 240.0,
            g,
            &mut m,
        );
        assert!(
            (f.force.z - 1000.0 * 9.81 * 0.04 * 0.07).abs() < 1e-9,
            "{}",
            f.force.z
        );
        // The half-submerged box's buoyancy acts at the middle of its wet half: no torque upright.
        assert!(f.torque.norm() < 1e-12);
    }

    #[test]
    fn sphere_cap_matches_the_closed_form() {
        // Half a sphere: 2/3 pi r^3, centroid 3r/8 below the centre.
        let (v, c) = submerged(&Solid::Sphere { radius: 0.1 }, &Isometry3::identity(), 0.0);
        assert!((v - 2.0 / 3.0 * PI * 1e-3).abs() < 1e-15);
        assert!((c.z + 3.0 * 0.1 / 8.0).abs() < 1e-15);
    }

    #[test]
    fn a_cylinder_cut_into_coaxial_slices_is_long_along_the_body() {
        use nalgebra::Translation3;
        // robots/sandfish-robot.urdf's segment: a cylinder 0.065 m long, 0.0175 m in radius, along
        // the link's x as seven slices end to end, each wider (0.035 m) than long (0.0093 m). The
        // link is the cylinder: axis x, length 0.065, semi-axes 0.0175, and Kelasidi's coefficients
        // written out for it.
        let (r, l, n) = (0.0175, 0.065, 7);
        let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI / 2.0);
        let slices: Vec<PlacedSolid> = (0..n)
            .map(|k| PlacedSolid {
                solid: Solid::Cylinder {
                    radius: r,
                    length: l / n as f64,
                },
                pose: Isometry3::from_parts(
                    Translation3::new(-l / 2.0 + (k as f64 + 0.5) * l / n as f64, 0.0, 0.0),
                    turn,
                ),
            })
            .collect();
        let c = Coefficients::default();
        let h = Hydro::new(slices.iter().copied(), 0.13, 1000.0, c, "seg0").unwrap();
        assert!(
            (h.frame * Vector3::x()).x.abs() > 1.0 - 1e-12,
            "{:?}",
            h.frame
        );
        assert!((h.length - l).abs() < 1e-12, "{}", h.length);
        assert!(h.half_width.iter().all(|w| (w - r).abs() < 1e-12));
        let rho = 1000.0;
        let c_t = 0.5 * rho * PI * c.skin_friction * 2.0 * r * l;
        let c_n = 0.5 * rho * c.drag * 2.0 * r * l;
        assert!(
            (h.c_t - c_t).abs() < 1e-12 * c_t
                && h.c_n.iter().all(|v| (v - c_n).abs() < 1e-12 * c_n)
        );
        assert!((h.volume - PI * r * r * l).abs() < 1e-15);
    }

    #[test]
    fn tilted_box_volume_is_close() {
        // A cube turned 30 degrees about x, its centre on the surface: half of it is under by symmetry.
        let pose = Isometry3::from_parts(
            Default::default(),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), PI / 6.0),
        );
        let (v, _) = submerged(&Solid::Box { half: [0.1; 3] }, &pose, 0.0);
        assert!((v - 0.004).abs() < 1e-12, "{v}");
        // A horizontal cylinder half under: half its volume.
        let pose = Isometry3::from_parts(
            Default::default(),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI / 2.0),
        );
        let (v, _) = submerged(
            &Solid::Cylinder {
                radius: 0.05,
                length: 0.2,
            },
            &pose,
            0.0,
        );
        assert!((v / (PI * 0.0025 * 0.2) - 0.5).abs() < 1e-12, "{v}");
        // A quarter of its diameter under: the circular segment, (theta - sin theta) / 2 pi with
        // theta = 2 acos(0.5), 19.55 % of the volume.
        let (v, _) = submerged(
            &Solid::Cylinder {
                radius: 0.05,
                length: 0.2,
            },
            &(Isometry3::translation(0.0, 0.0, 0.025) * pose),
            0.0,
        );
        let theta = 2.0 * 0.5f64.acos();
        let exact = (theta - theta.sin()) / (2.0 * PI);
        assert!((v / (PI * 0.0025 * 0.2) - exact).abs() < 1e-9, "{v}");
    }

    #[test]
    fn drag_along_and_across_follows_the_coefficients() {
        let c = Coefficients::default();
        let (r, len) = (0.05, 0.2);
        let (hydro, solids) = cylinder_link(r, len, 1.0, c);
        // Kelasidi's relations for a circular cylinder (a = b = r).
        let c_t = 0.5 * 1000.0 * PI * 0.03 * (2.0 * r) * len;
        let c_n = 0.5 * 1000.0 * 2.0 * (2.0 * r) * len;
        assert!((hydro.c_t - c_t).abs() < 1e-12);
        assert!((hydro.c_n[0] - c_n).abs() < 1e-12 && (hydro.c_n[1] - c_n).abs() < 1e-12);
        assert!((hydro.mu_n[0] - 1000.0 * PI * r * r * len).abs() < 1e-12);
        assert_eq!(hydro.lambda[0][0], 0.0);
        let w = water([0.0; 3]);
        let g = Vector3::zeros();
        // 0.3 m/s along the link (x), 0.2 m/s across it (y).
        let mut m = Memory::default();
        let f = w.wrench_of(
            &hydro,
            solids.iter().copied(),
            &at(-1.0, Vector3::new(0.3, 0.2, 0.0)),
            0.01,
            g,
            &mut m,
        );
        assert!(
            (f.force.x + c_t * (0.3 + 0.09)).abs() < 1e-12,
            "{}",
            f.force.x
        );
        assert!(
            (f.force.y + c_n * (0.2 + 0.04)).abs() < 1e-12,
            "{}",
            f.force.y
        );
        assert!(f.force.z.abs() < 1e-12);
        // In a current equal to the link's velocity: no drag at all.
        let w = water([0.3, 0.2, 0.0]);
        let mut m = Memory::default();
        let f = w.wrench_of(
            &hydro,
            solids.iter().copied(),
            &at(-1.0, Vector3::new(0.3, 0.2, 0.0)),
            0.01,
            g,
            &mut m,
        );
        assert!(f.force.norm() < 1e-12);
    }

    /// A sinking sphere-less cylinder, falling broadside, integrated here with the law's own forces:
    /// reaches the velocity where weight - buoyancy = c_n (v + v^2) (the drag law's terminal speed).
    #[test]
    fn terminal_velocity_of_a_sinking_link() {
        let c = Coefficients::default();
        let (r, len) = (0.02, 0.3);
        let volume = PI * r * r * len;
        let mass = 1500.0 * volume; // 1.5 times water's density
        let (hydro, solids) = cylinder_link(r, len, mass, c);
        let w = water([0.0; 3]);
        let g = Vector3::new(0.0, 0.0, -9.81);
        let mut m = Memory::default();
        let (mut z, mut v) = (-1.0, 0.0);
        let dt = 1.0 / 240.0;
        for _ in 0..2400 {
            let f = w.wrench_of(
                &hydro,
                solids.iter().copied(),
                &at(z, Vector3::new(0.0, 0.0, v)),
                dt,
                g,
                &mut m,
            );
            v += dt * (f.force.z / mass - 9.81);
            z += dt * v;
        }
        let net = (mass - 1000.0 * volume) * 9.81;
        let cn = hydro.c_n[1];
        // c_n (u + u^2) = net, u > 0 the sinking speed.
        let u = (-1.0 + (1.0 + 4.0 * net / cn).sqrt()) / 2.0;
        assert!((-v - u).abs() < 1e-3 * u, "{v} vs {u}");
    }

    /// The relaxed added mass stays bounded where the explicit one diverges: a neutrally buoyant link
    /// (mu_n = m) pushed across by a constant force accelerates at F / (m + mu_n).
    #[test]
    fn added_mass_is_stable_and_implicit_in_steady_state() {
        let c = Coefficients {
            drag: 0.0,
            skin_friction: 0.0,
            linear: 0.0,
            ..Coefficients::default()
        };
        let (r, len) = (0.05, 0.2);
        let mass = 1000.0 * PI * r * r * len;
        let (hydro, solids) = cylinder_link(r, len, mass, c);
        assert!((hydro.mu_n[0] - mass).abs() < 1e-12);
        let w = water([0.0; 3]);
        let mut m = Memory::default();
        let dt = 1.0 / 240.0;
        let push = 1.0;
        let mut v = 0.0;
        let mut last_a = 0.0;
        for _ in 0..240 {
            let f = w.wrench_of(
                &hydro,
                solids.iter().copied(),
                &at(-1.0, Vector3::new(0.0, v, 0.0)),
                dt,
                Vector3::zeros(),
                &mut m,
            );
            let a = (push + f.force.y) / mass;
            v += dt * a;
            last_a = a;
        }
        assert!(
            (last_a - push / (2.0 * mass)).abs() < 1e-9 * last_a,
            "{last_a}"
        );
    }

    /// A light, large link: explicit drag would overshoot (c dt / m of about 17); the limited drag
    /// stops its relative motion in a step at most, never reverses it.
    #[test]
    fn drag_never_reverses_a_light_links_motion() {
        let (r, len, mass) = (0.25, 0.5, 0.06);
        // Drag alone: the added mass (here 1,600 times the link's) has its own regularisation.
        let c = Coefficients {
            added_mass: 0.0,
            ..Coefficients::default()
        };
        let (hydro, solids) = cylinder_link(r, len, mass, c);
        let w = water([0.0; 3]);
        let dt = 1.0 / 240.0;
        let mut m = Memory::default();
        let mut v = 1.0;
        for _ in 0..50 {
            let f = w.wrench_of(
                &hydro,
                solids.iter().copied(),
                &at(-1.0, Vector3::new(0.0, v, 0.0)),
                dt,
                Vector3::zeros(),
                &mut m,
            );
            let next = v + dt * f.force.y / mass;
            assert!(next >= -1e-12 && next <= v, "{v} -> {next}");
            v = next;
        }
    }

    #[test]
    fn overlapping_water_regions_are_refused() {
        let at = |x0: f64| {
            crate::media::Medium::Water(
                WaterFile {
                    area: [x0, 0.0, x0 + 1.0, 1.0],
                    surface: 0.0,
                    depth: 1.0,
                    density: None,
                    current: None,
                    coefficients: None,
                }
                .resolve("m")
                .unwrap(),
            )
        };
        // Side by side (sharing an edge): fine; overlapping: refused, both named.
        assert!(check_overlap(&[at(0.0), at(1.0)]).is_ok());
        let e = check_overlap(&[at(0.0), at(0.5)]).unwrap_err().to_string();
        assert!(e.contains("media[0] and media[1]"), "{e}");
    }

    #[test]
    fn bad_input_is_one_line_naming_the_key() {
        let mut file = WaterFile {
            area: [0.0, 0.0, 1.0, 1.0],
            surface: 0.0,
            depth: 1.0,
            density: Some(-1.0),
            current: None,
            coefficients: None,
        };
        let e = file
            .resolve("world.yaml: media[0]")
            .unwrap_err()
            .to_string();
        assert!(e.contains("media[0]: density"), "{e}");
        file.density = None;
        file.current = Some([f64::NAN, 0.0, 0.0]);
        let e = file.resolve("media[0]").unwrap_err().to_string();
        assert!(e.contains("media[0]: current"), "{e}");
        file.current = None;
        file.coefficients = Some(CoefficientsFile {
            drag: Some(-2.0),
            ..Default::default()
        });
        let e = file.resolve("media[0]").unwrap_err().to_string();
        assert!(e.contains("coefficients: drag"), "{e}");
        let e = serde_norway::from_str::<WaterFile>(
            "{area: [0, 0, 1, 1], depth: 1, coefficients: {cd: 1}}",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("cd"), "{e}");
        let e = Hydro::new(
            std::iter::empty(),
            1.0,
            1000.0,
            Coefficients::default(),
            "links: tail",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("links: tail: has no volume"), "{e}");
    }
}
