//! `snake-cli env`: run episodes of the RL environment with a fixed policy.

use std::time::Instant;

use crate::output::say;
use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use snake_core::env::{ResetOptions, SnakeEnv};
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

/// Arguments of `snake-cli env`. The env's own flags (`--joints`, `--preset`, `--task`,
/// `--max-episode-steps`, `--goal`) and `--set KEY=VALUE` are env keywords, read by snake-rl's
/// `env_from_keywords` exactly as `snakesim.SnakeEnv(**keywords)` and a run configuration's `env` table
/// are: an absent flag takes the env's own default (`EnvConfig`), so no default is restated here.
#[derive(Args, Debug)]
pub struct EnvArgs {
    /// The policy that chooses actions.
    #[arg(long, value_enum, default_value_t = Policy::Gait)]
    pub policy: Policy,
    /// Episodes to run.
    #[arg(long, default_value_t = 3)]
    pub episodes: usize,
    /// Seed of the starts (episode k is the k-th reset after seeding) and of the random policy.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Number of joints N (default: the env's, 5).
    #[arg(long)]
    pub joints: Option<u64>,
    /// Parameter preset: paper or snakebot-gym, the paper's published env (default: paper).
    #[arg(long)]
    pub preset: Option<Preset>,
    /// The task whose defaults the other keywords override: paper (snakesim/Snake-v0), goal
    /// (SnakeGoal-v0), pegs (SnakePegs-v0), rough (SnakeRough-v0) or swim (SnakeSwim-v0) (default:
    /// paper).
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(
        snake_core::env::Task::ALL.map(snake_core::env::Task::name)
    ))]
    pub task: Option<String>,
    /// Env steps before an episode is truncated (default: the task's; 5000 for the paper's).
    #[arg(long, alias = "max-steps")]
    pub max_episode_steps: Option<u64>,
    /// Goal X,Y in metres (default: the task's; 0,-10 for the paper's).
    #[arg(long, value_parser = parse_goal, allow_hyphen_values = true)]
    pub goal: Option<(f64, f64)>,
    /// Any env keyword, as snakesim.SnakeEnv takes it: e.g. world=worlds/rough.yaml,
    /// robot=robots/wheeled-8.yaml, reward.progress_weight=1, snake.skin_friction.forward=0.05
    /// (repeatable; the flags above win).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
}

impl EnvArgs {
    /// The env keywords the flags name, `--set` first, the flags over them.
    fn keywords(&self) -> Result<serde_json::Map<String, serde_json::Value>> {
        use serde_json::{json, Value};
        let mut keywords = match snake_rl::config::parse_overrides(&self.set)
            .map_err(|e| anyhow::anyhow!("--set: {e}"))?
        {
            Value::Object(map) => map,
            _ => unreachable!("parse_overrides returns a mapping"),
        };
        if let Some(joints) = self.joints {
            keywords.insert("joints".into(), json!(joints));
        }
        if let Some(preset) = self.preset {
            keywords.insert("preset".into(), json!(preset.name()));
        }
        if let Some(task) = &self.task {
            keywords.insert("task".into(), json!(task));
        }
        if let Some(steps) = self.max_episode_steps {
            keywords.insert("max_episode_steps".into(), json!(steps));
        }
        if let Some((x, y)) = self.goal {
            keywords.insert("goal".into(), json!([x, y]));
        }
        Ok(keywords)
    }
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
    let max_episodes = snake_rl::config::limits::MAX_EVAL_EPISODES as usize;
    if !(1..=max_episodes).contains(&args.episodes) {
        bail!(
            "--episodes must be in [1, {max_episodes}], got {}",
            args.episodes
        );
    }
    let keywords = args.keywords()?;
    let config = snake_rl::config::env_from_keywords(&keywords).map_err(|e| {
        // Name the flag where one set the keyword, as the other commands do.
        let flag = match e.key() {
            Some("max_episode_steps") if args.max_episode_steps.is_some() => "--max-episode-steps",
            Some("goal") if args.goal.is_some() => "--goal",
            Some("joints") if args.joints.is_some() => "--joints",
            _ => return anyhow::anyhow!("{e}"),
        };
        anyhow::anyhow!("{flag}: {}", e.detail())
    })?;
    config.validate()?;
    let joints = config.joints();
    if args.policy == Policy::Gait && config.action_dim() != joints {
        bail!(
            "--policy gait gives one joint target per joint, but this env's actions are {} values \
             (the goal task steers a wave: use --policy zero or random)",
            config.action_dim()
        );
    }
    let mut env = SnakeEnv::new(config)?;
    let mut rng = ChaCha8Rng::seed_from_u64(args.seed);
    let mut action = vec![0.0f32; env.action_dim()];
    let mut targets = vec![0.0f64; joints];
    let mut obs = vec![0.0f32; env.observation_dim()];
    let scale = env.config().action_scale;

    let max_steps = env.config().max_episode_steps;
    let goal = match env.config().goal_distribution {
        None => format!("goal ({}, {})", env.config().goal.0, env.config().goal.1),
        Some(_) => "goals drawn each episode".to_owned(),
    };
    say!(
        "env: {joints} joints, preset {}, policy {}, {goal}, max {max_steps} steps",
        keywords
            .get("preset")
            .and_then(|p| p.as_str())
            .unwrap_or(snake_rl::config::RunConfig::default().preset.name()),
        args.policy
            .to_possible_value()
            .expect("no skipped variants")
            .get_name(),
    )?;
    let randomized = env.config().randomize.is_some();
    say!(
        "{:>7}  {:>12}  {:>6}  {:>7}  {:>9}{}",
        "episode",
        "return",
        "length",
        "success",
        "distance",
        if randomized { "  physics" } else { "" }
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
                // With `randomize`, what the episode drew (its keys, in their order).
                let physics: String = if randomized {
                    let drawn: Vec<String> = env
                        .physics()
                        .values()
                        .map(|(key, value)| match key {
                            "latency_steps" => format!("{key} {value}"),
                            _ => format!("{key} {value:.4}"),
                        })
                        .collect();
                    format!("  {}", drawn.join(", "))
                } else {
                    String::new()
                };
                say!(
                    "{episode:>7}  {ret:>12.1}  {length:>6}  {:>7}  {:>8.2}m{physics}",
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
