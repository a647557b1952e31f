//! The state primitives the media and calibration build on, against pybullet 3.2.7 bit for bit:
//! external forces and torques (`applyExternalForce`/`applyExternalTorque`, WORLD_FRAME), state resets
//! (`resetBasePositionAndOrientation` + `resetBaseVelocity`, `resetJointState`) and link velocities
//! (`getLinkState(computeLinkVelocity=1)`). `reference/state_reference.py` runs the same script.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde::Serialize;
use snake_core::{BaseState, Gait, LateralUndulation, Pose, Preset, Snake, StartPose};
use snakesim_tests::{assert_identical, read_csv, run_reference_script};

const DT: f64 = 1.0 / 240.0;
const JOINTS: usize = 10;
const STEPS: usize = 480;
const RESET_STEP: usize = 200;

#[derive(Serialize)]
struct Spec {
    steps: usize,
}

fn reset_joint(j: usize) -> (f64, f64) {
    let j = j as f64;
    (0.3 * (0.7 * j).sin(), 0.5 * (1.3 * j).cos())
}

/// The external force on link 3, its point's offset from the link's centre, the base torque.
fn push(k: usize) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let t = k as f64 * DT;
    (
        [3.0 * (2.0 * t).sin(), 1.5, 2.0 * (3.0 * t).cos()],
        [0.1, -0.2, 0.05],
        [0.0, 0.0, 0.4 * t.cos()],
    )
}

fn run_ours() -> Vec<Vec<f64>> {
    let config = Preset::Paper.config(JOINTS);
    let start = StartPose {
        x: 0.0,
        y: 0.0,
        z: 0.25,
        yaw: 0.0,
    };
    let mut snake = Snake::new(&config, start).expect("snake builds");
    let body = snake.body();
    let mut gait = LateralUndulation::default();
    let mut targets = vec![0.0; JOINTS];
    let xyz = [0.02f64, -0.015, 0.34];
    let w = (1.0 - (xyz[0] * xyz[0] + xyz[1] * xyz[1] + xyz[2] * xyz[2])).sqrt();
    let reset = BaseState {
        pose: Pose {
            position: Vector3::new(0.3, -0.2, 0.4),
            orientation: UnitQuaternion::new_unchecked(Quaternion::new(w, xyz[0], xyz[1], xyz[2])),
        },
        linear_velocity: Vector3::new(0.2, -0.1, 0.05),
        angular_velocity: Vector3::new(0.0, 0.1, 0.3),
    };
    let mut rows = Vec::with_capacity(STEPS);
    for step in 1..=STEPS {
        let k = step - 1;
        let world = snake.world_mut();
        if k == RESET_STEP {
            world.reset_base_state(body, &reset).unwrap();
            let (q, qd): (Vec<f64>, Vec<f64>) = (0..JOINTS).map(reset_joint).unzip();
            world.reset_joint_states(body, &q, &qd).unwrap();
        }
        gait.next_targets(&mut targets);
        world
            .set_position_targets(body, &targets, 10.0, 0.1, 1.0)
            .unwrap();
        let (force, offset, torque) = push(k);
        let centre = world.link_poses(body).unwrap()[3].position;
        world
            .apply_external_force(
                body,
                Some(3),
                Vector3::from(force),
                centre + Vector3::from(offset),
            )
            .unwrap();
        world
            .apply_external_torque(body, None, Vector3::from(torque))
            .unwrap();
        snake.step().expect("step");
        let base = snake.base_state().unwrap();
        let joints = snake.joint_states().unwrap();
        let q = base.pose.orientation.coords;
        let mut row = vec![step as f64, step as f64 * DT];
        row.extend(base.pose.position.iter());
        row.extend([q.x, q.y, q.z, q.w]);
        row.extend(joints.iter().map(|j| j.position));
        row.extend(base.linear_velocity.iter());
        row.extend(base.angular_velocity.iter());
        row.extend(joints.iter().map(|j| j.velocity));
        row.extend(joints.iter().map(|j| j.motor_torque));
        for v in snake.world().link_velocities(body).unwrap() {
            row.extend(v.linear.iter());
            row.extend(v.angular.iter());
        }
        rows.push(row);
    }
    rows
}

#[test]
fn forces_resets_and_link_velocities_match_pybullet() {
    let Some(dir) = run_reference_script("state_reference.py", &Spec { steps: STEPS }, "state")
    else {
        return;
    };
    let reference = read_csv(&dir.join("state.csv"));
    let ours = run_ours();
    assert_identical("state", &reference.header, &reference.rows, &ours);
    // The pushes and the reset moved the snake: a run without them would not pass this by accident.
    let z = reference.header.iter().position(|h| h == "base_z").unwrap();
    assert!(
        reference.rows[RESET_STEP][z] > 0.3,
        "the reset lifted the base"
    );
}

#[test]
fn bad_state_is_refused() {
    let mut snake = Snake::new(&Preset::Paper.config(3), StartPose::resting(0.25)).unwrap();
    let body = snake.body();
    let world = snake.world_mut();
    let err = world
        .reset_joint_states(body, &[0.0; 2], &[0.0; 3])
        .unwrap_err();
    assert!(err.to_string().contains("3 joints"), "{err}");
    let err = world
        .reset_joint_states(body, &[0.0, f64::NAN, 0.0], &[0.0; 3])
        .unwrap_err();
    assert!(err.to_string().contains("finite"), "{err}");
    let err = world
        .apply_external_force(body, Some(7), Vector3::zeros(), Vector3::zeros())
        .unwrap_err();
    assert!(err.to_string().contains("no link 7"), "{err}");
    let err = world
        .apply_external_torque(body, None, Vector3::new(f64::INFINITY, 0.0, 0.0))
        .unwrap_err();
    assert!(err.to_string().contains("finite"), "{err}");
}
