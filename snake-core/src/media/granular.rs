//! A dry granular medium (issue 59): resistive force theory (RFT) after Li, Zhang and Goldman 2013
//! ("A terradynamics of legged locomotion on granular media", Science 339:1408).
//!
//! **The law.** A small plate element below the surface at depth `|z|`, moving through the grains,
//! takes the stress `sigma = zeta * alpha(beta, gamma) * |z|` on its leading surface (the surface facing
//! the motion; trailing surfaces take none). `beta` is the plate's angle of attack, `gamma` the angle of
//! its motion below the horizontal, both in the vertical plane of the motion; `alpha = (alpha_x,
//! alpha_z)` is Li et al.'s generic fit ([`alpha`]), `alpha_x` resisting the horizontal motion and
//! `alpha_z` pointing up; `zeta` (N/m^3) scales the generic fit to a medium. The generic coefficients sum
//! to `alpha_z(0, pi/2) = 1.000`, so `zeta` is the medium's `alpha_z` for a horizontal plate pushed
//! straight down: the one number a user measures.
//!
//! **Three dimensions.** Li's law is two-dimensional: the plate's normal and its velocity in one
//! vertical plane. For an element whose motion leaves that plane we superpose two two-dimensional cases
//! by the share of the motion in each, as Treers, Cao and Stuart 2021 (IEEE RA-L 6:1887, "Granular
//! resistive force theory implementation for three-dimensional trajectories") do: the plane is the
//! vertical plane of the element's normal (r: the normal's horizontal direction, s = z x r across it);
//! the motion's part in that plane (share `p`) takes Li's stress, and its part across the plane, a
//! sliding of the grains along the surface, takes Coulomb friction: the body-grain friction `mu` times
//! the pressure the element bears under that stress (none on a trailing face), along the sliding's
//! share across the plane. We use this rather than Agarwal, Goldman and
//! Kamrin's 3D-RFT (PNAS 2023, 120:e2214017120), whose fitted functions we could not retrieve here to
//! cite; both reduce to Li's law in the plane.
//!
//! **Zero speed.** The law is rate-independent: the stress does not shrink with the speed, so it has no
//! value at rest, and applied explicitly it would flip its sign each step around rest. We regularise it
//! as a stiff elastic-plastic contact (the idea of Yilmaz, Douglas, Perron and Kamrin's "elastic RFT",
//! Soft Matter 2026): each element keeps an elastic displacement `u` (world frame) that grows with its
//! motion (`u += v dt`) and is capped at `elastic` metres; the element's motion direction is `u`'s, and
//! its stress is the law's times `|u| / elastic`. A resting body is held by a displacement below the
//! cap (no creep); a moving one reaches the cap after `elastic / |v|` seconds and then feels the law
//! itself. docs/media.md studies the element size and `elastic` and shows the steady results do not
//! depend on them.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::{invalid, Result};
use crate::limits::{
    check_range, check_range_above, GRANULAR_ELASTIC, MAX_GRANULAR_COEFFICIENT,
    MAX_GRANULAR_FRICTION, MAX_GRANULAR_ZETA,
};
use crate::media::geometry::{check_element_size, LinkGeometry};
use crate::media::{LinkMemory, LinkState, Region, RegionFile, Wrench};

/// Li et al.'s Fourier coefficients (their Eq. 1, the generic fit's names).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Coefficients {
    /// `A00`.
    #[serde(rename = "A00")]
    pub a00: f64,
    /// `A10`.
    #[serde(rename = "A10")]
    pub a10: f64,
    /// `B11`.
    #[serde(rename = "B11")]
    pub b11: f64,
    /// `B01`.
    #[serde(rename = "B01")]
    pub b01: f64,
    /// `B-11`.
    #[serde(rename = "B-11")]
    pub bm11: f64,
    /// `C11`.
    #[serde(rename = "C11")]
    pub c11: f64,
    /// `C01`.
    #[serde(rename = "C01")]
    pub c01: f64,
    /// `C-11`.
    #[serde(rename = "C-11")]
    pub cm11: f64,
    /// `D10`.
    #[serde(rename = "D10")]
    pub d10: f64,
}

/// Li, Zhang and Goldman 2013's generic coefficients (Science 339:1408, the fit of their Fig. 2 and
/// Table S1; dimensionless, scaled by `zeta`).
pub const GENERIC: Coefficients = Coefficients {
    a00: 0.206,
    a10: 0.169,
    b11: 0.212,
    b01: 0.358,
    bm11: 0.055,
    c11: -0.124,
    c01: 0.253,
    cm11: 0.007,
    d10: 0.088,
};

