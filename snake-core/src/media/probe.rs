//! Li et al.'s plate experiment in silico (`snake-cli probe`, `snakesim.media.probe`): a thin plate of
//! `length x width` at the angle of attack `beta`, its centre `depth` below a granular medium's
//! surface, moved at `speed` in the direction `gamma` below the horizontal, through the medium of a
//! world file. The plate is a box `length x width x length/1000` (its edges take under 0.5 % of the
//! force) cut into the medium's surface elements; it moves until every element's elastic displacement
//! has reached the cap, and the force on it is the medium's law summed over them: what a user compares
//! with a measurement of their own sand to fit `zeta`.
//!
//! Frame: x is the horizontal direction of the motion, z up; the force is reported as the medium
//! pushes the plate (`force_x` against the motion when positive motion is along +x, so Li's
//! `alpha_x = -force_x / (zeta L W depth)` and `alpha_z = force_z / (zeta L W depth)`).

use nalgebra::{UnitQuaternion, Vector3};
use serde::Serialize;

use crate::error::{invalid, Result};
use crate::limits::{check_range, check_range_above, MAX_OBSTACLE_SIZE};
use crate::media::granular::{alpha, Granular};
use crate::media::{LinkGeometry, LinkMemory, LinkState, Medium, Primitive, Shape};
use crate::world::Pose;

/// A plate experiment's settings; angles in degrees, within Li et al.'s domain `[-90, 90]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plate {
    /// Along the motion's plane, metres.
    pub length: f64,
    /// Across it, metres.
    pub width: f64,
    /// Angle of attack, degrees.
    pub beta: f64,
    /// Intrusion angle (the motion's angle below the horizontal), degrees.
    pub gamma: f64,
    /// Depth of the plate's centre below the surface, metres.
    pub depth: f64,
    /// Speed, m/s.
    pub speed: f64,
}

/// What the probe measured, and the law integrated over the plate for comparison.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProbeResult {
    /// Horizontal force along the motion's horizontal direction, N.
    pub force_x: f64,
    /// Vertical force, N (up positive).
    pub force_z: f64,
    /// Force per unit plate area, N/m^2.
    pub stress_x: f64,
    /// Force per unit plate area, N/m^2.
    pub stress_z: f64,
    /// Li's law over the plate's face: `-zeta alpha_x L W depth`, N.
    pub law_x: f64,
    /// `zeta alpha_z L W depth`, N.
    pub law_z: f64,
    /// `alpha_x` of the law at these angles.
    pub alpha_x: f64,
    /// `alpha_z` of the law at these angles.
    pub alpha_z: f64,
    /// Surface elements of the plate.
    pub elements: usize,
}

impl Plate {
    /// Checks the settings; `flag` names each value as the caller calls it (`--beta`).
    pub fn check(&self, flag: impl Fn(&str) -> String) -> Result<()> {
        check_range_above(&flag("length"), self.length, 0.0, MAX_OBSTACLE_SIZE)?;
        check_range_above(&flag("width"), self.width, 0.0, MAX_OBSTACLE_SIZE)?;
        check_range(&flag("beta"), self.beta, -90.0, 90.0)?;
        check_range(&flag("gamma"), self.gamma, -90.0, 90.0)?;
        check_range_above(&flag("depth"), self.depth, 0.0, MAX_OBSTACLE_SIZE)?;
        check_range_above(&flag("speed"), self.speed, 0.0, 1.0e3)?;
        Ok(())
    }
}

/// The first granular medium of `media`.
pub fn granular(media: &[Medium]) -> Result<&Granular> {
    media
        .iter()
        .find_map(|m| match m {
            Medium::Granular(g) => Some(g),
            Medium::Water(_) => None,
        })
        .ok_or_else(|| {
            invalid("the world has no granular medium (media: [{medium: granular, ...}])")
        })
}

