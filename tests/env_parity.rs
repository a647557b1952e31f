//! snake-core's [`SnakeEnv`] against the paper's env rebuilt in pybullet 3.2.7, bit for bit.
//!
//! `reference/paper_env_reference.py` runs the paper's `SnakeEnv.reset`/`step` logic (fresh
//! BulletClient and resetSimulation per episode, plane, gravity, the snakebot-gym snake, one step
//! before the first observation, POSITION_CONTROL with force 10, numpy float32 observations and
//! reward, gym's TimeLimit) on the same start poses and action sequences; every observation value,
//! reward and end flag must have identical bits. The paper's goal marker (a static duck mesh beyond
//! the goal) is left out on both sides: it only matters if the snake touches it.

use serde::Serialize;
use snake_core::env::python_hypot;
use snake_core::{EnvConfig, ResetOptions, SnakeEnv, StartPose};
use snakesim_tests::{assert_identical, read_csv, run_reference_script};

#[derive(Serialize)]
struct Spec {
    #[serde(skip_serializing_if = "Option::is_none")]
    hypot: Option<HypotSpec>,
    envs: Vec<EnvSpec>,
}

#[derive(Serialize)]
struct HypotSpec {
    count: usize,
    seed: u64,
}

#[derive(Serialize, Clone)]
struct EnvSpec {
    name: String,
    joints: usize,
    max_episode_steps: u64,
    goal_radius: f64,
    episodes: Vec<Episode>,
}

#[derive(Serialize, Clone)]
struct Episode {
    /// x, y, z, yaw.
    start: [f64; 4],
    goal: [f64; 2],
    /// float32 actions, widened to f64 exactly so that JSON carries them without rounding.
    actions: Vec<Vec<f64>>,
    /// On our side, reset with this seed (whose draw gave `start`) instead of passing the start.
    #[serde(skip)]
    seed: Option<u64>,
}

/// xorshift64*: a small deterministic generator for the action sequences.
struct XorShift(u64);

