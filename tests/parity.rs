//! snake-core against pybullet 3.2.7, bit for bit.
//!
//! Every scenario is run by `reference/pybullet_reference.py` in pybullet and by snake-core here; the
//! state after every step (base pose and velocity, joint angles, velocities and motor torques) must
//! have identical bits. The system is chaotic (1e-12 m at the start grows to metres in 10 s), so
//! anything short of identical would not be parity.

use snakesim_tests::{assert_identical, run_ours, run_reference, Scenario};

const TEN_SECONDS: u64 = 2400;

fn check(tag: &str, scenarios: Vec<Scenario>) {
    let Some(tables) = run_reference(&scenarios, tag) else {
        return;
    };
    for (s, table) in scenarios.iter().zip(tables) {
        let ours = run_ours(s);
        assert_identical(&s.name, &table.header, &table.rows, &ours);
    }
}

#[test]
fn gait_resting_and_dropped_for_every_size_and_preset() {
    let mut scenarios = Vec::new();
    for joints in [1, 2, 5, 10, 20] {
        for preset in ["paper", "snakebot-gym"] {
            scenarios.push(Scenario::new(
                format!("rest-{joints}-{preset}"),
                joints,
                preset,
                [0.0, 0.0, 0.25, 0.0],
                TEN_SECONDS,
                "gait",
            ));
            scenarios.push(Scenario::new(
                format!("drop-{joints}-{preset}"),
                joints,
                preset,
                [0.3, -0.2, 0.5, 0.7],
                TEN_SECONDS,
                "gait",
            ));
        }
    }
    check("gait", scenarios);
}

#[test]
fn steered_gait() {
    let mut left = Scenario::new(
        "steer-left",
        8,
        "paper",
        [0.0, 0.0, 0.25, 0.0],
        TEN_SECONDS,
        "gait",
    );
    left.control.steering = Some(0.2);
    let mut right = Scenario::new(
        "steer-right",
        8,
        "snakebot-gym",
        [1.0, 2.0, 0.5, -0.4],
        TEN_SECONDS,
        "gait",
    );
    right.control.steering = Some(-0.2);
    check("steer", vec![left, right]);
}

#[test]
fn lying_still_under_zero_targets() {
    let scenarios = vec![
        Scenario::new(
            "still-5",
            5,
            "paper",
            [0.0, 0.0, 0.25, 0.0],
            TEN_SECONDS,
            "zero",
        ),
        Scenario::new(
            "still-10-drop",
            10,
            "snakebot-gym",
            [0.0, 0.0, 0.5, 1.0],
            TEN_SECONDS,
            "zero",
        ),
    ];
    check("still", scenarios.clone());
    // And it does lie still: resting on the plane, creeping by no more than the solver's own creep
    // (pybullet's snake creeps 0.4 mm over 10 s with 0.06 kg links and 3.2 mm with 1 kg links).
    for s in &scenarios {
        let rows = run_ours(s);
        let last = rows.last().unwrap();
        let drift = (last[2] - s.start[0]).hypot(last[3] - s.start[1]);
        assert!(drift < 5e-3, "{}: drifted {drift} m", s.name);
        assert!(
            (last[4] - 0.25).abs() < 1e-4,
            "{}: base height {}",
            s.name,
            last[4]
        );
    }
}

#[test]
fn each_control_mode() {
    let start = [0.0, 0.0, 0.25, 0.3];
    let mut position = Scenario::new("position-gains", 6, "paper", start, TEN_SECONDS, "position");
    position.control.kp = Some(0.3);
    position.control.kd = Some(0.6);
    position.control.force = Some(7.0);
    let mut clamped = Scenario::new(
        "position-clamped",
        6,
        "snakebot-gym",
        start,
        TEN_SECONDS,
        "position",
    );
    clamped.control.kp = Some(0.2);
    clamped.control.kd = Some(1.0);
    clamped.control.max_velocity = Some(2.0);
    clamped.control.target_velocity = Some(0.5);
    let mut velocity = Scenario::new("velocity", 6, "paper", start, TEN_SECONDS, "velocity");
    velocity.control.force = Some(5.0);
    let mut torque = Scenario::new("torque", 6, "paper", start, TEN_SECONDS, "torque");
    torque.control.force = Some(2.0);
    check("control", vec![position, clamped, velocity, torque]);
}

#[test]
fn each_friction_setting() {
    let settings: Vec<(&str, serde_json::Value)> = vec![
        ("lateral", serde_json::json!({"lateralFriction": 1.3})),
        (
            "anisotropic",
            serde_json::json!({"anisotropicFriction": [0.5, 0.05, 1.0]}),
        ),
        ("spinning", serde_json::json!({"spinningFriction": 0.05})),
        ("rolling", serde_json::json!({"rollingFriction": 0.02})),
        ("restitution", serde_json::json!({"restitution": 0.4})),
        ("anchor", serde_json::json!({"frictionAnchor": 1})),
        ("joint-damping", serde_json::json!({"jointDamping": 0.3})),
        (
            "body-damping",
            serde_json::json!({"linearDamping": 0.1, "angularDamping": 0.2}),
        ),
    ];
    let scenarios = settings
        .into_iter()
        .map(|(name, dynamics)| {
            let mut s = Scenario::new(
                format!("friction-{name}"),
                5,
                "paper",
                [0.0, 0.0, 0.5, 0.2],
                TEN_SECONDS,
                "gait",
            );
            s.dynamics = serde_json::from_value(dynamics).unwrap();
            s
        })
        .collect();
    check("friction", scenarios);
}
