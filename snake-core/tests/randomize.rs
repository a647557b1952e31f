//! Randomized physics (`EnvConfig::randomize`, issue 47 item 2): zero width is the plain env bit for
//! bit, a seed draws one physics, each parameter reaches the world, bad ranges are one line.

use std::path::Path;

use snake_core::{
    EnvConfig, Preset, Randomize, ResetOptions, RobotRef, SkinFriction, SnakeEnv, Task, VecSnakeEnv,
};

fn robot_path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/yaw-pitch-16.yaml")
}

/// Every parameter at its nominal value, zero width (ground friction: the plane's 0.5).
fn nominal() -> Randomize {
    Randomize {
        ground_friction: Some([0.5, 0.5]),
        mass_scale: Some([1.0, 1.0]),
        effort_scale: Some([1.0, 1.0]),
        kp_scale: Some([1.0, 1.0]),
        kd_scale: Some([1.0, 1.0]),
        latency_steps: Some([0.0, 0.0]),
        obs_noise: Some([0.0, 0.0]),
        skin_friction_scale: None,
        current_speed: None,
        current_heading: None,
    }
}

fn wide() -> Randomize {
    Randomize {
        ground_friction: Some([0.3, 0.9]),
        mass_scale: Some([0.8, 1.2]),
        effort_scale: Some([0.7, 1.0]),
        kp_scale: Some([0.8, 1.2]),
        kd_scale: Some([0.8, 1.2]),
        latency_steps: Some([0.0, 2.0]),
        obs_noise: Some([0.0, 0.02]),
        skin_friction_scale: None,
        current_speed: None,
        current_heading: None,
    }
}

fn action(t: usize, n: usize) -> Vec<f32> {
    (0..n)
        .map(|j| (0.05 * t as f32 + 0.7 * j as f32).sin())
        .collect()
}

/// Runs `steps` steps (resetting with seed + episode when an episode ends) and returns every bit.
fn rollout(config: EnvConfig, seed: u64, steps: usize) -> Vec<u64> {
    let mut env = SnakeEnv::new(config).unwrap();
    let n = env.action_dim();
    let mut bits = Vec::new();
    let (obs, info) = env.reset(Some(seed), ResetOptions::default()).unwrap();
    bits.extend(obs.iter().map(|v| v.to_bits() as u64));
    bits.push(info.distance.to_bits());
    for t in 0..steps {
        let s = env.step(&action(t, n)).unwrap();
        bits.extend(s.obs.iter().map(|v| v.to_bits() as u64));
        bits.extend([
            s.reward.to_bits(),
            s.info.distance.to_bits(),
            s.info.work.to_bits(),
            s.info.time.to_bits(),
            s.terminated as u64,
            s.truncated as u64,
        ]);
        if s.terminated || s.truncated {
            let (obs, _) = env.reset(None, ResetOptions::default()).unwrap();
            bits.extend(obs.iter().map(|v| v.to_bits() as u64));
        }
    }
    bits
}

#[test]
fn zero_width_at_nominal_is_the_plain_env_bit_for_bit() {
    let cube = EnvConfig::for_task(Task::Goal, Preset::Paper, 6);
    let robot = EnvConfig {
        robot: Some(RobotRef::load(&robot_path()).unwrap()),
        max_episode_steps: 150,
        ..EnvConfig::for_task(Task::Paper, Preset::Paper, 1)
    };
    for plain in [cube, robot] {
        let randomized = EnvConfig {
            randomize: Some(nominal()),
            ..plain.clone()
        };
        let a = rollout(plain, 7, 300);
        let b = rollout(randomized, 7, 300);
        assert_eq!(a.len(), b.len());
        if let Some(i) = a.iter().zip(&b).position(|(x, y)| x != y) {
            panic!("first difference at value {i}");
        }
    }
}