impl XorShift {
    fn unit(&mut self) -> f64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        (x.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A travelling wave (period 1.5 s at 240 Hz, phase lag `lag` turns per joint: positive runs from
/// head to tail) plus uniform noise, as float32.
fn wave(
    joints: usize,
    steps: usize,
    amplitude: f64,
    lag: f64,
    noise: f64,
    seed: u64,
) -> Vec<Vec<f64>> {
    let mut rng = XorShift(seed);
    (0..steps)
        .map(|k| {
            (0..joints)
                .map(|j| {
                    let phase = std::f64::consts::TAU * (k as f64 / 360.0 - lag * (j + 1) as f64);
                    let a = amplitude * phase.sin() + noise * (2.0 * rng.unit() - 1.0);
                    a as f32 as f64
                })
                .collect()
        })
        .collect()
}

/// Uniform float32 actions in [-1.2, 1.2] (so that clipping is exercised).
fn random(joints: usize, steps: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = XorShift(seed);
    (0..steps)
        .map(|_| {
            (0..joints)
                .map(|_| (1.2 * (2.0 * rng.unit() - 1.0)) as f32 as f64)
                .collect()
        })
        .collect()
}

fn config(spec: &EnvSpec) -> EnvConfig {
    EnvConfig {
        max_episode_steps: spec.max_episode_steps,
        goal_radius: spec.goal_radius,
        ..EnvConfig::snakebot_gym(spec.joints)
    }
}

fn episode(start: [f64; 4], goal: [f64; 2], actions: Vec<Vec<f64>>) -> Episode {
    Episode {
        start,
        goal,
        actions,
        seed: None,
    }
}

/// An episode whose start our env draws from `seed` (the reference gets the drawn pose).
fn seeded_episode(spec: &EnvSpec, seed: u64, goal: [f64; 2], actions: Vec<Vec<f64>>) -> Episode {
    let mut probe = SnakeEnv::new(config(spec)).unwrap();
    let (_, info) = probe.reset(Some(seed), ResetOptions::default()).unwrap();
    let s = info.start;
    Episode {
        start: [s.x, s.y, s.z, s.yaw],
        goal,
        actions,
        seed: Some(seed),
    }
}

/// Runs every episode of `spec` in one env, in order; one table per episode in the reference's columns.
fn run_ours(spec: &EnvSpec) -> Vec<Vec<Vec<f64>>> {
    let mut env = SnakeEnv::new(config(spec)).unwrap();
    let mut tables = Vec::new();
    for ep in &spec.episodes {
        let [x, y, z, yaw] = ep.start;
        let goal = Some((ep.goal[0], ep.goal[1]));
        let options = match ep.seed {
            Some(_) => ResetOptions { start: None, goal },
            None => ResetOptions {
                start: Some(StartPose { x, y, z, yaw }),
                goal,
            },
        };
        let (obs, info) = env.reset(ep.seed, options).unwrap();
        assert_eq!(
            [info.start.x, info.start.y, info.start.z, info.start.yaw],
            ep.start
        );
        let row = |step: usize, reward: f64, terminated: bool, truncated: bool, obs: &[f32]| {
            let mut row = vec![
                step as f64,
                reward,
                terminated as u8 as f64,
                truncated as u8 as f64,
            ];
            row.extend(obs.iter().map(|&v| v as f64));
            row
        };
        let mut rows = vec![row(0, 0.0, false, false, &obs)];
        let mut obs = obs;
        for (k, action) in ep.actions.iter().enumerate() {
            let action: Vec<f32> = action.iter().map(|&a| a as f32).collect();
            let out = env.step_into(&action, &mut obs).unwrap();
            rows.push(row(k + 1, out.reward, out.terminated, out.truncated, &obs));
            if out.terminated || out.truncated {
                break;
            }
        }
        tables.push(rows);
    }
    tables
}

/// Our episodes of `envs`, checked against the reference's; `None` without a reference environment.
fn check(tag: &str, envs: Vec<EnvSpec>) -> Option<Vec<Vec<Vec<f64>>>> {
    let dir = run_reference_script(
        "paper_env_reference.py",
        &Spec {
            hypot: None,
            envs: envs.clone(),
        },
        tag,
    )?;
    let mut all = Vec::new();
    for spec in &envs {
        let ours = run_ours(spec);
        for (k, table) in ours.into_iter().enumerate() {
            let name = format!("{}-{k}", spec.name);
            let reference = read_csv(&dir.join(format!("{name}.csv")));
            assert_identical(&name, &reference.header, &reference.rows, &table);
            all.push(table);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    Some(all)
}

const LONG: usize = 2000;

#[test]
fn paper_env_episodes_5_and_10_joints() {
    let mut five = EnvSpec {
        name: "env5".into(),
        joints: 5,
        max_episode_steps: 5000,
        goal_radius: 1.0,
        episodes: vec![
            episode(
                [0.3, -0.2, 0.5, 0.1],
                [0.0, -10.0],
                wave(5, LONG, 0.8, 0.125, 0.3, 1),
            ),
            episode([-0.45, 0.4, 0.5, -0.18], [0.0, -10.0], random(5, LONG, 2)),
        ],
    };
    let seeded = seeded_episode(&five, 42, [0.0, -10.0], wave(5, LONG, 1.1, 0.125, 0.1, 3));
    five.episodes.push(seeded);
    let mut ten = EnvSpec {
        name: "env10".into(),
        joints: 10,
        max_episode_steps: 5000,
        goal_radius: 1.0,
        episodes: vec![
            episode(
                [0.0, 0.0, 0.5, 0.0],
                [0.0, -10.0],
                wave(10, LONG, 0.6, 0.125, 0.2, 4),
            ),
            episode([0.21, 0.37, 0.5, 0.19], [2.5, -7.5], random(10, LONG, 5)),
        ],
    };
    let seeded = seeded_episode(&ten, 7, [0.0, -10.0], random(10, LONG, 6));
    ten.episodes.push(seeded);
    let Some(tables) = check("env-long", vec![five, ten]) else {
        return;
    };
    for table in &tables {
        assert_eq!(
            table.len(),
            LONG + 1,
            "these episodes run to the end of their actions"
        );
        // The observation moves: the snake does not lie still.
        let (first, last) = (&table[0], &table[LONG]);
        assert!((first[4] - last[4]).abs() + (first[5] - last[5]).abs() > 0.05);
    }
}

#[test]
fn reaching_a_near_goal_terminates_with_100() {
    let spec = EnvSpec {
        name: "goal".into(),
        joints: 5,
        max_episode_steps: 5000,
        goal_radius: 1.0,
        episodes: vec![
            // With the snakebot-gym masses (a light head, 1 kg links) a wave running from tail to
            // head pushes the snake towards +y, about 1.4 m in the first 1.25 s.
            episode(
                [0.0, 0.0, 0.5, 0.0],
                [0.0, 2.5],
                wave(5, 1500, 0.9, -0.125, 0.0, 7),
            ),
            // Then a second episode in the same env after the termination, with a non-integral goal.
            episode(
                [0.1, -0.1, 0.5, 0.05],
                [0.3, 2.7],
                wave(5, 1500, 0.9, -0.125, 0.05, 8),
            ),
        ],
    };
    let Some(tables) = check("env-goal", vec![spec]) else {
        return;
    };
    for table in tables {
        let last = table.last().unwrap();
        assert!(table.len() < 1501, "the goal was not reached");
        assert_eq!((last[1], last[2], last[3]), (100.0, 1.0, 0.0));
    }
}

#[test]
fn truncation_by_the_time_limit() {
    let spec = EnvSpec {
        name: "limit".into(),
        joints: 10,
        max_episode_steps: 300,
        goal_radius: 1.0,
        episodes: vec![
            episode([0.4, 0.1, 0.5, -0.1], [0.0, -10.0], random(10, 400, 9)),
            episode(
                [-0.2, 0.3, 0.5, 0.15],
                [0.0, -10.0],
                wave(10, 400, 0.7, 0.125, 0.2, 10),
            ),
        ],
    };
    let Some(tables) = check("env-limit", vec![spec]) else {
        return;
    };
    for table in tables {
        assert_eq!(table.len(), 301);
        let last = table.last().unwrap();
        assert_eq!((last[2], last[3]), (0.0, 1.0));
    }
}

#[test]
fn hypot_is_cpython_math_hypot() {
    let Some(dir) = run_reference_script(
        "paper_env_reference.py",
        &Spec {
            hypot: Some(HypotSpec {
                count: 200_000,
                seed: 2024,
            }),
            envs: vec![],
        },
        "env-hypot",
    ) else {
        return;
    };
    let table = read_csv(&dir.join("hypot.csv"));
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(table.rows.len(), 200_000);
    let mut libm_differs = 0;
    for row in &table.rows {
        let (x, y, expected) = (row[0], row[1], row[2]);
        let ours = python_hypot(x, y);
        assert_eq!(
            ours.to_bits(),
            expected.to_bits(),
            "hypot({x:?}, {y:?}): CPython {expected:?}, ours {ours:?}"
        );
        libm_differs += (x.hypot(y).to_bits() != expected.to_bits()) as usize;
    }
    // glibc's hypot is not CPython's: it differs on a small fraction of these inputs, which is why
    // the env carries its own port.
    println!(
        "libm hypot differs from CPython's on {libm_differs} of {} samples",
        table.rows.len()
    );
}
