//! Writing the observation vector.

use super::config::{ObservationLayout, ObservationPart, ObservationStructure};
use super::height_map::{GroundProbe, HeightMap};
use crate::error::Result;
use crate::robot::Simulation;
pub(crate) use crate::world::BaseState;

/// Planar heading of the base: the rotation about world z of its x axis (0 at the paper's start
/// orientation, where the tail extends along +y and the snake crawls towards -y).
pub(crate) fn heading(base: &BaseState) -> f64 {
    let q = base.pose.orientation.quaternion().coords; // (x, y, z, w)
    let (x, y, z, w) = (q.x, q.y, q.z, q.w);
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// The terrain layout's head frame, which rolling does not scramble: (heading, mirror). The heading
/// is that of the base's y axis (the body's long axis, which rolling about it leaves in place) less
/// a quarter turn, so that upright and level it equals [`heading`]; mirror is -1 while the head is
/// upside down (its z axis below the horizontal) and +1 otherwise. Why not [`heading`]: the x axis
/// it follows turns half a turn when the head rolls over, and lying on its side it points up or
/// down and has no heading at all, which on hills happens again and again. Why mirror: upside
/// down the yaw joints bend the body the other way for the same action, so the frame's left is
/// mirrored to stay the side a positive steering bends towards (docs/tasks.md, "The head frame on
/// hills").
pub(crate) fn rolled_frame(base: &BaseState) -> (f64, f64) {
    let q = base.pose.orientation.quaternion().coords; // (x, y, z, w)
    let (x, y, z, w) = (q.x, q.y, q.z, q.w);
    // The base's y axis in the world is (R01, R11, R21); a quarter turn back, (R11, -R01), it is
    // where a level head's x axis would point.
    let (r01, r11) = (2.0 * (x * y - w * z), 1.0 - 2.0 * (x * x + z * z));
    let r22 = 1.0 - 2.0 * (x * x + y * y);
    ((-r01).atan2(r11), if r22 < 0.0 { -1.0 } else { 1.0 })
}

/// Scratch buffers of the joint reads, kept to make stepping allocation-free.
#[derive(Debug, Clone, Default)]
pub(crate) struct JointScratch {
    pub positions: Vec<f64>,
    pub velocities: Vec<f64>,
}

impl JointScratch {
    pub fn new(joints: usize) -> Self {
        JointScratch {
            positions: vec![0.0; joints],
            velocities: vec![0.0; joints],
        }
    }
}

/// Fills `obs` (of `structure`'s length) part by part, in `structure`'s order, from the snake's
/// current state and, for the terrain layout, from `ground` sampled at the grid `map`; returns the
/// base state. `layout` picks the head frame (the rolled one for the terrain layout); the wave's
/// part is written where `wave_phase` is given.
///
/// Every value is the simulator's double cast to `float32` (round to nearest), as the paper's
/// `np.array(...).astype(np.float32)` does.
#[allow(clippy::too_many_arguments)]
pub(crate) fn write(
    layout: ObservationLayout,
    structure: &ObservationStructure,
    snake: &dyn Simulation,
    goal: (f64, f64),
    wave_phase: Option<f64>,
    (ground, map): (&GroundProbe, &HeightMap),
    scratch: &mut JointScratch,
    obs: &mut [f32],
) -> Result<BaseState> {
    let base = snake.base_state()?;
    snake.read_joints(&mut scratch.positions, &mut scratch.velocities)?;
    let p = base.pose.position;
    let (yaw, mirror) = match layout {
        ObservationLayout::Paper => (0.0, 1.0),
        ObservationLayout::Extended => (heading(&base), 1.0),
        ObservationLayout::Terrain => rolled_frame(&base),
    };
    let (s, c) = yaw.sin_cos();
    // World vectors into the head frame: rotation by -yaw about z, left mirrored upside down.
    let to_head = |vx: f64, vy: f64| (mirror * (c * vx + s * vy), -s * vx + c * vy);
    let mut at = 0;
    for &(part, size) in structure.parts() {
        let out = &mut obs[at..at + size];
        at += size;
        match part {
            ObservationPart::BasePosition => out.copy_from_slice(&[p.x as f32, p.y as f32]),
            ObservationPart::JointStates => {
                let joints = scratch.positions.iter().zip(&scratch.velocities);
                for (pair, (q, v)) in out.chunks_exact_mut(2).zip(joints) {
                    pair.copy_from_slice(&[*q as f32, *v as f32]);
                }
            }
            ObservationPart::GoalVector => {
                let (gx, gy) = to_head(goal.0 - p.x, goal.1 - p.y);
                out.copy_from_slice(&[gx as f32, gy as f32]);
            }
            ObservationPart::Heading => out.copy_from_slice(&[s as f32, c as f32]),
            ObservationPart::BaseVelocity => {
                let v = base.linear_velocity;
                let (vx, vy) = to_head(v.x, v.y);
                out.copy_from_slice(&[vx as f32, vy as f32]);
            }
            ObservationPart::WavePhase => {
                if let Some(phase) = wave_phase {
                    let (s, c) = phase.sin_cos();
                    out.copy_from_slice(&[s as f32, c as f32]);
                }
            }
            ObservationPart::WorldUp => {
                // The world's up in the head's own frame (not mirrored). The cube snake's joints
                // all turn about its z axis, so the head's up is the whole body's: on hills it
                // rolls over.
                let up = base
                    .pose
                    .orientation
                    .inverse_transform_vector(&nalgebra::Vector3::z());
                for (o, u) in out.iter_mut().zip(up.iter()) {
                    *o = *u as f32;
                }
            }
            ObservationPart::HeightMap => ground.write(map, [p.x, p.y, p.z], yaw, mirror, out),
        }
    }
    Ok(base)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Pose;
    use nalgebra::{UnitQuaternion, Vector3};
    use std::f64::consts::{FRAC_PI_2, PI};

    fn base(orientation: UnitQuaternion<f64>) -> BaseState {
        BaseState {
            pose: Pose {
                position: Vector3::zeros(),
                orientation,
            },
            linear_velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
        }
    }

    #[test]
    fn the_rolled_frame_keeps_its_heading_when_the_head_rolls_and_mirrors_upside_down() {
        for yaw in [-2.5, -0.7, 0.0, 0.4, 1.9, 3.0] {
            let level = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
            // Upright and level: the x axis's heading, not mirrored.
            let (h, m) = rolled_frame(&base(level));
            assert!((h - heading(&base(level))).abs() < 1e-12 && m == 1.0);
            // Rolled about the body's long (y) axis: on its side, the x axis points straight down
            // and `heading` has no meaning; upside down it is half a turn off. The rolled frame
            // keeps the heading, mirrored once the head's z points below the horizontal.
            for (roll, mirror) in [
                (0.3, 1.0),
                (1.4, 1.0),
                (1.7, -1.0),
                (PI, -1.0),
                (-2.0, -1.0),
            ] {
                let rolled = level * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), roll);
                let (h, m) = rolled_frame(&base(rolled));
                let off = (h - yaw + PI).rem_euclid(2.0 * PI) - PI;
                assert!(off.abs() < 1e-9, "yaw {yaw} roll {roll}: heading {h}");
                assert_eq!(m, mirror, "yaw {yaw} roll {roll}");
            }
            let upside_down = level * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), PI);
            let off = (heading(&base(upside_down)) - yaw).rem_euclid(2.0 * PI);
            assert!((off - PI).abs() < 1e-9, "{off}");
            // Pitched (the head raised about its x axis) short of vertical: still the heading.
            let pitched =
                level * UnitQuaternion::from_axis_angle(&Vector3::x_axis(), FRAC_PI_2 - 0.2);
            let (h, _) = rolled_frame(&base(pitched));
            assert!(((h - yaw + PI).rem_euclid(2.0 * PI) - PI).abs() < 1e-9);
        }
    }
}