#[test]
fn same_seed_same_draw_different_seeds_differ_within_ranges() {
    let config = EnvConfig {
        randomize: Some(wide()),
        ..EnvConfig::for_task(Task::Goal, Preset::Paper, 4)
    };
    let mut a = SnakeEnv::new(config.clone()).unwrap();
    let mut b = SnakeEnv::new(config.clone()).unwrap();
    let mut plain = SnakeEnv::new(EnvConfig {
        randomize: None,
        ..config
    })
    .unwrap();
    let mut seen = Vec::new();
    for seed in 0..20 {
        let (_, ia) = a.reset(Some(seed), ResetOptions::default()).unwrap();
        let pa = *a.physics();
        b.reset(Some(seed), ResetOptions::default()).unwrap();
        assert_eq!(pa, *b.physics());
        // The draw leaves the main stream alone: the plain env's start and goal.
        let (_, ip) = plain.reset(Some(seed), ResetOptions::default()).unwrap();
        assert_eq!((ia.start, ia.goal), (ip.start, ip.goal));
        let r = wide();
        for (value, [low, high]) in [
            (pa.ground_friction, r.ground_friction.unwrap()),
            (pa.mass_scale, r.mass_scale.unwrap()),
            (pa.effort_scale, r.effort_scale.unwrap()),
            (pa.kp_scale, r.kp_scale.unwrap()),
            (pa.kd_scale, r.kd_scale.unwrap()),
            (pa.obs_noise, r.obs_noise.unwrap()),
        ] {
            let v = value.unwrap();
            assert!((low..=high).contains(&v), "{v} outside [{low}, {high}]");
        }
        assert!(pa.latency_steps.unwrap() <= 2);
        seen.push(pa);
    }
    for i in 1..seen.len() {
        assert_ne!(seen[i].mass_scale, seen[0].mass_scale);
    }
    let latencies: std::collections::BTreeSet<u32> =
        seen.iter().map(|p| p.latency_steps.unwrap()).collect();
    assert_eq!(latencies.into_iter().collect::<Vec<_>>(), vec![0, 1, 2]);
}

#[test]
fn an_episodes_physics_never_depends_on_the_steps_before_it() {
    // Two controllers evaluated on a seed's episodes must meet the same physics in each: the k-th
    // reset's draw is the k-th draw of the physics stream, however long the episodes before were
    // (the observation noise of their steps comes from a stream of its own).
    use rand::SeedableRng;
    let config = EnvConfig {
        randomize: Some(wide()),
        ..EnvConfig::for_task(Task::Goal, Preset::Paper, 4)
    };
    let mut stream = rand_chacha::ChaCha12Rng::seed_from_u64(5);
    stream.set_stream(snake_core::PHYSICS_STREAM);
    let expected: Vec<_> = (0..3).map(|_| wide().draw(&mut stream)).collect();
    for steps in [1, 7, 60] {
        let mut env = SnakeEnv::new(config.clone()).unwrap();
        env.reset(Some(5), ResetOptions::default()).unwrap();
        let mut drawn = vec![*env.physics()];
        for _ in 0..2 {
            for t in 0..steps {
                env.step(&action(t, env.action_dim())).unwrap();
            }
            env.reset(None, ResetOptions::default()).unwrap();
            drawn.push(*env.physics());
        }
        assert_eq!(drawn, expected, "episodes of {steps} steps");
    }
}

#[test]
fn mass_and_ground_friction_reach_the_world() {
    for robot in [None, Some(RobotRef::load(&robot_path()).unwrap())] {
        let base = EnvConfig {
            robot,
            ..EnvConfig::for_task(Task::Paper, Preset::Paper, 3)
        };
        let mut plain = SnakeEnv::new(base.clone()).unwrap();
        let mut env = SnakeEnv::new(EnvConfig {
            randomize: Some(Randomize {
                mass_scale: Some([1.5, 1.5]),
                ground_friction: Some([0.8, 0.8]),
                ..Randomize::default()
            }),
            ..base
        })
        .unwrap();
        plain.reset(Some(1), ResetOptions::default()).unwrap();
        let (_, _) = env.reset(Some(1), ResetOptions::default()).unwrap();
        // Read back through the world.
        let read = |e: &SnakeEnv| {
            let body = e.body().unwrap();
            let (world, id, ground) = (body.world(), body.id(), body.ground());
            let links = world.num_joints(id).unwrap();
            let parts: Vec<_> = std::iter::once(None).chain((0..links).map(Some)).collect();
            let infos: Vec<_> = parts
                .iter()
                .map(|&p| world.dynamics_info(id, p).unwrap())
                .collect();
            (infos, world.dynamics_info(ground, None).unwrap())
        };
        let (plain_parts, plain_ground) = read(&plain);
        let (parts, ground) = read(&env);
        assert_eq!(plain_ground.lateral_friction, 0.5);
        assert_eq!(ground.lateral_friction, 0.8);
        let mut dynamic = 0;
        for (p, q) in plain_parts.iter().zip(&parts) {
            if p.mass > 0.0 {
                dynamic += 1;
                assert_eq!(q.mass, p.mass * 1.5);
                for k in 0..3 {
                    // Inertia from the shape: linear in the mass.
                    assert!((q.inertia[k] - 1.5 * p.inertia[k]).abs() <= 1e-12 * p.inertia[k]);
                }
            } else {
                assert_eq!(q.mass, 0.0);
            }
        }
        assert!(dynamic >= 4);
    }
}