/// Coefficient tables by name: what `coefficients: NAME` may say.
pub const NAMED_COEFFICIENTS: &[(&str, Coefficients)] = &[("generic", GENERIC)];

impl Coefficients {
    /// A table by name ([`NAMED_COEFFICIENTS`]).
    pub fn named(name: &str, what: &str) -> Result<Self> {
        NAMED_COEFFICIENTS
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, c)| *c)
            .ok_or_else(|| {
                let known: Vec<&str> = NAMED_COEFFICIENTS.iter().map(|(n, _)| *n).collect();
                invalid(format!(
                    "{what}: unknown coefficient table {:?}; known: {}, or a table of A00, A10, B11, B01, B-11, C11, C01, C-11, D10",
                    crate::files::excerpt(name),
                    known.join(", ")
                ))
            })
    }

    fn check(&self, what: &str) -> Result<()> {
        for (name, v) in [
            ("A00", self.a00),
            ("A10", self.a10),
            ("B11", self.b11),
            ("B01", self.b01),
            ("B-11", self.bm11),
            ("C11", self.c11),
            ("C01", self.c01),
            ("C-11", self.cm11),
            ("D10", self.d10),
        ] {
            check_range(
                &format!("{what}: {name}"),
                v,
                -MAX_GRANULAR_COEFFICIENT,
                MAX_GRANULAR_COEFFICIENT,
            )?;
        }
        Ok(())
    }

    /// `(alpha_x, alpha_z)` from `cos 2 beta`, `sin 2 beta`, `cos gamma`, `sin gamma`: Li et al.'s Eq. 1
    /// with the angle sums expanded, so that the per-element law needs no trigonometric call.
    #[inline]
    pub fn alpha_cs(&self, c2b: f64, s2b: f64, cg: f64, sg: f64) -> (f64, f64) {
        // sin(2b + g), sin(-2b + g), cos(2b + g), cos(-2b + g).
        let s_plus = s2b * cg + c2b * sg;
        let s_minus = c2b * sg - s2b * cg;
        let c_plus = c2b * cg - s2b * sg;
        let c_minus = c2b * cg + s2b * sg;
        let az =
            self.a00 + self.a10 * c2b + self.b11 * s_plus + self.b01 * sg + self.bm11 * s_minus;
        let ax = self.c11 * c_plus + self.c01 * cg + self.cm11 * c_minus + self.d10 * s2b;
        (ax, az)
    }
}

/// Li et al.'s `(alpha_x, alpha_z)` (dimensionless; times `zeta` in N/m^3 for a medium) for the plate
/// angle `beta` and the intrusion angle `gamma`, radians. In `[-pi/2, pi/2]` both, it is their Eq. 1:
///
/// `alpha_z = A00 + A10 cos 2b + B11 sin(2b + g) + B01 sin g + B-11 sin(-2b + g)`,
/// `alpha_x = C11 cos(2b + g) + C01 cos g + C-11 cos(-2b + g) + D10 sin 2b`.
///
/// Other angles follow by Li et al.'s symmetries: a plate turned by pi is the same plate (period pi in
/// `beta`, which Eq. 1 has), and the mirror image `x -> -x` takes `(beta, gamma)` to `(-beta, pi -
/// gamma)` and `alpha_x` to `-alpha_x`.
pub fn alpha(beta: f64, gamma: f64, c: &Coefficients) -> (f64, f64) {
    use std::f64::consts::{FRAC_PI_2, PI};
    let mut g = gamma.sin().atan2(gamma.cos());
    let mut b = beta;
    let mut mirror = false;
    if g > FRAC_PI_2 {
        (b, g, mirror) = (-b, PI - g, true);
    } else if g < -FRAC_PI_2 {
        (b, g, mirror) = (-b, -PI - g, true);
    }
    let (ax, az) = c.alpha_cs((2.0 * b).cos(), (2.0 * b).sin(), g.cos(), g.sin());
    (if mirror { -ax } else { ax }, az)
}

/// `zeta` as written: N/m^3.
pub type Zeta = f64;

/// `coefficients` as written: a name ([`NAMED_COEFFICIENTS`]) or a table of Li's nine coefficients.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum CoefficientsFile {
    /// `generic`.
    Named(String),
    /// `{A00: ..., ..., D10: ...}`, every key.
    Table(Coefficients),
}

impl Default for CoefficientsFile {
    fn default() -> Self {
        CoefficientsFile::Named("generic".into())
    }
}

fn default_element() -> f64 {
    DEFAULT_ELEMENT
}

