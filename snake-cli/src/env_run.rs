//! `snake-cli env`: run episodes of the RL environment with a fixed policy.

use std::time::Instant;

use crate::output::say;
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use snake_core::env::{EnvConfig, ResetOptions, SnakeEnv};
use snake_core::{Gait, LateralUndulation, Preset};

/// A policy that needs no learning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Policy {
    /// Uniform random actions in [-1, 1].
    Random,
    /// All targets 0: the snake lies still.
    Zero,
    /// The lateral-undulation gait (snake.py's wave) as actions.
    Gait,
}

/// Arguments of `snake-cli env`.
#[derive(Args, Debug)]
pub struct EnvArgs {
    /// Number of joints N.
    #[arg(long, default_value_t = 5)]
    pub joints: usize,
    /// The policy that chooses actions.
    #[arg(long, value_enum, default_value_t = Policy::Gait)]
    pub policy: Policy,
    /// Episodes to run.
    #[arg(long, default_value_t = 3)]
    pub episodes: usize,
    /// Seed of the starts (episode k is the k-th reset after seeding) and of the random policy.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Parameter preset: paper or snakebot-gym (the paper's published env).
    #[arg(long, default_value = "paper")]
    pub preset: Preset,
    /// Env steps before an episode is truncated.
    #[arg(long, default_value_t = 5000)]
    pub max_steps: u64,
    /// Goal X,Y in metres.
    #[arg(long, value_parser = parse_goal, allow_hyphen_values = true, default_value = "0,-10")]
    pub goal: (f64, f64),
}

fn parse_goal(text: &str) -> Result<(f64, f64), String> {
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("'{text}' is not X,Y (two numbers separated by a comma)"))?;
    match values[..] {
        [x, y] if x.is_finite() && y.is_finite() => Ok((x, y)),
        [_, _] => Err(format!("'{text}': the goal must be finite")),
        _ => Err(format!(
            "'{text}' has {} values; expected X,Y",
            values.len()
        )),
    }
}

/// Runs the episodes and prints one line each, then the totals.
pub fn run(args: &EnvArgs) -> Result<()> {
    if args.joints < 1 {
        bail!("--joints must be at least 1, got {}", args.joints);
    }
    let max_episodes = snake_rl::config::limits::MAX_EVAL_EPISODES as usize;
    if !(1..=max_episodes).contains(&args.episodes) {
        bail!(
            "--episodes must be in [1, {max_episodes}], got {}",
            args.episodes
        );
    }
    let config = EnvConfig {
        goal: args.goal,
        max_episode_steps: args.max_steps,
        ..EnvConfig::with_preset(args.preset, args.joints)
    };
    config.validate()?;
    let mut env = SnakeEnv::new(config)?;
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut action = vec![0.0f32; args.joints];
    let mut targets = vec![0.0f64; args.joints];
    let mut obs = vec![0.0f32; env.observation_dim()];
    let scale = env.config().action_scale;

    say!(
        "env: {} joints, preset {}, policy {}, goal ({}, {}), max {} steps",
        args.joints,
        args.preset,
        args.policy
            .to_possible_value()
            .expect("no skipped variants")
            .get_name(),
        args.goal.0,
        args.goal.1,
        args.max_steps
    )?;
    say!(
        "{:>7}  {:>12}  {:>6}  {:>7}  {:>9}",
        "episode",
        "return",
        "length",
        "success",
        "distance"
    )?;
    let (mut total_steps, mut successes) = (0u64, 0usize);
    let clock = Instant::now();
    for episode in 0..args.episodes {
        let seed = (episode == 0).then_some(args.seed);
        env.reset_into(seed, ResetOptions::default(), &mut obs)?;
        let mut gait = LateralUndulation::default();
        let (mut ret, mut length) = (0.0f64, 0u64);
        loop {
            match args.policy {
                Policy::Random => action
                    .iter_mut()
                    .for_each(|a| *a = rng.gen_range(-1.0..=1.0)),
                Policy::Zero => action.fill(0.0),
                Policy::Gait => {
                    gait.next_targets(&mut targets);
                    for (a, t) in action.iter_mut().zip(&targets) {
                        *a = (t / scale) as f32;
                    }
                }
            }
            let out = env.step_into(&action, &mut obs)?;
            ret += out.reward;
            length += 1;
            if out.terminated || out.truncated {
                successes += usize::from(out.info.success);
                say!(
                    "{episode:>7}  {ret:>12.1}  {length:>6}  {:>7}  {:>8.2}m",
                    if out.info.success { "yes" } else { "no" },
                    out.info.distance
                )?;
                break;
            }
        }
        total_steps += length;
    }
    let wall = clock.elapsed().as_secs_f64();
    say!(
        "{} episodes, {} reached the goal; {total_steps} env steps in {wall:.2} s: {:.0} env steps/s",
        args.episodes,
        successes,
        total_steps as f64 / wall
    )?;
    Ok(())
}