#[test]
fn latency_delays_the_targets_by_exactly_k_steps() {
    let k = 3;
    let base = EnvConfig::for_task(Task::Paper, Preset::Paper, 4);
    let mut delayed = SnakeEnv::new(EnvConfig {
        randomize: Some(Randomize {
            latency_steps: Some([k as f64, k as f64]),
            ..Randomize::default()
        }),
        ..base.clone()
    })
    .unwrap();
    let mut direct = SnakeEnv::new(base).unwrap();
    delayed.set_physics_trace(true);
    direct.set_physics_trace(true);
    let (o1, _) = delayed.reset(Some(3), ResetOptions::default()).unwrap();
    let (o2, _) = direct.reset(Some(3), ResetOptions::default()).unwrap();
    assert_eq!(o1, o2);
    assert_eq!(delayed.physics().latency_steps, Some(k as u32));
    let n = 4;
    for t in 0..200 {
        let a = action(t, n);
        // The un-delayed env gets the same actions shifted by k, the zero action first.
        let shifted = if t < k {
            vec![0.0; n]
        } else {
            action(t - k, n)
        };
        let s1 = delayed.step(&a).unwrap();
        let s2 = direct.step(&shifted).unwrap();
        let t1 = &delayed.physics_trace().unwrap().targets;
        let t2 = &direct.physics_trace().unwrap().targets;
        assert_eq!(t1, t2, "targets at step {t}");
        assert_eq!(s1.obs, s2.obs, "observation at step {t}");
        if t >= k {
            let expect: Vec<f64> = action(t - k, n).iter().map(|&v| f64::from(v)).collect();
            assert_eq!(t1, &expect);
        }
    }
}

#[test]
fn obs_noise_has_the_requested_std_and_stays_out_of_the_reward() {
    let std = 0.05;
    let base = EnvConfig::for_task(Task::Goal, Preset::Paper, 5);
    let mut noisy = SnakeEnv::new(EnvConfig {
        randomize: Some(Randomize {
            obs_noise: Some([std, std]),
            ..Randomize::default()
        }),
        ..base.clone()
    })
    .unwrap();
    let mut clean = SnakeEnv::new(base).unwrap();
    let (mut sum, mut sum2, mut count) = (0.0f64, 0.0f64, 0usize);
    for episode in 0..4 {
        let (a, ia) = noisy.reset(Some(episode), ResetOptions::default()).unwrap();
        let (b, ib) = clean.reset(Some(episode), ResetOptions::default()).unwrap();
        assert_eq!(ia.distance, ib.distance);
        assert_ne!(a, b);
        for t in 0..250 {
            let act = action(t, noisy.action_dim());
            let s1 = noisy.step(&act).unwrap();
            let s2 = clean.step(&act).unwrap();
            assert_eq!(s1.reward.to_bits(), s2.reward.to_bits());
            assert_eq!(s1.info.distance.to_bits(), s2.info.distance.to_bits());
            assert_eq!((s1.terminated, s1.truncated), (s2.terminated, s2.truncated));
            for (x, y) in s1.obs.iter().zip(&s2.obs) {
                let e = f64::from(*x) - f64::from(*y);
                sum += e;
                sum2 += e * e;
                count += 1;
            }
        }
    }
    let mean = sum / count as f64;
    let measured = (sum2 / count as f64 - mean * mean).sqrt();
    // ~17,000 samples: the sample std is within ~0.6 % of the truth (1 sigma); 3 % is 5 sigma.
    assert!(count > 15_000);
    assert!((measured / std - 1.0).abs() < 0.03, "std {measured}");
    assert!(
        mean.abs() < 5.0 * std / (count as f64).sqrt(),
        "mean {mean}"
    );
}