fn default_elastic() -> f64 {
    DEFAULT_ELASTIC
}

/// The default surface element size, metres.
pub const DEFAULT_ELEMENT: f64 = 0.01;

/// The default elastic displacement at yield, metres.
pub const DEFAULT_ELASTIC: f64 = 0.002;

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
    /// Strength: Li et al.'s scaling factor, N/m^3 (the stress on a horizontal plate pushed straight
    /// down, per metre of depth).
    pub zeta: Zeta,
    /// Li et al.'s coefficient table: `generic` (the default) or a table of all nine.
    #[serde(default)]
    pub coefficients: CoefficientsFile,
    /// Body-grain friction coefficient (grains sliding along the surface).
    pub friction: f64,
    /// Surface element size, metres (default 0.01).
    #[serde(default = "default_element")]
    pub element: f64,
    /// Elastic displacement at yield, metres (default 0.002): the zero-speed regularisation.
    #[serde(default = "default_elastic")]
    pub elastic: f64,
}

/// A checked granular medium.
#[derive(Debug, Clone, PartialEq)]
pub struct Granular {
    /// Where it is.
    pub region: Region,
    /// N/m^3.
    pub zeta: f64,
    /// The coefficient table.
    pub coefficients: Coefficients,
    /// Body-grain friction coefficient.
    pub friction: f64,
    /// Surface element size, metres.
    pub element: f64,
    /// Elastic displacement at yield, metres.
    pub elastic: f64,
}

impl GranularFile {
    /// Checks every value; `what` names the entry (`media[0]`).
    pub fn resolve(&self, what: &str) -> Result<Granular> {
        let region = RegionFile {
            area: self.area,
            surface: self.surface,
            depth: self.depth,
        }
        .resolve(what)?;
        check_range_above(&format!("{what}: zeta"), self.zeta, 0.0, MAX_GRANULAR_ZETA)?;
        check_range(
            &format!("{what}: friction"),
            self.friction,
            0.0,
            MAX_GRANULAR_FRICTION,
        )?;
        check_element_size(&format!("{what}: element"), self.element)?;
        check_range_above(
            &format!("{what}: elastic"),
            self.elastic,
            GRANULAR_ELASTIC.0,
            GRANULAR_ELASTIC.1,
        )?;
        let coefficients = match &self.coefficients {
            CoefficientsFile::Named(name) => {
                Coefficients::named(name, &format!("{what}: coefficients"))?
            }
            CoefficientsFile::Table(t) => {
                t.check(&format!("{what}: coefficients"))?;
                *t
            }
        };
        Ok(Granular {
            region,
            zeta: self.zeta,
            coefficients,
            friction: self.friction,
            element: self.element,
            elastic: self.elastic,
        })
    }
}

/// The stress on one element (N/m^2, world frame) for its outward normal `n`, its motion direction
/// `d` (unit), its depth below the surface (> 0) and `zeta`, `mu`, `c` of the medium: the law of the
/// module docs, before the elastic ramp.
pub fn element_stress(
    n: &Vector3<f64>,
    d: &Vector3<f64>,
    depth: f64,
    zeta: f64,
    mu: f64,
    c: &Coefficients,
) -> Vector3<f64> {
    let up = Vector3::z();
    // The vertical plane of the normal: r its horizontal direction; a horizontal face takes the
    // plane of the motion instead (Li's own two-dimensional case).
    let nh = Vector3::new(n.x, n.y, 0.0);
    let dh = Vector3::new(d.x, d.y, 0.0);
    let mut r = if nh.norm_squared() > 1e-12 {
        nh.normalize()
    } else if dh.norm_squared() > 1e-24 {
        dh.normalize()
    } else {
        Vector3::x()
    };
    let s = up.cross(&r);
    let scale = zeta * depth;
    let mut stress = Vector3::zeros();
    let (nr, nz) = (n.dot(&r), n.z);
    let np = nr.hypot(nz);
    // In the plane: the motion's part along r and z.
    let mut dr = d.dot(&r);
    if dr < 0.0 {
        r = -r;
        dr = -dr;
    }
    let (nr, dz) = (n.dot(&r), d.z);
    let p = dr.hypot(dz);
    // The leading face: moving into it. A plate moving exactly along itself (Li's beta = -gamma) has
    // no leading face; its lower face takes the law there (both faces give the same alpha, which
    // has period pi in beta, so the law stays continuous through the switch).
    let into = dr * nr + dz * nz;
    let leads = into > 0.0 || (into == 0.0 && (nz < 0.0 || (nz == 0.0 && nr > 0.0)));
    if p > 1e-12 && np > 1e-12 && leads {
        let (sb, cb) = (nr / np, -nz / np);
        let (c2b, s2b) = (cb * cb - sb * sb, 2.0 * sb * cb);
        let (ax, az) = c.alpha_cs(c2b, s2b, dr / p, -dz / p);
        stress += p * scale * (az * up - ax * r);
    }
    // Across the plane: grains sliding along the surface, resisted by Coulomb friction on the
    // pressure the face bears (the normal part of Li's stress; none on a trailing face), along the
    // sliding's share across the plane.
    let ds = d.dot(&s);
    let tangential = (d - d.dot(n) * n).norm();
    if mu > 0.0 && ds != 0.0 && tangential > 1e-12 {
        let pressure = stress.dot(n).abs();
        stress -= (ds / tangential) * mu * pressure * s;
    }
    stress
}

