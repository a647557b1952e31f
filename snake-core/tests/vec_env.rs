//! [`VecSnakeEnv`]: threaded stepping is bit-identical to stepping the same envs one by one, resets
//! included; bad input fails before any env moves.

use snake_core::{EnvConfig, Error, ResetOptions, SnakeEnv, VecSnakeEnv};

/// Short episodes that end both ways: truncated after 37 steps, or terminated when the base comes
/// within 1 m of (0, 0.9) (some starts are that close already, so some episodes last one step).
fn config() -> EnvConfig {
    EnvConfig {
        goal: (0.0, 0.9),
        max_episode_steps: 37,
        ..EnvConfig::snakebot_gym(4)
    }
}

/// xorshift64* in [-1.2, 1.2), as float32.
struct Actions(u64);

impl Actions {
    fn fill(&mut self, out: &mut [f32]) {
        for a in out {
            let mut x = self.0;
            x ^= x >> 12;
            x ^= x << 25;
            x ^= x >> 27;
            self.0 = x;
            let u = (x.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
            *a = (2.4 * u - 1.2) as f32;
        }
    }
}

/// Everything one vectorised step produces, as bits.
#[derive(Debug, PartialEq)]
struct Record {
    obs: Vec<u32>,
    rewards: Vec<u64>,
    terminated: Vec<bool>,
    truncated: Vec<bool>,
    finals: Vec<(usize, Vec<u32>, u64, u64)>,
}

fn bits(v: &[f32]) -> Vec<u32> {
    v.iter().map(|x| x.to_bits()).collect()
}

const M: usize = 6;
const STEPS: usize = 700;

fn run_vec(mut envs: VecSnakeEnv) -> Vec<Record> {
    let (n, d) = (envs.action_dim(), envs.observation_dim());
    let mut obs = vec![0.0; M * d];
    envs.reset(Some(100), &mut obs).unwrap();
    let mut actions = vec![0.0f32; M * n];
    let mut gen = Actions(0x9e37_79b9_7f4a_7c15);
    let (mut rewards, mut terminated, mut truncated) =
        (vec![0.0; M], vec![false; M], vec![false; M]);
    let mut records = vec![Record {
        obs: bits(&obs),
        rewards: vec![],
        terminated: vec![],
        truncated: vec![],
        finals: vec![],
    }];
    for _ in 0..STEPS {
        gen.fill(&mut actions);
        let finals = envs
            .step(
                &actions,
                &mut obs,
                &mut rewards,
                &mut terminated,
                &mut truncated,
            )
            .unwrap();
        let finals = finals
            .iter()
            .map(|f| {
                (
                    f.env,
                    bits(f.observation),
                    f.info.distance.to_bits(),
                    f.info.episode_return.to_bits(),
                )
            })
            .collect();
        records.push(Record {
            obs: bits(&obs),
            rewards: rewards.iter().map(|r| r.to_bits()).collect(),
            terminated: terminated.clone(),
            truncated: truncated.clone(),
            finals,
        });
    }
    records
}

/// The same M envs as plain [`SnakeEnv`]s, stepped one after the other with SB3-style resets.
fn run_one_by_one() -> Vec<Record> {
    let mut envs: Vec<SnakeEnv> = (0..M).map(|_| SnakeEnv::new(config()).unwrap()).collect();
    let (n, d) = (envs[0].action_dim(), envs[0].observation_dim());
    let mut obs = vec![0.0; M * d];
    for (i, env) in envs.iter_mut().enumerate() {
        env.reset_into(
            Some(100 + i as u64),
            ResetOptions::default(),
            &mut obs[i * d..(i + 1) * d],
        )
        .unwrap();
    }
    let mut actions = vec![0.0f32; M * n];
    let mut gen = Actions(0x9e37_79b9_7f4a_7c15);
    let mut records = vec![Record {
        obs: bits(&obs),
        rewards: vec![],
        terminated: vec![],
        truncated: vec![],
        finals: vec![],
    }];
    for _ in 0..STEPS {
        gen.fill(&mut actions);
        let mut record = Record {
            obs: vec![],
            rewards: vec![],
            terminated: vec![],
            truncated: vec![],
            finals: vec![],
        };
        for (i, env) in envs.iter_mut().enumerate() {
            let o = &mut obs[i * d..(i + 1) * d];
            let out = env.step_into(&actions[i * n..(i + 1) * n], o).unwrap();
            record.rewards.push(out.reward.to_bits());
            record.terminated.push(out.terminated);
            record.truncated.push(out.truncated);
            if out.terminated || out.truncated {
                record.finals.push((
                    i,
                    bits(o),
                    out.info.distance.to_bits(),
                    out.info.episode_return.to_bits(),
                ));
                env.reset_into(None, ResetOptions::default(), o).unwrap();
            }
        }
        record.obs = bits(&obs);
        records.push(record);
    }
    records
}

#[test]
fn threads_are_bit_identical_to_one_by_one() {
    let reference = run_one_by_one();
    let terminations: usize = reference
        .iter()
        .map(|r| r.terminated.iter().filter(|t| **t).count())
        .sum();
    let truncations: usize = reference
        .iter()
        .map(|r| r.truncated.iter().filter(|t| **t).count())
        .sum();
    assert!(
        terminations >= 5 && truncations >= 20,
        "{terminations} terminations, {truncations} truncations"
    );

    let variants = [
        (
            "sequential",
            VecSnakeEnv::new(config(), M)
                .unwrap()
                .with_threads(1)
                .unwrap(),
        ),
        (
            "2 threads",
            VecSnakeEnv::new(config(), M)
                .unwrap()
                .with_threads(2)
                .unwrap(),
        ),
        (
            "5 threads",
            VecSnakeEnv::new(config(), M)
                .unwrap()
                .with_threads(5)
                .unwrap(),
        ),
        ("global pool", VecSnakeEnv::new(config(), M).unwrap()),
    ];
    for (name, envs) in variants {
        let records = run_vec(envs);
        for (step, (a, b)) in reference.iter().zip(&records).enumerate() {
            assert_eq!(a, b, "{name}: step {step} differs from stepping one by one");
        }
    }
}

#[test]
fn reset_seeds_env_i_with_seed_plus_i() {
    let mut envs = VecSnakeEnv::new(config(), 3).unwrap();
    let d = envs.observation_dim();
    let mut obs = vec![0.0; 3 * d];
    envs.reset(Some(u64::MAX), &mut obs).unwrap();
    for i in 0..3 {
        let mut single = SnakeEnv::new(config()).unwrap();
        let (o, info) = single
            .reset(
                Some(u64::MAX.wrapping_add(i as u64)),
                ResetOptions::default(),
            )
            .unwrap();
        assert_eq!(&obs[i * d..(i + 1) * d], &o[..]);
        assert_eq!(envs.info(i).unwrap().start, info.start);
    }
}

#[test]
fn reset_each_seeds_each_env_with_its_own_seed() {
    // Env i with seeds[i]; None continues env i's stream, as a reset without a seed does.
    let mut envs = VecSnakeEnv::new(config(), 3).unwrap();
    let d = envs.observation_dim();
    let mut obs = vec![0.0; 3 * d];
    envs.reset(Some(10), &mut obs).unwrap();
    envs.reset_each(&[Some(7), None, Some(u64::MAX)], &mut obs)
        .unwrap();
    let mut middle = SnakeEnv::new(config()).unwrap();
    middle.reset(Some(11), ResetOptions::default()).unwrap();
    let expected = [
        SnakeEnv::new(config())
            .unwrap()
            .reset(Some(7), ResetOptions::default()),
        middle.reset(None, ResetOptions::default()),
        SnakeEnv::new(config())
            .unwrap()
            .reset(Some(u64::MAX), ResetOptions::default()),
    ];
    for (i, single) in expected.into_iter().enumerate() {
        let (o, info) = single.unwrap();
        assert_eq!(&obs[i * d..(i + 1) * d], &o[..], "env {i}");
        assert_eq!(envs.info(i).unwrap().start, info.start, "env {i}");
    }
    let err = envs.reset_each(&[Some(1), Some(2)], &mut obs).unwrap_err();
    assert!(
        err.to_string().contains("seeds must have 3 values, got 2"),
        "{err}"
    );
}

#[test]
fn bad_input_fails_before_any_env_moves() {
    let mut envs = VecSnakeEnv::new(EnvConfig::snakebot_gym(4), 2).unwrap();
    let (n, d) = (envs.action_dim(), envs.observation_dim());
    let mut obs = vec![0.0; 2 * d];
    let (mut r, mut te, mut tr) = (vec![0.0; 2], vec![false; 2], vec![false; 2]);
    let actions = vec![0.1f32; 2 * n];
    let err = envs
        .step(&actions, &mut obs, &mut r, &mut te, &mut tr)
        .unwrap_err();
    assert!(
        matches!(&err, Error::InvalidArgument(m) if m.contains("reset")),
        "{err}"
    );

    envs.reset(Some(1), &mut obs).unwrap();
    let before = obs.clone();
    let short = vec![0.1f32; 2 * n - 1];
    let err = envs
        .step(&short, &mut obs, &mut r, &mut te, &mut tr)
        .unwrap_err();
    assert!(err.to_string().contains("actions"), "{err}");
    let mut nan = actions.clone();
    nan[n + 2] = f32::NAN;
    let err = envs
        .step(&nan, &mut obs, &mut r, &mut te, &mut tr)
        .unwrap_err();
    assert!(err.to_string().contains("env 1: action[2]"), "{err}");
    let err = envs
        .step(&actions, &mut obs[..d], &mut r, &mut te, &mut tr)
        .unwrap_err();
    assert!(err.to_string().contains("obs_out"), "{err}");
    let err = envs
        .step(&actions, &mut obs, &mut r[..1], &mut te, &mut tr)
        .unwrap_err();
    assert!(err.to_string().contains("rewards_out"), "{err}");
    assert_eq!(obs, before);
    assert!(envs.envs().all(|e| e.episode_step() == 0));

    envs.step(&actions, &mut obs, &mut r, &mut te, &mut tr)
        .unwrap();
    assert!(envs.envs().all(|e| e.episode_step() == 1));
    assert!(VecSnakeEnv::new(EnvConfig::snakebot_gym(4), 0).is_err());
    assert!(VecSnakeEnv::new(EnvConfig::snakebot_gym(4), 1)
        .unwrap()
        .with_threads(0)
        .is_err());
    let mut one = vec![0.0; d];
    assert!(envs
        .reset_env(2, None, ResetOptions::default(), &mut one)
        .is_err());
    envs.reset_env(1, Some(5), ResetOptions::default(), &mut one)
        .unwrap();
    assert_eq!(envs.envs().nth(1).unwrap().episode_step(), 0);
}
