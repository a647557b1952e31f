//! Writing the observation vector.

use super::config::ObservationLayout;
use super::height_map::{GroundProbe, HEIGHT_MAP_LEN};
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

/// Fills `obs` (of the layout's length, plus 2 with a wave phase) from the snake's current state and,
/// for the terrain layout, from `ground`; returns the base state.
///
/// Every value is the simulator's double cast to `float32` (round to nearest), as the paper's
/// `np.array(...).astype(np.float32)` does.
pub(crate) fn write(
    layout: ObservationLayout,
    snake: &dyn Simulation,
    goal: (f64, f64),
    wave_phase: Option<f64>,
    ground: &GroundProbe,
    scratch: &mut JointScratch,
    obs: &mut [f32],
) -> Result<BaseState> {
    let base = snake.base_state()?;
    snake.read_joints(&mut scratch.positions, &mut scratch.velocities)?;
    let p = base.pose.position;
    obs[0] = p.x as f32;
    obs[1] = p.y as f32;
    let n = scratch.positions.len();
    for j in 0..n {
        obs[2 + 2 * j] = scratch.positions[j] as f32;
        obs[3 + 2 * j] = scratch.velocities[j] as f32;
    }
    if layout.is_extended() {
        let yaw = heading(&base);
        let (s, c) = yaw.sin_cos();
        // World vectors into the head frame: rotation by -yaw about z.
        let to_head = |vx: f64, vy: f64| (c * vx + s * vy, -s * vx + c * vy);
        let (gx, gy) = to_head(goal.0 - p.x, goal.1 - p.y);
        let v = base.linear_velocity;
        let (vx, vy) = to_head(v.x, v.y);
        let extra = &mut obs[2 + 2 * n..2 + 2 * n + 6];
        extra.copy_from_slice(&[
            gx as f32, gy as f32, s as f32, c as f32, vx as f32, vy as f32,
        ]);
        if let Some(phase) = wave_phase {
            let (s, c) = phase.sin_cos();
            obs[2 + 2 * n + 6] = s as f32;
            obs[2 + 2 * n + 7] = c as f32;
        }
        if layout == ObservationLayout::Terrain {
            // After the wave's phase where there is one: the world's up in the head frame, then the
            // map. The cube snake's joints all turn about its z axis, so the head's up is the whole
            // body's: on hills it rolls over, and upside down its steering is mirrored.
            let at = obs.len() - HEIGHT_MAP_LEN;
            let up = base
                .pose
                .orientation
                .inverse_transform_vector(&nalgebra::Vector3::z());
            for (o, u) in obs[at - 3..at].iter_mut().zip(up.iter()) {
                *o = *u as f32;
            }
            ground.write([p.x, p.y, p.z], yaw, &mut obs[at..]);
        }
    }
    Ok(base)
}