#[test]
fn motors_and_skin_scale_and_work_on_every_task() {
    let skin = SkinFriction::new(0.1, 0.2, 0.3);
    for task in Task::ALL {
        let mut config = EnvConfig::for_task(task, Preset::Paper, 5);
        config.snake.skin_friction = Some(skin);
        config.randomize = Some(Randomize {
            skin_friction_scale: Some([0.5, 1.5]),
            ..wide()
        });
        let mut env = SnakeEnv::new(config).unwrap();
        env.reset(Some(11), ResetOptions::default()).unwrap();
        let p = *env.physics();
        let c = env.snake().unwrap().config();
        let nominal = Preset::Paper.config(5);
        assert_eq!(c.motor_force, nominal.motor_force * p.effort_scale.unwrap());
        assert_eq!(c.position_gain, nominal.position_gain * p.kp_scale.unwrap());
        assert_eq!(c.velocity_gain, nominal.velocity_gain * p.kd_scale.unwrap());
        for t in 0..50 {
            env.step(&action(t, env.action_dim())).unwrap();
        }
    }
}

#[test]
fn vector_env_i_is_the_single_env_seeded_s_plus_i() {
    let config = EnvConfig {
        randomize: Some(wide()),
        ..EnvConfig::for_task(Task::Goal, Preset::Paper, 4)
    };
    let n = 3;
    let mut vec_env = VecSnakeEnv::new(config.clone(), n)
        .unwrap()
        .with_threads(2)
        .unwrap();
    let d = vec_env.observation_dim();
    let mut obs = vec![0.0f32; n * d];
    vec_env.reset(Some(40), &mut obs).unwrap();
    let envs: Vec<_> = vec_env.envs().collect();
    for (i, env) in envs.iter().enumerate() {
        let mut single = SnakeEnv::new(config.clone()).unwrap();
        let (o, _) = single
            .reset(Some(40 + i as u64), ResetOptions::default())
            .unwrap();
        assert_eq!(&obs[i * d..(i + 1) * d], &o[..]);
        assert_eq!(env.physics(), single.physics());
    }
}