/// Runs the plate experiment in `medium` (see the module docs).
pub fn probe(medium: &Granular, plate: &Plate) -> Result<ProbeResult> {
    let r = &medium.region;
    let half = 0.5 * plate.length.max(plate.width);
    if plate.depth + half > r.max[2] - r.min[2] {
        return Err(invalid(format!(
            "the plate reaches below the medium's bottom ({} m deep)",
            r.max[2] - r.min[2]
        )));
    }
    let (beta, gamma) = (plate.beta.to_radians(), plate.gamma.to_radians());
    // The plate's length runs along x turned by beta about y so that its leading normal, for
    // beta > 0, faces forward and down: (sin b, 0, -cos b) is the box's -z face turned.
    let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -beta);
    let thickness = plate.length.min(plate.width) * 1e-3;
    let shape = Shape {
        primitive: Primitive::Box([0.5 * plate.length, 0.5 * plate.width, 0.5 * thickness]),
        pose: Pose {
            position: Vector3::zeros(),
            orientation: UnitQuaternion::identity(),
        },
    };
    // Mass 0: the plate is moved, not simulated, so no stability bound raises `elastic` for it.
    let link = LinkGeometry::new(0.0, vec![shape], Some(medium.element), "element")?;
    let centre = Vector3::new(
        0.5 * (r.min[0] + r.max[0]),
        0.5 * (r.min[1] + r.max[1]),
        r.max[2] - plate.depth,
    );
    let velocity = plate.speed * Vector3::new(gamma.cos(), 0.0, -gamma.sin());
    let state = LinkState {
        pose: Pose {
            position: centre,
            orientation: turn,
        },
        linear: velocity,
        angular: Vector3::zeros(),
    };
    // Enough steps of a short interval to fill every element's elastic displacement, without moving
    // the plate (the stress is taken at this depth).
    let dt = medium.elastic / plate.speed;
    let mut memory = LinkMemory::default();
    let mut w = medium.wrench(&link, &state, dt, &mut memory);
    for _ in 0..2 {
        w = medium.wrench(&link, &state, dt, &mut memory);
    }
    let area = plate.length * plate.width;
    let (ax, az) = alpha(beta, gamma, &medium.coefficients);
    let law = medium.zeta * area * plate.depth;
    Ok(ProbeResult {
        force_x: w.force.x,
        force_z: w.force.z,
        stress_x: w.force.x / area,
        stress_z: w.force.z / area,
        law_x: -ax * law,
        law_z: az * law,
        alpha_x: ax,
        alpha_z: az,
        elements: link.elements.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::media::granular::{CoefficientsFile, GranularFile};

    fn sand(element: f64) -> Granular {
        GranularFile {
            area: [-1.0, -1.0, 1.0, 1.0],
            surface: 0.0,
            depth: 0.5,
            zeta: 2.0e5,
            coefficients: CoefficientsFile::default(),
            friction: 0.2,
            element,
            elastic: 0.002,
        }
        .resolve("media[0]")
        .unwrap()
    }

    #[test]
    fn the_plate_feels_the_law_integrated_over_it_within_2_percent() {
        let g = sand(0.005);
        for (beta, gamma) in [
            (0.0, 90.0),
            (0.0, -90.0),
            (30.0, 45.0),
            (-45.0, 20.0),
            (60.0, 0.0),
            (90.0, 0.0),
            (-30.0, -60.0),
            (0.0, 0.0),
        ] {
            let plate = Plate {
                length: 0.0381,
                width: 0.0254,
                beta,
                gamma,
                depth: 0.076,
                speed: 0.01,
            };
            let r = probe(&g, &plate).unwrap();
            let scale = r.law_x.hypot(r.law_z);
            let error = (r.force_x - r.law_x).hypot(r.force_z - r.law_z) / scale;
            assert!(
                error < 0.02,
                "beta {beta} gamma {gamma}: {r:?} error {error}"
            );
        }
    }
}