impl Granular {
    /// The elastic displacement at yield this step for `link`: `elastic`, or more where the link is
    /// so light for the medium's strength that the stiffness `F / elastic` would make the explicit
    /// step unstable. `F` is a third of `zeta * sum(depth * area)` over the submerged elements (a
    /// box leads with at most three faces); the bound keeps `4 F dt^2 / (m elastic) <= 1`, the 4 for
    /// rotation (a force at a box's corner turns it about 3 to 6 times as stiffly as it moves it), within
    /// the explicit damped spring's limit of 2. Without the 4, the paper's cubes driven by the `lateral`
    /// gait leapt out of the sand. A 0.5 m cube of 1 kg 0.25 m deep in zeta 2e5 needs 1.7 m; the robot
    /// sandfish 1 cm below the surface 3 mm.
    pub fn stable_elastic(&self, link: &LinkGeometry, state: &LinkState, dt: f64) -> f64 {
        if link.mass <= 0.0 {
            return self.elastic;
        }
        let surface = self.region.surface();
        let mut load = 0.0;
        for el in &link.elements {
            let at = state.pose.position + state.pose.orientation * el.point;
            let depth = surface - at.z;
            if depth > 0.0 && self.region.contains([at.x, at.y, at.z]) {
                load += depth * el.area;
            }
        }
        let force = self.zeta * load / 3.0;
        self.elastic.max(4.0 * force * dt * dt / link.mass)
    }

