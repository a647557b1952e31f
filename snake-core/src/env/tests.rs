//! Unit tests of the env: bad input, configuration, seeding, rewards and episode ends.

use super::*;
use crate::{Error, Preset};
use std::f64::consts::TAU;

fn env(config: EnvConfig) -> SnakeEnv {
    SnakeEnv::new(config).expect("valid config")
}

fn invalid_message(result: Result<impl std::fmt::Debug>) -> String {
    match result {
        Err(Error::InvalidArgument(m)) => m.to_string(),
        other => panic!("expected InvalidArgument, got {other:?}"),
    }
}

#[test]
fn step_before_reset_is_an_error() {
    let mut e = env(EnvConfig::default());
    let m = invalid_message(e.step(&[0.0f32; 5]));
    assert!(m.contains("reset"), "{m}");
}

#[test]
fn bad_actions_are_errors_and_leave_the_episode_running() {
    let mut e = env(EnvConfig::default());
    e.reset(Some(1), ResetOptions::default()).unwrap();
    let m = invalid_message(e.step(&[0.0f32; 4]));
    assert!(m.contains("5 values") && m.contains("got 4"), "{m}");
    let m = invalid_message(e.step(&[0.0f32; 6]));
    assert!(m.contains("got 6"), "{m}");
    let m = invalid_message(e.step(&[0.0, 0.0, f32::NAN, 0.0, 0.0]));
    assert!(m.contains("action[2]"), "{m}");
    let m = invalid_message(e.step(&[0.0, 0.0, 0.0, f64::INFINITY, 0.0]));
    assert!(m.contains("action[3]"), "{m}");
    let mut obs = vec![0.0; 3];
    let m = invalid_message(e.step_into(&[0.0f32; 5], &mut obs));
    assert!(m.contains("observation buffer"), "{m}");
    // None of that moved the snake or counted a step.
    assert_eq!(e.episode_step(), 0);
    assert!(e.step(&[0.0f32; 5]).is_ok());
    assert_eq!(e.episode_step(), 1);
}

#[test]
fn bad_reset_options_are_errors() {
    let mut e = env(EnvConfig::default());
    let goal = ResetOptions {
        goal: Some((f64::NAN, 0.0)),
        ..ResetOptions::default()
    };
    assert!(invalid_message(e.reset(None, goal)).contains("goal"));
    let start = ResetOptions {
        start: Some(StartPose {
            x: 0.0,
            y: f64::INFINITY,
            z: 0.5,
            yaw: 0.0,
        }),
        ..ResetOptions::default()
    };
    assert!(invalid_message(e.reset(None, start)).contains("start"));
    let mut obs = vec![0.0; 11];
    assert!(invalid_message(e.reset_into(None, ResetOptions::default(), &mut obs)).contains("12"));
    assert!(e.needs_reset());
}

#[test]
fn bad_configs_name_the_field() {
    let cases: Vec<(EnvConfig, &str)> = vec![
        (EnvConfig::with_preset(Preset::Paper, 0), "snake.joints"),
        (
            EnvConfig {
                goal: (f64::NAN, 1.0),
                ..EnvConfig::default()
            },
            "goal",
        ),
        (
            EnvConfig {
                goal_radius: -1.0,
                ..EnvConfig::default()
            },
            "goal_radius",
        ),
        (
            EnvConfig {
                max_episode_steps: 0,
                ..EnvConfig::default()
            },
            "max_episode_steps",
        ),
        (
            EnvConfig {
                physics_steps_per_env_step: 0,
                ..EnvConfig::default()
            },
            "physics_steps_per_env_step",
        ),
        (
            EnvConfig {
                start: StartDistribution {
                    x: [0.5, -0.5],
                    ..StartDistribution::default()
                },
                ..EnvConfig::default()
            },
            "start.x",
        ),
        (
            EnvConfig {
                start: StartDistribution {
                    yaw: [0.0, f64::INFINITY],
                    ..StartDistribution::default()
                },
                ..EnvConfig::default()
            },
            "start.yaw",
        ),
        (
            EnvConfig {
                action_scale: 0.0,
                ..EnvConfig::default()
            },
            "action_scale",
        ),
        (
            EnvConfig {
                reward: RewardConfig {
                    energy_weight: f64::NAN,
                    ..RewardConfig::default()
                },
                ..EnvConfig::default()
            },
            "reward.energy_weight",
        ),
        (
            EnvConfig {
                height_map: HeightMap {
                    side: 9,
                    spacing: 0.75,
                },
                ..EnvConfig::goal_task(Preset::Paper, 5)
            },
            "height_map",
        ),
    ];
    for (config, field) in cases {
        let m = invalid_message(SnakeEnv::new(config));
        assert!(m.starts_with(field), "error for {field}: {m}");
        assert!(!m.contains('\n'), "one line: {m}");
    }
}