#[test]
fn bad_ranges_are_one_line_naming_the_key() {
    let cases: [(Randomize, &str); 9] = [
        (
            // Accepted once (> 0), it made the first physics step non-finite at every reset.
            Randomize {
                mass_scale: Some([1e-300, 1e-300]),
                ..Randomize::default()
            },
            "randomize.mass_scale: must lie within 0.01 <= low <= high <= 100, got [1e-300, 1e-300]",
        ),
        (
            Randomize {
                effort_scale: Some([0.5, 1e300]),
                ..Randomize::default()
            },
            "randomize.effort_scale: must lie within 0.01 <= low <= high <= 100, got [0.5, 1e300]",
        ),
        (
            Randomize {
                mass_scale: Some([1.2, 0.8]),
                ..Randomize::default()
            },
            "randomize.mass_scale: must have low <= high",
        ),
        (
            Randomize {
                effort_scale: Some([f64::NAN, 1.0]),
                ..Randomize::default()
            },
            "randomize.effort_scale: must be finite",
        ),
        (
            Randomize {
                kp_scale: Some([-1.0, 1.0]),
                ..Randomize::default()
            },
            "randomize.kp_scale: must lie within",
        ),
        (
            Randomize {
                kd_scale: Some([0.0, 1.0]),
                ..Randomize::default()
            },
            "randomize.kd_scale: must lie within",
        ),
        (
            Randomize {
                latency_steps: Some([0.0, 33.0]),
                ..Randomize::default()
            },
            "randomize.latency_steps: must lie within",
        ),
        (
            Randomize {
                latency_steps: Some([0.5, 1.0]),
                ..Randomize::default()
            },
            "randomize.latency_steps: must be whole env steps",
        ),
        (
            Randomize {
                skin_friction_scale: Some([1.0, 1.0]),
                ..Randomize::default()
            },
            "randomize.skin_friction_scale: needs a body with skin friction",
        ),
    ];
    for (r, expected) in cases {
        let config = EnvConfig {
            randomize: Some(r),
            ..EnvConfig::default()
        };
        let e = SnakeEnv::new(config).unwrap_err().to_string();
        assert!(e.contains(expected), "{e}");
        assert!(!e.contains('\n'));
    }
    let unknown: Result<Randomize, _> = serde_json::from_str(r#"{"mass": [1, 2]}"#);
    assert!(unknown
        .unwrap_err()
        .to_string()
        .contains("unknown field `mass`"));
}

/// Every value a scale's range may hold builds a finite simulation: each scale at both ends of
/// [`MIN_PHYSICS_SCALE`, `MAX_PHYSICS_SCALE`], alone and all together, on the paper's snake, the
/// snakebot-gym snake (1 kg links), the yaw-pitch robot and a skinned snake, 2.5 s of a wave each.
#[test]
fn every_scale_the_validator_accepts_builds_a_finite_simulation() {
    use snake_core::limits::{MAX_PHYSICS_SCALE, MIN_PHYSICS_SCALE};
    let mut bodies = vec![
        EnvConfig::for_task(Task::Goal, Preset::Paper, 10),
        EnvConfig::for_task(Task::Goal, Preset::SnakebotGym, 10),
        EnvConfig {
            robot: Some(RobotRef::load(&robot_path()).unwrap()),
            ..EnvConfig::for_task(Task::Goal, Preset::Paper, 15)
        },
    ];
    let mut skinned = EnvConfig::for_task(Task::Paper, Preset::Paper, 5);
    skinned.snake.skin_friction = Some(SkinFriction::new(0.1, 0.2, 0.3));
    bodies.push(skinned);
    for body in bodies {
        let has_skin = body.snake.skin_friction.is_some();
        for end in [MIN_PHYSICS_SCALE, MAX_PHYSICS_SCALE] {
            let at = Some([end, end]);
            let mut ranges = vec![
                Randomize {
                    mass_scale: at,
                    ..Randomize::default()
                },
                Randomize {
                    effort_scale: at,
                    ..Randomize::default()
                },
                Randomize {
                    kp_scale: at,
                    ..Randomize::default()
                },
                Randomize {
                    kd_scale: at,
                    ..Randomize::default()
                },
                Randomize {
                    mass_scale: at,
                    effort_scale: at,
                    kp_scale: at,
                    kd_scale: at,
                    skin_friction_scale: if has_skin { at } else { None },
                    ..Randomize::default()
                },
            ];
            if has_skin {
                ranges.push(Randomize {
                    skin_friction_scale: at,
                    ..Randomize::default()
                });
            }
            // Light bodies with strong motors, heavy ones with weak motors.
            let other = if end == MIN_PHYSICS_SCALE {
                MAX_PHYSICS_SCALE
            } else {
                MIN_PHYSICS_SCALE
            };
            ranges.push(Randomize {
                mass_scale: at,
                effort_scale: Some([other, other]),
                kp_scale: Some([other, other]),
                kd_scale: Some([other, other]),
                ..Randomize::default()
            });
            for r in ranges {
                let config = EnvConfig {
                    randomize: Some(r),
                    ..body.clone()
                };
                let mut env = SnakeEnv::new(config).unwrap();
                env.reset(Some(3), ResetOptions::default())
                    .unwrap_or_else(|e| panic!("{r:?}: {e}"));
                let n = env.action_dim();
                // 2.5 s at the goal task's 30 Hz (the paper task's 240 Hz: a shorter time, as many steps).
                for t in 0..75 {
                    if let Err(e) = env.step(&action(t, n)) {
                        panic!("{r:?} at step {t}: {e}");
                    }
                }
            }
        }
    }
}
