//! Property tests over configurations, starts, goals and actions: whatever a user passes, the env
//! gives finite observations and rewards or a typed error; it never panics.
//!
//! Each value is drawn mostly from a plausible range and sometimes (1 in 100) from every f64 (NaN, infinities, subnormals,
//! extremes), so both the checks and the physics behind them are exercised. `PROPTEST_CASES` sets the
//! number of cases (default below).

use proptest::prelude::*;
use snake_core::env::{ActionMode, EnvConfig, ResetOptions, SnakeEnv};
use snake_core::{Error, Preset, StartPose, VecSnakeEnv};

/// Cases per property (each builds a world and steps it: ~3 ms; about 60 % of the generated
/// configurations are valid and run up to 40 env steps).
const CASES: u32 = 500;

/// A plausible value in `range`, or any f64 at all.
fn wild(range: std::ops::Range<f64>) -> BoxedStrategy<f64> {
    prop_oneof![99 => range, 1 => proptest::num::f64::ANY].boxed()
}

/// A range [low, high], now and then reversed.
fn pair(range: std::ops::Range<f64>) -> impl Strategy<Value = [f64; 2]> {
    (wild(range.clone()), wild(range), prop::bool::weighted(0.01)).prop_map(|(a, b, reversed)| {
        let (low, high) = if a <= b { (a, b) } else { (b, a) };
        if reversed {
            [high, low]
        } else {
            [low, high]
        }
    })
}

prop_compose! {
    fn config()(
        joints in prop_oneof![99 => 1usize..9, 1 => 0usize..1000],
        preset in prop_oneof![Just(Preset::Paper), Just(Preset::SnakebotGym)],
        goal in (wild(-30.0..30.0), wild(-30.0..30.0)),
        goal_radius in wild(0.0..3.0),
        max_episode_steps in prop_oneof![99 => 1u64..200, 1 => any::<u64>()],
        physics_steps in prop_oneof![99 => 1u32..16, 1 => any::<u32>()],
        start in (pair(-2.0..2.0), pair(-2.0..2.0), wild(0.0..1.0), pair(-4.0..4.0)),
        action_scale in wild(0.0..3.0),
        mode in prop_oneof![Just(ActionMode::Joints), Just(ActionMode::Gait), Just(ActionMode::Residual)],
        extended in any::<bool>(),
        weights in (wild(-2.0..2.0), wild(-2.0..2.0), wild(-2.0..2.0), wild(-2.0..2.0), wild(0.0..200.0)),
        physics in (wild(1e-3..10.0), wild(1e-3..10.0), wild(0.0..20.0), wild(0.0..50.0), wild(1e-4..0.05)),
        randomize in prop::option::weighted(0.3, (
            pair(0.0..2.0), pair(0.01..3.0), pair(0.01..3.0), pair(0.01..3.0), pair(0.01..3.0),
            prop_oneof![9 => (0u32..4, 0u32..4).prop_map(|(a, b)| [f64::from(a.min(b)), f64::from(a.max(b))]), 1 => pair(0.0..40.0)],
            pair(0.0..0.5),
        )),
    ) -> EnvConfig {
        let mut c = EnvConfig::with_preset(preset, joints);
        c.goal = goal;
        c.goal_radius = goal_radius;
        c.max_episode_steps = max_episode_steps;
        c.physics_steps_per_env_step = physics_steps;
        (c.start.x, c.start.y, c.start.z, c.start.yaw) = start;
        c.action_scale = action_scale;
        c.action.mode = mode;
        if extended {
            c.observation = snake_core::env::ObservationLayout::Extended;
        }
        (
            c.reward.distance_weight,
            c.reward.progress_weight,
            c.reward.smoothness_weight,
            c.reward.energy_weight,
            c.reward.success_reward,
        ) = weights;
        (c.snake.link_mass, c.snake.base_mass, c.snake.lateral_friction, c.snake.motor_force, c.snake.dt) =
            physics;
        c.randomize = randomize.map(|(friction, mass, effort, kp, kd, latency, noise)| {
            snake_core::Randomize {
                ground_friction: Some(friction),
                mass_scale: Some(mass),
                effort_scale: Some(effort),
                kp_scale: Some(kp),
                kd_scale: Some(kd),
                latency_steps: Some(latency),
                obs_noise: Some(noise),
                skin_friction_scale: None,
                current_speed: None,
                current_heading: None,
            }
        });
        c
    }
}

fn start_pose() -> impl Strategy<Value = Option<StartPose>> {
    prop::option::of(
        (
            wild(-5.0..5.0),
            wild(-5.0..5.0),
            wild(0.0..1.0),
            wild(-7.0..7.0),
        )
            .prop_map(|(x, y, z, yaw)| StartPose { x, y, z, yaw }),
    )
}

/// Actions: mostly of the right length (`None`) with plausible values, sometimes of any length or
/// holding any f32.
fn actions() -> impl Strategy<Value = Vec<(Option<usize>, Vec<f32>)>> {
    let value = prop_oneof![24 => -1.5f32..1.5, 1 => proptest::num::f32::ANY];
    let length = prop_oneof![12 => Just(None), 1 => (0usize..12).prop_map(Some)];
    prop::collection::vec((length, prop::collection::vec(value, 12)), 1..40)
}