#[test]
fn config_serde_defaults_and_unknown_fields() {
    let config: EnvConfig = serde_json::from_str(
        r#"{"goal": [1.0, -5.0], "observation": "extended", "start": {"z": 0.25}}"#,
    )
    .unwrap();
    assert_eq!(config.goal, (1.0, -5.0));
    assert_eq!(config.observation, ObservationLayout::Extended);
    assert_eq!(config.start.z, 0.25);
    assert_eq!(config.start.x, [-0.5, 0.5]);
    assert_eq!(config.max_episode_steps, 5000);
    let round_trip: EnvConfig =
        serde_json::from_str(&serde_json::to_string(&config).unwrap()).unwrap();
    assert_eq!(round_trip, config);
    let err = serde_json::from_str::<EnvConfig>(r#"{"goal_raduis": 2.0}"#).unwrap_err();
    assert!(err.to_string().contains("goal_raduis"), "{err}");
    let err = serde_json::from_str::<EnvConfig>(r#"{"reward": {"progress": 1.0}}"#).unwrap_err();
    assert!(err.to_string().contains("progress"), "{err}");
    let config: EnvConfig =
        serde_json::from_str(r#"{"reward": {"distance_precision": "float64"}}"#).unwrap();
    assert_eq!(config.reward.distance_precision, DistancePrecision::Float64);
}

#[test]
fn seeding_reproduces_and_none_continues_the_stream() {
    let mut a = env(EnvConfig::default());
    let mut b = env(EnvConfig::default());
    let (obs_a, info_a) = a.reset(Some(3), ResetOptions::default()).unwrap();
    let (obs_b, info_b) = b.reset(Some(3), ResetOptions::default()).unwrap();
    assert_eq!(obs_a, obs_b);
    assert_eq!(info_a.start, info_b.start);
    let s = info_a.start;
    assert!(
        (-0.5..0.5).contains(&s.x) && (-0.5..0.5).contains(&s.y) && (-0.2..0.2).contains(&s.yaw)
    );
    assert_eq!(s.z, 0.5);
    let (_, next_a) = a.reset(None, ResetOptions::default()).unwrap();
    let (_, next_b) = b.reset(None, ResetOptions::default()).unwrap();
    assert_eq!(next_a.start, next_b.start);
    assert_ne!(next_a.start, info_a.start);
    let (_, other) = b.reset(Some(4), ResetOptions::default()).unwrap();
    assert_ne!(other.start, info_a.start);
}

#[test]
fn options_fix_start_and_goal_for_one_episode() {
    let mut e = env(EnvConfig::default());
    let start = StartPose {
        x: 1.0,
        y: 2.0,
        z: 0.5,
        yaw: 0.3,
    };
    let options = ResetOptions {
        start: Some(start),
        goal: Some((3.0, 4.0)),
    };
    let (obs, info) = e.reset(Some(0), options).unwrap();
    assert_eq!(info.start, start);
    assert_eq!(info.goal, (3.0, 4.0));
    assert_eq!(e.goal(), (3.0, 4.0));
    // One physics step of free fall from z = 0.5: x and y have not moved (to float32 precision).
    assert!(
        (obs[0] - 1.0).abs() < 1e-6 && (obs[1] - 2.0).abs() < 1e-6,
        "{obs:?}"
    );
    let (_, info) = e.reset(None, ResetOptions::default()).unwrap();
    assert_eq!(info.goal, (0.0, -10.0));
}

#[test]
fn paper_reward_is_minus_the_float32_distance() {
    let mut e = env(EnvConfig::snakebot_gym(3));
    let (obs, info) = e.reset(Some(9), ResetOptions::default()).unwrap();
    assert_eq!(obs.len(), 8);
    assert_eq!(
        info.distance,
        paper_distance((0.0, -10.0), obs[0], obs[1], DistancePrecision::Float32)
    );
    for k in 0..50 {
        let a = (k as f32 * 0.1).sin();
        let step = e.step(&[a, -a, a]).unwrap();
        let d = python_hypot((0.0 - step.obs[0]) as f64, (-10.0 - step.obs[1]) as f64);
        assert_eq!(step.reward.to_bits(), (-d).to_bits());
        assert_eq!(step.info.distance, d);
        assert_eq!(step.info.reward_terms.goal, step.reward);
        assert_eq!(step.info.episode_step, k + 1);
    }
}

#[test]
fn reaching_the_goal_terminates_with_the_success_reward() {
    let mut e = env(EnvConfig {
        goal_radius: 2.0,
        ..EnvConfig::default()
    });
    let options = ResetOptions {
        goal: Some((0.0, -1.0)),
        ..ResetOptions::default()
    };
    let (_, info) = e.reset(Some(0), options).unwrap();
    assert!(
        info.distance < 2.0 && !info.success,
        "a reset never succeeds"
    );
    let step = e.step(&[0.0f32; 5]).unwrap();
    assert!(step.terminated && !step.truncated && step.info.success);
    assert_eq!(step.reward, 100.0);
    assert_eq!(step.info.reward_terms.goal, 100.0);
    let m = invalid_message(e.step(&[0.0f32; 5]));
    assert!(m.contains("ended"), "{m}");
    assert!(e.needs_reset());
    e.reset(None, ResetOptions::default()).unwrap();
    assert!(e.step(&[0.0f32; 5]).is_ok());
}

#[test]
fn truncation_after_max_episode_steps() {
    let mut e = env(EnvConfig {
        max_episode_steps: 4,
        ..EnvConfig::default()
    });
    e.reset(Some(0), ResetOptions::default()).unwrap();
    let mut total = 0.0;
    for k in 1..=4 {
        let step = e.step(&[0.2f32; 5]).unwrap();
        total += step.reward;
        assert!(!step.terminated);
        assert_eq!(step.truncated, k == 4);
        assert_eq!(step.info.episode_return, total);
    }
    assert!(e.step(&[0.2f32; 5]).is_err());
}

#[test]
fn actions_are_clipped_and_scaled() {
    let run = |scale: f64, action: f64| {
        let mut e = env(EnvConfig {
            action_scale: scale,
            ..EnvConfig::default()
        });
        e.reset(Some(5), ResetOptions::default()).unwrap();
        (0..30)
            .map(|_| e.step(&[action; 5]).unwrap().obs)
            .last()
            .unwrap()
    };
    assert_eq!(run(1.0, 7.0), run(1.0, 1.0));
    assert_eq!(run(0.5, 1.0), run(1.0, 0.5));
    assert_ne!(run(1.0, 1.0), run(1.0, 0.5));
}

#[test]
fn f32_and_f64_actions_and_step_into_agree() {
    let mut a = env(EnvConfig::default());
    let mut b = env(EnvConfig::default());
    a.reset(Some(11), ResetOptions::default()).unwrap();
    b.reset(Some(11), ResetOptions::default()).unwrap();
    let mut obs = vec![0.0; b.observation_dim()];
    for k in 0..40 {
        let action: Vec<f32> = (0..5).map(|j| ((k * 5 + j) as f32 * 0.37).sin()).collect();
        let action64: Vec<f64> = action.iter().map(|&v| v as f64).collect();
        let sa = a.step(&action).unwrap();
        let sb = b.step_into(&action64, &mut obs).unwrap();
        assert_eq!(sa.obs, obs);
        assert_eq!(sa.reward.to_bits(), sb.reward.to_bits());
        assert_eq!(sa.info, sb.info);
    }
}

#[test]
fn shaping_terms_add_up_and_are_reported() {
    let config = EnvConfig {
        reward: RewardConfig {
            progress_weight: 2.0,
            smoothness_weight: 0.5,
            energy_weight: 0.01,
            ..RewardConfig::default()
        },
        ..EnvConfig::default()
    };
    let mut e = env(config);
    let (_, info) = e.reset(Some(2), ResetOptions::default()).unwrap();
    let mut previous = info.distance;
    let mut previous_targets = [0.0f64; 5];
    for k in 0..60 {
        let action: Vec<f32> = (0..5)
            .map(|j| (k as f32 * 0.2 + j as f32).sin() * 1.3)
            .collect();
        let step = e.step(&action).unwrap();
        let t = step.info.reward_terms;
        assert_eq!(t.goal, -step.info.distance);
        assert_eq!(t.progress, 2.0 * (previous - step.info.distance));
        let targets: Vec<f64> = action
            .iter()
            .map(|&a| (a as f64).clamp(-1.0, 1.0))
            .collect();
        let change: f64 = targets
            .iter()
            .zip(&previous_targets)
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        assert_eq!(t.smoothness, -0.5 * change);
        assert!(t.energy <= 0.0);
        assert_eq!(step.reward, t.goal + t.progress + t.smoothness + t.energy);
        previous = step.info.distance;
        previous_targets.copy_from_slice(&targets);
    }
    // The motors do work while the snake wiggles.
    assert!(
        e.step(&[1.0f32, -1.0, 1.0, -1.0, 1.0])
            .unwrap()
            .info
            .reward_terms
            .energy
            < 0.0
    );
}

#[test]
fn extended_observation() {
    let mut e = env(EnvConfig {
        observation: ObservationLayout::Extended,
        goal: (3.0, -4.0),
        ..EnvConfig::default()
    });
    assert_eq!(e.observation_dim(), 18);
    let start = StartPose {
        x: 1.0,
        y: 1.0,
        z: 0.25,
        yaw: 0.0,
    };
    let options = ResetOptions {
        start: Some(start),
        ..ResetOptions::default()
    };
    let (obs, _) = e.reset(None, options).unwrap();
    // Heading 0: the head frame is the world frame.
    let close = |a: f32, b: f32| (a - b).abs() < 1e-4;
    assert!(close(obs[12], 2.0) && close(obs[13], -5.0), "{obs:?}");
    assert!(close(obs[14], 0.0) && close(obs[15], 1.0), "{obs:?}");
    // A quarter turn: the goal vector turns by -90 degrees.
    let options = ResetOptions {
        start: Some(StartPose {
            yaw: std::f64::consts::FRAC_PI_2,
            ..start
        }),
        ..ResetOptions::default()
    };
    let (obs, _) = e.reset(None, options).unwrap();
    assert!(close(obs[12], -5.0) && close(obs[13], -2.0), "{obs:?}");
    assert!(close(obs[14], 1.0) && close(obs[15], 0.0), "{obs:?}");
    let step = e.step(&[0.0f32; 5]).unwrap();
    assert_eq!(step.obs.len(), 18);
    assert!(step.obs.iter().all(|v| v.is_finite()));
}

#[test]
fn several_physics_steps_per_env_step() {
    let mut e = env(EnvConfig {
        physics_steps_per_env_step: 4,
        ..EnvConfig::default()
    });
    let (_, info) = e.reset(Some(0), ResetOptions::default()).unwrap();
    assert_eq!(info.time, 1.0 / 240.0);
    let step = e.step(&[0.1f32; 5]).unwrap();
    assert_eq!(step.info.time, 5.0 / 240.0);
}

/// Values beyond `crate::limits` are refused with the field named; inside them every output is finite.
#[test]
fn limits_refuse_what_would_not_be_finite_or_resolved() {
    use crate::limits::MAX_POSITION;
    let refused = |config: EnvConfig, needle: &str| {
        let e = SnakeEnv::new(config).expect_err("refused").to_string();
        assert!(e.contains(needle), "'{e}' should mention {needle}");
    };
    refused(
        EnvConfig {
            goal: (1e308, 0.0),
            ..EnvConfig::default()
        },
        "goal: must have |x| and |y| at most 10000",
    );
    let mut weights = EnvConfig::default();
    weights.reward.energy_weight = 1e308;
    refused(weights, "reward.energy_weight: must be in");
    refused(
        EnvConfig {
            physics_steps_per_env_step: u32::MAX,
            ..EnvConfig::default()
        },
        "physics_steps_per_env_step: must be in [1, 240]",
    );
    let mut start = EnvConfig::default();
    start.start.y = [0.0, 1e18];
    refused(start, "start.y: must lie within");

    let mut env = SnakeEnv::new(EnvConfig::default()).unwrap();
    for (x, needle) in [(1e39, "start must have"), (f64::MAX, "start must have")] {
        let options = ResetOptions {
            start: Some(StartPose {
                x,
                y: 0.0,
                z: 0.5,
                yaw: 0.0,
            }),
            goal: None,
        };
        let e = env.reset(Some(0), options).unwrap_err().to_string();
        assert!(e.contains(needle), "{e}");
    }
    let far_goal = ResetOptions {
        start: None,
        goal: Some((0.0, -1e39)),
    };
    assert!(env.reset(Some(0), far_goal).is_err());

    // At the edge of the limits the snake still rests on the plane and everything is finite.
    let mut config = EnvConfig {
        goal: (-MAX_POSITION, MAX_POSITION),
        ..EnvConfig::default()
    };
    config.reward.distance_weight = crate::limits::MAX_REWARD_WEIGHT;
    config.reward.energy_weight = crate::limits::MAX_REWARD_WEIGHT;
    let mut env = SnakeEnv::new(config).unwrap();
    let edge = ResetOptions {
        start: Some(StartPose {
            x: MAX_POSITION,
            y: -MAX_POSITION,
            z: 0.5,
            yaw: 0.0,
        }),
        goal: None,
    };
    env.reset(Some(0), edge).unwrap();
    for k in 0..240 {
        let a = (k as f32 * 0.1).sin();
        let step = env.step(&[a, -a, a, -a, a]).unwrap();
        assert!(step.reward.is_finite() && step.obs.iter().all(|v| v.is_finite()));
    }
    let poses = env.snake().unwrap().cube_poses().unwrap();
    assert!(
        poses.iter().all(|p| (p.position.z - 0.25).abs() < 0.01),
        "resting on the plane"
    );
}

/// The physics trace records every physics step's state without changing a bit of the episode.
#[test]
fn physics_trace_records_every_physics_step_and_changes_nothing() {
    for config in [
        EnvConfig::goal_task(Preset::Paper, 5),
        EnvConfig {
            physics_steps_per_env_step: 3,
            ..EnvConfig::snakebot_gym(4)
        },
    ] {
        let per_step = config.physics_steps_per_env_step as usize;
        let n = config.joints();
        let angles = config
            .observation_structure()
            .range(ObservationPart::JointStates)
            .unwrap();
        let mut plain = env(config.clone());
        let mut traced = env(config.clone());
        assert!(traced.physics_trace().is_none());
        traced.set_physics_trace(true);
        assert!(traced.physics_trace().unwrap().is_empty());
        let (obs_a, _) = plain.reset(Some(3), ResetOptions::default()).unwrap();
        let (obs_b, _) = traced.reset(Some(3), ResetOptions::default()).unwrap();
        assert_eq!(obs_a, obs_b);
        let trace = traced.physics_trace().unwrap();
        assert_eq!((trace.len(), trace.steps[0], trace.joints), (1, 1, n));
        assert!(trace.targets.iter().all(|t| t.is_nan()));
        let mut work = 0.0;
        for k in 0..40u64 {
            let action: Vec<f64> = (0..plain.action_dim())
                .map(|j| ((k as f64) * 0.3 + j as f64).sin())
                .collect();
            let a = plain.step(&action).unwrap();
            let b = traced.step(&action).unwrap();
            assert_eq!(a, b, "step {k}");
            let trace = traced.physics_trace().unwrap();
            let snake = traced.snake().unwrap();
            assert_eq!(trace.len(), per_step);
            let first = 2 + k * per_step as u64;
            assert_eq!(
                trace.steps,
                (first..first + per_step as u64).collect::<Vec<_>>()
            );
            assert_eq!(*trace.times.last().unwrap(), b.info.time);
            assert_eq!(trace.poses.len(), per_step * (n + 1) * 7);
            // The last row is the state the env's snake is in now.
            let last = &trace.poses[(per_step - 1) * (n + 1) * 7..];
            for (c, pose) in snake.cube_poses().unwrap().iter().enumerate() {
                let q = pose.orientation.coords;
                let p = pose.position;
                assert_eq!(
                    &last[7 * c..7 * c + 7],
                    &[p.x, p.y, p.z, q.x, q.y, q.z, q.w]
                );
            }
            for (j, state) in snake.joint_states().unwrap().iter().enumerate() {
                let row = (per_step - 1) * n + j;
                assert_eq!(trace.positions[row], state.position);
                assert_eq!(trace.velocities[row], state.velocity);
                assert_eq!(trace.torques[row], state.motor_torque);
                assert_eq!(b.obs[angles.start + 2 * j], state.position as f32);
            }
            if config.action.mode == ActionMode::Joints {
                let clipped = action
                    .iter()
                    .map(|a| a.clamp(-1.0, 1.0) * config.action_scale);
                for (row, target) in trace
                    .targets
                    .chunks(n)
                    .flat_map(|r| r.iter().zip(clipped.clone()))
                {
                    assert_eq!(*row, target);
                }
            } else {
                assert!(trace.targets.iter().all(|t| t.is_finite()));
            }
            // The env's work is the sum over these physics steps of |torque x velocity| dt.
            work += trace
                .torques
                .iter()
                .zip(&trace.velocities)
                .map(|(t, v)| (t * v).abs())
                .sum::<f64>()
                * config.snake.dt;
            assert!(
                (work - b.info.work).abs() <= 1e-12 * work.max(1.0),
                "{work} {}",
                b.info.work
            );
            if b.terminated || b.truncated {
                break;
            }
        }
        traced.set_physics_trace(false);
        assert!(traced.physics_trace().is_none());
    }
}

/// yaw-pitch-16's robot-file wave (the lifted lateral wave) in the goal task: steering 0 crawls
/// straight ahead, +1 turns the robot clockwise and -1 counter-clockwise, the envs' convention for the
/// sine wave too (the driver flips the sign of the yaw offset; see `gait::steered`). Directions of
/// travel are taken over whole 2 s gait cycles, from the end of the second cycle to the eighth.
#[test]
fn robot_wave_steers_the_envs_way() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/yaw-pitch-16.yaml");
    let config = EnvConfig {
        robot: Some(crate::RobotRef::load(&path).unwrap()),
        max_episode_steps: 10_000,
        goal: (500.0, 0.0),
        goal_distribution: None,
        ..EnvConfig::goal_task(Preset::Paper, 5)
    };
    let start = StartPose {
        x: 0.0,
        y: 0.0,
        z: 0.0254,
        yaw: 0.0,
    };
    let turn_and_speed = |steering: f64| {
        let mut e = env(config.clone());
        let options = ResetOptions {
            start: Some(start),
            ..ResetOptions::default()
        };
        let (mut obs, _) = e.reset(None, options).unwrap();
        let mut at_cycle = vec![(obs[0] as f64, obs[1] as f64)];
        // 60 env steps of 8 physics steps of 1/240 s: one 2 s cycle.
        for k in 0..8 * 60 {
            obs = e.step(&[steering, 0.0, 0.0]).unwrap().obs;
            if k % 60 == 59 {
                at_cycle.push((obs[0] as f64, obs[1] as f64));
            }
        }
        let direction = |c: usize| {
            let ((x0, y0), (x1, y1)) = (at_cycle[c], at_cycle[c + 1]);
            (y1 - y0).atan2(x1 - x0)
        };
        let mut turned = 0.0;
        for c in 1..7 {
            let d = direction(c + 1) - direction(c);
            turned +=
                (d + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        }
        let ((x0, y0), (x1, y1)) = (at_cycle[1], at_cycle[7]);
        (
            turned.to_degrees(),
            ((x1 - x0).hypot(y1 - y0)) / 12.0,
            direction(1).to_degrees(),
        )
    };
    let (straight, speed, heading) = turn_and_speed(0.0);
    assert!(
        straight.abs() < 15.0,
        "unsteered it turned {straight} degrees"
    );
    assert!(speed > 0.12, "unsteered it crawled {speed} m/s");
    assert!(
        (heading + 90.0).abs() < 20.0,
        "head first is -y; it went {heading} degrees"
    );
    let (right, _, _) = turn_and_speed(1.0);
    let (left, _, _) = turn_and_speed(-1.0);
    assert!(right < -120.0, "steering +1 turned {right} degrees");
    assert!(left > 120.0, "steering -1 turned {left} degrees");
}

#[test]
fn terrain_observation_is_the_extended_one_then_the_ground_under_and_around_the_head() {
    use crate::{HEIGHT_MAP_LEN, HEIGHT_MAP_SIDE};
    let rough = EnvConfig::rough_task(Preset::Paper, 10);
    let mut extended = env(rough.clone());
    let mut terrain = env(EnvConfig {
        observation: ObservationLayout::Terrain,
        ..rough
    });
    let dim = extended.observation_dim();
    assert_eq!(terrain.observation_dim(), dim + 3 + HEIGHT_MAP_LEN);
    // The paper's values and the wave's phase are the extended layout's; the goal and the velocity
    // are the same world vectors in the rolled head frame (observation::rolled_frame): turned by
    // its heading and, upside down, mirrored.
    // Where the goal vector starts: after the base position and the joints' pairs.
    let n = terrain
        .config()
        .observation_structure()
        .offset(ObservationPart::GoalVector)
        .unwrap();
    let same = |a: &[f32], b: &[f32]| {
        assert_eq!(a[..n], b[..n]);
        assert_eq!(a[n + 6..dim], b[n + 6..dim]);
        let mirror = if b[dim + 2] < 0.0 { -1.0 } else { 1.0 };
        for at in [n, n + 4] {
            let world = |v: &[f32], m: f32| {
                let heading = (v[n + 2] as f64).atan2(v[n + 3] as f64);
                ((v[at + 1] as f64).atan2((m * v[at]) as f64) + heading).rem_euclid(TAU)
            };
            let off = (world(a, 1.0) - world(b, mirror)).abs();
            assert!(
                off.min(TAU - off) < 1e-5,
                "{:?} {:?}",
                &a[n..n + 6],
                &b[n..n + 6]
            );
            let norm = |v: &[f32]| (v[at] as f64).hypot(v[at + 1] as f64);
            assert!((norm(a) - norm(b)).abs() < 1e-5 * norm(a).max(1.0));
        }
    };
    let (a, _) = extended.reset(Some(6), ResetOptions::default()).unwrap();
    let (b, _) = terrain.reset(Some(6), ResetOptions::default()).unwrap();
    same(&a, &b);
    // Dropped upright: the world's up is the head's z axis.
    assert!(b[dim + 2] > 0.99, "{:?}", &b[dim..dim + 3]);
    let mut last = b;
    let mut upside_down = 0;
    for k in 0..300 {
        // A full wave, steered hard one way then the other: it rolls over on these hills.
        let action = [if k % 120 < 60 { 1.0f32 } else { -1.0 }, 1.0, 1.0];
        let sa = extended.step(&action).unwrap();
        let sb = terrain.step(&action).unwrap();
        same(&sa.obs, &sb.obs);
        upside_down += usize::from(sb.obs[dim + 2] < 0.0);
        last = sb.obs;
    }
    // The mirrored frame was checked too: this episode spends 132 of its 300 steps upside down.
    assert!(
        upside_down > 60,
        "upside down in {upside_down} of 300 steps"
    );
    let up = &last[dim..dim + 3];
    let norm = up.iter().map(|u| u * u).sum::<f32>().sqrt();
    assert!((norm - 1.0).abs() < 1e-5, "{up:?}");
    let map = &last[dim + 3..];
    // The cube snake's yaw joints keep it straight in the vertical plane, so on hills its head is
    // often off the ground (height_map's tests check the map where it rests): below it, not above.
    let c = HEIGHT_MAP_SIDE / 2;
    assert!(map[c * HEIGHT_MAP_SIDE + c] < -0.2, "{map:?}");
    // On hills up to 1.2 m the map is not flat.
    let (lo, hi) = map
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    assert!(hi - lo > 0.05, "{map:?}");
}

#[test]
fn the_rough_task_ends_an_episode_whose_head_leaves_the_ground() {
    // A flat heightfield reaching 0.5 m beyond a goal 5 m behind the start: the unsteered wave
    // crawls ahead (-y) and off the grid's edge at y = -5.5 m.
    let mut config = EnvConfig::rough_task(Preset::Paper, 10);
    let rough = config.terrain.as_mut().unwrap().rough.as_mut().unwrap();
    (rough.amplitude, rough.hills_amplitude, rough.margin) = (0.0, 0.0, 0.5);
    let mut e = env(config);
    let start = StartPose {
        x: 0.0,
        y: 0.0,
        z: 0.5,
        yaw: 0.0,
    };
    let options = ResetOptions {
        start: Some(start),
        goal: Some((0.0, 5.0)),
    };
    e.reset(Some(1), options).unwrap();
    let mut last_y = 0.0;
    for _ in 0..900 {
        let s = e.step(&[0.0f32, 0.0, 0.0]).unwrap();
        let y = s.obs[1] as f64;
        if s.terminated {
            assert!(
                !s.info.success && y < -5.5 && last_y >= -5.5,
                "{last_y} {y}"
            );
            return;
        }
        assert!(!s.truncated, "the head never left the ground (y {y})");
        last_y = y;
    }
    panic!("the episode did not end");
}

/// The goal of [`one_crater_ahead`]'s episode, 12 m ahead of the start (-y).
const CRATER_GOAL: (f64, f64) = (0.0, -12.0);

/// A 10-joint snake reset on flat rough ground (no bumps, no hills) with what `set` adds to its
/// config, facing [`CRATER_GOAL`] 12 m ahead from the origin at height `z`; 600-step episodes.
fn on_flat_rough_ground(z: f64, set: impl FnOnce(&mut EnvConfig)) -> SnakeEnv {
    let mut config = EnvConfig::rough_task(Preset::Paper, 10);
    let rough = config.terrain.as_mut().unwrap().rough.as_mut().unwrap();
    (rough.amplitude, rough.hills_amplitude) = (0.0, 0.0);
    set(&mut config);
    config.max_episode_steps = 600;
    let mut e = env(config);
    let options = ResetOptions {
        start: Some(StartPose {
            x: 0.0,
            y: 0.0,
            z,
            yaw: 0.0,
        }),
        goal: Some(CRATER_GOAL),
    };
    e.reset(Some(1), options).unwrap();
    e
}

/// The rough ground's own keys in `config`.
fn rough_of(config: &mut EnvConfig) -> &mut RoughGround {
    config.terrain.as_mut().unwrap().rough.as_mut().unwrap()
}

/// [`on_flat_rough_ground`] with one crater, `craters` (count 1, on the line), across the line to
/// the goal: its centre 6-8 m ahead. The unsteered wave crawls ahead into it.
fn one_crater_ahead(craters: Craters, progress_around_craters: bool) -> SnakeEnv {
    // Bullet puts the grid's z = 0 halfway between its lowest and highest sample: the flat ground
    // lies half the crater's depth up.
    on_flat_rough_ground(0.5 + 0.5 * craters.depth, |config| {
        rough_of(config).craters = Craters {
            count: 1,
            offset: 0.0,
            ..craters
        };
        config.reward.progress_around_craters = progress_around_craters;
    })
}

/// `footprints`, each a disc.
fn discs(footprints: &[Footprint]) -> Vec<Disc> {
    let disc = |f: &Footprint| match *f {
        Footprint::Disc(d) => d,
        Footprint::Capsule(c) => panic!("a disc expected, got {c:?}"),
    };
    footprints.iter().map(disc).collect()
}

/// `footprints`, each a capsule.
fn capsules(footprints: &[Footprint]) -> Vec<Capsule> {
    let capsule = |f: &Footprint| match *f {
        Footprint::Capsule(c) => c,
        Footprint::Disc(d) => panic!("a capsule expected, got {d:?}"),
    };
    footprints.iter().map(capsule).collect()
}

#[test]
fn a_crater_that_terminates_ends_the_episode_once_the_head_is_over_its_floor() {
    let run = |terminate: bool| {
        let craters = Craters {
            terminate,
            ..Craters::default()
        };
        let mut e = one_crater_ahead(craters, false);
        let floors = discs(&e.course.hazards);
        let mut heads = Vec::new();
        for _ in 0..600 {
            let s = e.step(&[0.0f32, 0.0, 0.0]).unwrap();
            heads.push(e.position);
            if s.terminated || s.truncated {
                return (floors, heads, s.terminated, s.info.success);
            }
        }
        unreachable!("600 steps truncate")
    };
    let (floors, heads, terminated, success) = run(true);
    assert_eq!(floors.len(), 1);
    let f = floors[0];
    assert!(
        f.x == 0.0 && (-8.0..=-6.0).contains(&f.y) && f.radius == 2.25,
        "{f:?}"
    );
    let (last, before) = (heads[heads.len() - 1], &heads[..heads.len() - 1]);
    assert!(terminated && !success, "{:?} {f:?}", heads.last());
    assert!(f.contains(last.0, last.1), "{last:?} {f:?}");
    assert!(before.iter().all(|h| !f.contains(h.0, h.1)));
    // Without `terminate` the same episode goes on over the floor.
    let (floors, heads_on, terminated, _) = run(false);
    assert!(floors.is_empty() && !terminated);
    assert_eq!(&heads_on[..heads.len()], &heads[..]);
}

#[test]
fn progress_around_craters_measures_the_way_around_them() {
    // The crater does not end the episode here. The progress terms add up to the way around the
    // crater from the start less that from where the head ends (it telescopes), not to the
    // straight distances.
    let mut e = one_crater_ahead(Craters::default(), true);
    let goal = CRATER_GOAL;
    let crater = discs(&e.course.route_around);
    assert_eq!(crater.len(), 1);
    let origin = e.origin;
    let around = |p: (f64, f64)| crater[0].route_distance(p, goal);
    let straight = |p: (f64, f64)| (goal.0 - p.0).hypot(goal.1 - p.1);
    let mut progress = 0.0;
    let mut longest_detour = 0.0f64;
    for _ in 0..450 {
        let s = e.step(&[0.0f32, 0.0, 0.0]).unwrap();
        progress += s.info.reward_terms.progress;
        longest_detour = longest_detour.max(around(e.position) - straight(e.position));
    }
    assert!((progress - (around(origin) - around(e.position))).abs() < 1e-9);
    // In the crater the way out and around is metres longer than the straight line.
    assert!(longest_detour > 2.0, "{longest_detour}");
}

#[test]
fn progress_around_ridges_measures_the_way_around_them() {
    // One ridge across the line to a goal 12 m ahead on flat rough ground; the unsteered wave
    // crawls up to it. The progress terms add up to the way around the ridge from the start less
    // that from where the head ends (it telescopes), not to the straight distances. The flat
    // ground lies half the ridge's height (0.75 m) below the grid's z = 0 and a start may not lie
    // below z = 0: the body drops 0.5 m.
    let mut e = on_flat_rough_ground(0.0, |config| {
        rough_of(config).ridges = Ridges {
            count: 1,
            offset: 0.0,
            ..Ridges::default()
        };
        config.reward.progress_around_ridges = true;
    });
    let ridge = capsules(&e.course.route_around);
    assert_eq!(ridge.len(), 1);
    // Across the line (along x), its middle on it, 3-10 m ahead; the footprint 0.75 m and the
    // clearance 1 m either side of its crest line.
    let (c, goal) = (ridge[0], CRATER_GOAL);
    assert!(c.segment.a.1 == c.segment.b.1 && c.segment.a.0 == -c.segment.b.0);
    assert!((-10.0..=-3.0).contains(&c.segment.a.1) && c.radius == 1.75);
    let origin = e.origin;
    let around = |p: (f64, f64)| c.route_distance(p, goal);
    let straight = |p: (f64, f64)| (goal.0 - p.0).hypot(goal.1 - p.1);
    assert!(around(origin) > straight(origin) + 0.5);
    let mut progress = 0.0;
    for _ in 0..450 {
        let s = e.step(&[0.0f32, 0.0, 0.0]).unwrap();
        progress += s.info.reward_terms.progress;
    }
    assert!((progress - (around(origin) - around(e.position))).abs() < 1e-9);
    assert!((progress - (straight(origin) - straight(e.position))).abs() > 0.5);
}

/// The goal vector of an extended or terrain observation of a body of `joints` joints, read by the
/// observation's structure (the part is where both layouts put it).
fn goal_vector(obs: &[f32], joints: usize) -> (f32, f32) {
    let at = ObservationLayout::Extended
        .structure(joints, false, 0)
        .range(ObservationPart::GoalVector)
        .unwrap();
    (obs[at.start], obs[at.start + 1])
}

#[test]
fn a_larger_height_map_holds_the_default_one_in_its_middle() {
    // The rough task's hills, the terrain observation with the default 5 x 5 map and with a 9 x 9
    // one at the same spacing: the same episode, the same values before the map, and the inner
    // 5 x 5 points of the larger map are the default map's.
    let base = EnvConfig {
        observation: ObservationLayout::Terrain,
        ..EnvConfig::rough_task(Preset::Paper, 10)
    };
    let large = EnvConfig {
        height_map: HeightMap {
            side: 9,
            spacing: HEIGHT_MAP_SPACING,
        },
        ..base.clone()
    };
    let (mut a, mut b) = (env(base), env(large));
    assert_eq!(
        b.observation_dim(),
        a.observation_dim() - HEIGHT_MAP_LEN + 81
    );
    let (mut oa, _) = a.reset(Some(3), ResetOptions::default()).unwrap();
    let (mut ob, _) = b.reset(Some(3), ResetOptions::default()).unwrap();
    for step in 0..40 {
        let head = oa.len() - HEIGHT_MAP_LEN;
        assert_eq!(oa[..head], ob[..head], "step {step}");
        let (small, big) = (&oa[head..], &ob[head..]);
        for i in 0..HEIGHT_MAP_SIDE {
            for j in 0..HEIGHT_MAP_SIDE {
                assert_eq!(small[i * HEIGHT_MAP_SIDE + j], big[(i + 2) * 9 + j + 2]);
            }
        }
        assert!(
            big.iter().any(|h| (h - big[40]).abs() > 0.05),
            "hills in view"
        );
        oa = a.step(&[0.3f32, 0.0, 0.0]).unwrap().obs;
        ob = b.step(&[0.3f32, 0.0, 0.0]).unwrap().obs;
    }
    let bad = EnvConfig {
        observation: ObservationLayout::Terrain,
        height_map: HeightMap {
            side: 6,
            spacing: 0.5,
        },
        ..EnvConfig::rough_task(Preset::Paper, 10)
    };
    let m = invalid_message(SnakeEnv::new(bad));
    assert!(m.starts_with("height_map.side: must be odd"), "{m}");
}

/// Every task's observation, in every layout (and the terrain layout with a larger height map), is
/// its structure: the sizes sum to its length, the names are unique, and each named part holds what
/// its name says.
#[test]
fn the_observation_structure_names_every_value() {
    use crate::{HEIGHT_MAP_SIDE, HEIGHT_MAP_SPACING};
    let layouts = ObservationLayout::ALL
        .into_iter()
        .map(|l| (l, HEIGHT_MAP_SIDE))
        .chain([(ObservationLayout::Terrain, 7)]);
    for (layout, side) in layouts {
        for task in Task::ALL {
            let config = EnvConfig {
                observation: layout,
                height_map: HeightMap {
                    side,
                    spacing: HEIGHT_MAP_SPACING,
                },
                ..EnvConfig::for_task(task, Preset::Paper, 6)
            };
            let what = format!(
                "{} task, {} layout, side {side}",
                task.name(),
                layout.name()
            );
            let structure = config.observation_structure();
            let names: Vec<_> = structure.named().collect();
            assert_eq!(structure.len(), config.observation_dim(), "{what}");
            let sum: usize = names.iter().map(|(_, n)| n).sum();
            assert_eq!(sum, config.observation_dim(), "{what}");
            let unique: std::collections::HashSet<_> = names.iter().map(|(n, _)| n).collect();
            assert_eq!(unique.len(), names.len(), "{what}: {names:?}");
            let has = |p: ObservationPart| structure.range(p).is_some();
            assert_eq!(has(ObservationPart::GoalVector), layout.is_extended());
            assert_eq!(
                has(ObservationPart::WavePhase),
                config.observes_wave_phase(),
                "{what}"
            );
            assert_eq!(
                has(ObservationPart::HeightMap),
                layout == ObservationLayout::Terrain
            );
            for (name, _) in &names {
                let part = ObservationPart::from_name(name).unwrap();
                assert_eq!(structure.range_of(name), structure.range(part));
            }
            let mut e = env(config.clone());
            let (mut obs, _) = e.reset(Some(5), ResetOptions::default()).unwrap();
            assert_eq!(obs.len(), config.observation_dim(), "{what}");
            for _ in 0..30 {
                let slice = |p: ObservationPart| &obs[structure.range(p).unwrap()];
                let snake = e.snake().unwrap();
                let base = snake.base_state().unwrap();
                let p = base.pose.position;
                assert_eq!(
                    slice(ObservationPart::BasePosition),
                    [p.x as f32, p.y as f32]
                );
                let pairs: Vec<f32> = snake
                    .joint_states()
                    .unwrap()
                    .iter()
                    .flat_map(|j| [j.position as f32, j.velocity as f32])
                    .collect();
                assert_eq!(slice(ObservationPart::JointStates), pairs, "{what}");
                if layout.is_extended() {
                    let (gx, gy) = goal_vector(&obs, config.joints());
                    let g = slice(ObservationPart::GoalVector);
                    assert_eq!((g[0], g[1]), (gx, gy));
                    let far = (e.goal().0 - p.x).hypot(e.goal().1 - p.y);
                    let norm = f64::from(gx).hypot(f64::from(gy));
                    assert!((norm - far).abs() < 1e-4 * far.max(1.0), "{what}");
                    let h = slice(ObservationPart::Heading);
                    assert!((h[0].hypot(h[1]) - 1.0).abs() < 1e-5, "{what}");
                    let v = slice(ObservationPart::BaseVelocity);
                    let speed = base.linear_velocity.x.hypot(base.linear_velocity.y);
                    let seen = f64::from(v[0]).hypot(f64::from(v[1]));
                    assert!((seen - speed).abs() < 1e-4 * speed.max(1.0), "{what}");
                }
                if has(ObservationPart::WavePhase) {
                    let w = slice(ObservationPart::WavePhase);
                    assert!((w[0].hypot(w[1]) - 1.0).abs() < 1e-5, "{what}");
                }
                if layout == ObservationLayout::Terrain {
                    let up = slice(ObservationPart::WorldUp);
                    let norm = (up.iter().map(|u| u * u).sum::<f32>()).sqrt();
                    assert!((norm - 1.0).abs() < 1e-5, "{what}");
                    assert_eq!(slice(ObservationPart::HeightMap).len(), side * side);
                }
                let action = vec![0.3f32; e.action_dim()];
                obs = e.step(&action).unwrap().obs;
            }
        }
    }
}