    /// The medium's wrench on a link in `state`, and each element's elastic displacement kept in
    /// `memory` (see the module docs).
    pub fn wrench(
        &self,
        link: &LinkGeometry,
        state: &LinkState,
        dt: f64,
        memory: &mut LinkMemory,
    ) -> Wrench {
        let mut w = Wrench::default();
        if memory.elements.len() != link.elements.len() {
            memory.elements = vec![Vector3::zeros(); link.elements.len()];
        }
        let rot = state.pose.orientation;
        let com = state.pose.position;
        let surface = self.region.surface();
        let elastic = self.stable_elastic(link, state, dt);
        for (el, u) in link.elements.iter().zip(memory.elements.iter_mut()) {
            let offset = rot * el.point;
            let at = com + offset;
            let depth = surface - at.z;
            if depth <= 0.0 || !self.region.contains([at.x, at.y, at.z]) {
                *u = Vector3::zeros();
                continue;
            }
            let v = state.velocity_at(&offset);
            *u += v * dt;
            let len = u.norm();
            if len > elastic {
                *u *= elastic / len;
            } else if len == 0.0 {
                continue;
            }
            // The displacement one step on (u + v dt): the spring's look-ahead, a damper of time
            // constant dt in the elastic range, which keeps a resting body from chattering.
            let q = *u + v * dt;
            let len = q.norm();
            if len == 0.0 {
                continue;
            }
            let d = q / len;
            let n = rot * el.normal;
            let ramp = (len / elastic).min(1.0);
            let f = ramp
                * el.area
                * element_stress(&n, &d, depth, self.zeta, self.friction, &self.coefficients);
            w.force += f;
            w.torque += offset.cross(&f);
        }
        w
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn a_horizontal_plate_pushed_straight_down_has_alpha_z_one() {
        let (ax, az) = alpha(0.0, FRAC_PI_2, &GENERIC);
        assert!((az - 1.0).abs() < 1e-12 && ax.abs() < 1e-12, "{ax} {az}");
    }

    #[test]
    fn the_symmetries_hold() {
        for &(b, g) in &[(0.3, 0.2), (-1.0, 1.2), (1.4, -0.7)] {
            let (ax, az) = alpha(b, g, &GENERIC);
            let (bx, bz) = alpha(b + std::f64::consts::PI, g, &GENERIC);
            assert!((ax - bx).abs() < 1e-12 && (az - bz).abs() < 1e-12);
            let (mx, mz) = alpha(-b, std::f64::consts::PI - g, &GENERIC);
            assert!((ax + mx).abs() < 1e-12 && (az - mz).abs() < 1e-12);
        }
    }

    #[test]
    fn the_element_law_is_li_in_the_plane() {
        // A horizontal plate's lower face moving straight down: zeta |z| up.
        let s = element_stress(
            &Vector3::new(0.0, 0.0, -1.0),
            &Vector3::new(0.0, 0.0, -1.0),
            0.1,
            1e5,
            0.3,
            &GENERIC,
        );
        assert!((s - Vector3::new(0.0, 0.0, 1e4)).norm() < 1e-9, "{s}");
        // A vertical plate's face moving along its normal (+x): alpha(pi/2, 0) against the motion.
        let (ax, az) = alpha(FRAC_PI_2, 0.0, &GENERIC);
        let s = element_stress(&Vector3::x(), &Vector3::x(), 0.1, 1e5, 0.3, &GENERIC);
        assert!((s - 1e4 * Vector3::new(-ax, 0.0, az)).norm() < 1e-9, "{s}");
        // Its trailing face takes nothing but friction across (none here: the motion is in plane).
        let s = element_stress(&-Vector3::x(), &Vector3::x(), 0.1, 1e5, 0.3, &GENERIC);
        assert!(s.norm() < 1e-12, "{s}");
    }

    #[test]
    fn bad_values_are_refused_naming_the_key() {
        let good = GranularFile {
            area: [-1.0, -1.0, 1.0, 1.0],
            surface: 0.0,
            depth: 0.2,
            zeta: 1e5,
            coefficients: CoefficientsFile::default(),
            friction: 0.2,
            element: 0.01,
            elastic: 0.002,
        };
        assert!(good.resolve("media[0]").is_ok());
        for (bad, key) in [
            (
                GranularFile {
                    zeta: -1.0,
                    ..good.clone()
                },
                "zeta",
            ),
            (
                GranularFile {
                    zeta: f64::NAN,
                    ..good.clone()
                },
                "zeta",
            ),
            (
                GranularFile {
                    element: 0.0,
                    ..good.clone()
                },
                "element",
            ),
            (
                GranularFile {
                    coefficients: CoefficientsFile::Named("mud".into()),
                    ..good.clone()
                },
                "coefficients",
            ),
        ] {
            let err = bad.resolve("media[0]").unwrap_err().to_string();
            assert!(err.contains(&format!("media[0]: {key}")), "{err}");
        }
    }

    #[test]
    fn a_world_file_reads_its_granular_media_once_and_refuses_them_off_the_plane() {
        use crate::WorldSpec;
        let dir = std::path::Path::new(".");
        let ok = "media:\n  - {medium: granular, area: [-1, -1, 1, 1], depth: 0.3, zeta: 2.0e5, friction: 0.2,\n     coefficients: {A00: 1, A10: 0, B11: 0, B01: 0, B-11: 0, C11: 0, C01: 0, C-11: 0, D10: 0}}\n";
        let spec = WorldSpec::parse(ok, "w.yaml", dir).unwrap();
        assert!(spec.has_granular() && !spec.is_flat_plane());
        let crate::media::Medium::Granular(g) = &spec.media[0] else {
            panic!("granular")
        };
        assert_eq!(
            (g.coefficients.a00, g.element, g.elastic),
            (1.0, 0.01, 0.002)
        );
        for (text, expect) in [
            (
                "ground: {slope: {degrees: 5}}\nmedia: [{medium: granular, area: [0, 0, 1, 1], depth: 0.1, zeta: 1.0e5, friction: 0.2}]\n",
                "w.yaml: media: a granular medium needs the plane ground",
            ),
            (
                "media: [{medium: granular, area: [0, 0, 1, 1], depth: 0.1, zeta: 1.0e5, friction: 0.2, coefficients: {A00: 1}}]\n",
                "w.yaml",
            ),
            (
                "media: [{medium: granular, area: [0, 0, 1, 1], depth: 0.1, zeta: 1.0e5}]\n",
                "friction",
            ),
            (
                "media: [{medium: granular, area: [0, 0, 1, 1], depth: 0.1, zeta: .inf, friction: 0.2}]\n",
                "w.yaml",
            ),
        ] {
            let err = WorldSpec::parse(text, "w.yaml", dir).unwrap_err().to_string();
            assert!(err.contains(expect) && !err.contains('\n'), "{err}");
        }
    }
}