/// Errors a user can cause: bad input, or physics that blew up (reported, never hidden).
fn typed(e: &Error) -> bool {
    matches!(e, Error::InvalidArgument(_) | Error::NonFinite(_))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: CASES, ..ProptestConfig::default() })]

    #[test]
    fn env_outputs_are_finite_or_a_typed_error(
        config in config(),
        seed in any::<u64>(),
        start in start_pose(),
        goal in prop::option::of((wild(-30.0..30.0), wild(-30.0..30.0))),
        steps in actions(),
    ) {
        let env = SnakeEnv::new(config.clone());
        prop_assert_eq!(env.is_ok(), config.validate().is_ok());
        let mut env = match env {
            Ok(env) => env,
            Err(e) => {
                prop_assert!(matches!(e, Error::InvalidArgument(_)), "{e}");
                return Ok(());
            }
        };
        match env.reset(Some(seed), ResetOptions { start, goal }) {
            Ok((obs, info)) => {
                prop_assert!(obs.iter().all(|v| v.is_finite()), "reset obs {obs:?}");
                prop_assert!(info.distance.is_finite());
            }
            Err(e) => {
                prop_assert!(typed(&e), "{e}");
                return Ok(());
            }
        }
        for (length, values) in &steps {
            let action = &values[..length.unwrap_or(env.action_dim()).min(values.len())];
            match env.step(action) {
                Ok(step) => {
                    prop_assert!(step.obs.iter().all(|v| v.is_finite()), "obs {:?}", step.obs);
                    prop_assert!(step.reward.is_finite() && step.info.episode_return.is_finite());
                    if step.terminated || step.truncated {
                        break;
                    }
                }
                Err(e) => {
                    prop_assert!(typed(&e), "{e}");
                    // A physics blow-up ends the episode: the env asks for a reset, it does not go on.
                    if matches!(e, Error::NonFinite(_)) {
                        prop_assert!(env.step(action).is_err());
                    }
                    if action.len() == env.action_dim() && action.iter().all(|a| a.is_finite()) {
                        break;
                    }
                }
            }
        }
    }

    #[test]
    fn vec_env_sizes_and_actions_are_checked(
        num_envs in prop_oneof![3 => 1usize..4, 1 => any::<usize>()],
        joints in 1usize..4,
        values in prop::collection::vec(prop_oneof![4 => -1.0f64..1.0, 1 => proptest::num::f64::ANY], 0..16),
    ) {
        let config = EnvConfig::with_preset(Preset::Paper, joints);
        let mut envs = match VecSnakeEnv::new(config, num_envs) {
            Ok(envs) => envs,
            Err(e) => {
                prop_assert!(matches!(e, Error::InvalidArgument(_)), "{e}");
                prop_assert!(num_envs == 0 || num_envs > snake_core::limits::MAX_ENVS);
                return Ok(());
            }
        };
        let (m, d) = (envs.num_envs(), envs.observation_dim());
        let mut obs = vec![0.0f32; m * d];
        envs.reset(Some(0), &mut obs).unwrap();
        let (mut rewards, mut done, mut cut) = (vec![0.0; m], vec![false; m], vec![false; m]);
        let result = envs.step(&values, &mut obs, &mut rewards, &mut done, &mut cut).map(|_| ());
        let valid = values.len() == m * joints && values.iter().all(|v| v.is_finite());
        prop_assert_eq!(result.is_ok(), valid, "{:?}", result);
        if valid {
            prop_assert!(obs.iter().all(|v| v.is_finite()) && rewards.iter().all(|r| r.is_finite()));
        }
    }
}

proptest! {
    // Each case builds a pool and swims 20 env steps (~20 ms).
    #![proptest_config(ProptestConfig { cases: 60, ..ProptestConfig::default() })]

    /// The swimming task (its built-in pool) under `randomize`'s current, whatever its ranges: finite
    /// observations and rewards, or a one-line error naming the key.
    #[test]
    fn a_randomized_current_is_finite_or_a_typed_error(
        speed in pair(0.0..2.0),
        heading in prop::option::of(pair(-7.0..7.0)),
        seed in any::<u64>(),
    ) {
        let mut config = EnvConfig::for_task(snake_core::env::Task::Swim, Preset::Paper, 3);
        config.randomize = Some(snake_core::Randomize {
            current_speed: Some(speed),
            current_heading: heading,
            ..Default::default()
        });
        let mut env = match SnakeEnv::new(config) {
            Ok(env) => env,
            Err(e) => {
                prop_assert!(e.to_string().contains("randomize.current_"), "{e}");
                return Ok(());
            }
        };
        let (obs, _) = env.reset(Some(seed), ResetOptions::default()).unwrap();
        prop_assert!(obs.iter().all(|v| v.is_finite()), "reset obs {obs:?}");
        for _ in 0..20 {
            let step = env.step(&[0.5f32, 0.0, 0.0]).unwrap();
            prop_assert!(step.obs.iter().all(|v| v.is_finite()), "obs {:?}", step.obs);
            prop_assert!(step.reward.is_finite());
        }
    }
}
