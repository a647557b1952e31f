//! `snake-cli train`: PPO with the native trainer, from Rust alone (no Python needed).
//!
//! The configuration comes in layers: the defaults (the paper's Table 1, from `snake_rl::config`),
//! `--config FILE.yaml`, `--set KEY=VALUE`, then the flags below. The run directory has the layout
//! of every snakesim run (see `snake_rl::rundir`).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::output::say;
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Map, Value};
use snake_rl::config::{self, RunConfig};
use snake_rl::rundir::EvaluationRow;
use snake_rl::trainer::{self, Observer, Outcome, Progress, Session};

/// Arguments of `snake-cli train`. Flags left out keep the value of `--config` (or the default).
#[derive(Args, Debug)]
pub struct TrainArgs {
    /// A run configuration (YAML; see snake-py/configs/).
    #[arg(long, value_name = "FILE.yaml")]
    pub config: Option<PathBuf>,
    /// Any configuration key, e.g. ppo.n_steps=256 or env.max_episode_steps=1000 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Where the run goes (default runs/native-ARCH-JOINTS-PRESET-seedSEED).
    #[arg(long)]
    pub run_dir: Option<PathBuf>,
    /// Continue the run in --run-dir from its latest checkpoint.
    #[arg(long, requires = "run_dir")]
    pub resume: bool,
    /// No progress bar (default: a bar when stderr is a terminal).
    #[arg(long)]
    pub no_progress: bool,
    /// Snake joints.
    #[arg(long)]
    pub joints: Option<u64>,
    /// Network: small (pi/vf [64, 64]) or large (shared [128, 128] first).
    #[arg(long)]
    pub arch: Option<String>,
    /// Robot preset: paper or snakebot-gym.
    #[arg(long)]
    pub preset: Option<String>,
    /// Total timesteps.
    #[arg(long)]
    pub timesteps: Option<u64>,
    /// Parallel envs.
    #[arg(long)]
    pub n_envs: Option<u64>,
    /// Seed.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Evaluate every N timesteps (0: at the end only).
    #[arg(long)]
    pub eval_freq: Option<u64>,
    /// Episodes per evaluation.
    #[arg(long)]
    pub eval_episodes: Option<u64>,
    /// Seed of the evaluation episodes.
    #[arg(long)]
    pub eval_seed: Option<u64>,
    /// Checkpoint every N timesteps (0: only the final one).
    #[arg(long)]
    pub checkpoint_freq: Option<u64>,
    /// Normalise observations and rewards (SB3's VecNormalize).
    #[arg(long)]
    pub normalize: bool,
    /// Threads for the envs and the updates.
    #[arg(long)]
    pub threads: Option<u64>,
}

/// Help texts that quote the defaults of the one configuration type.
pub fn with_default_help(cmd: clap::Command) -> clap::Command {
    let d = RunConfig::default();
    let help = [
        ("joints", format!("Snake joints (default {})", d.joints)),
        (
            "arch",
            format!(
                "Network: small (pi/vf [64, 64]) or large (shared [128, 128] first) (default {})",
                d.arch
            ),
        ),
        (
            "preset",
            format!("Robot preset: paper or snakebot-gym (default {})", d.preset),
        ),
        (
            "timesteps",
            format!("Total timesteps (default {})", d.timesteps),
        ),
        ("n_envs", format!("Parallel envs (default {})", d.n_envs)),
        ("seed", format!("Seed (default {})", d.seed)),
        (
            "eval_freq",
            format!(
                "Evaluate every N timesteps; 0: at the end only (default {})",
                d.eval_freq
            ),
        ),
        (
            "eval_episodes",
            format!("Episodes per evaluation (default {})", d.eval_episodes),
        ),
        (
            "eval_seed",
            format!(
                "Seed of the evaluation episodes (default seed + {})",
                config::EVAL_SEED_OFFSET
            ),
        ),
        (
            "checkpoint_freq",
            format!(
                "Checkpoint every N timesteps; 0: only the final one (default {})",
                d.checkpoint_freq
            ),
        ),
        (
            "threads",
            "Threads for the envs and the updates (default: one per core)".to_owned(),
        ),
    ];
    help.into_iter()
        .fold(cmd, |cmd, (name, text)| cmd.mut_arg(name, |a| a.help(text)))
}

/// The configuration layers of the command line, as one JSON mapping.
fn flag_layer(args: &TrainArgs) -> Value {
    let mut m = Map::new();
    let mut put = |key: &str, v: Option<Value>| {
        if let Some(v) = v {
            m.insert(key.to_owned(), v);
        }
    };
    put("joints", args.joints.map(Value::from));
    put("arch", args.arch.clone().map(Value::from));
    put("preset", args.preset.clone().map(Value::from));
    put("timesteps", args.timesteps.map(Value::from));
    put("n_envs", args.n_envs.map(Value::from));
    put("seed", args.seed.map(Value::from));
    put("eval_freq", args.eval_freq.map(Value::from));
    put("eval_episodes", args.eval_episodes.map(Value::from));
    put("eval_seed", args.eval_seed.map(Value::from));
    put("checkpoint_freq", args.checkpoint_freq.map(Value::from));
    put("normalize", args.normalize.then_some(Value::Bool(true)));
    put("threads", args.threads.map(Value::from));
    Value::Object(m)
}

/// A progress bar of timesteps with timesteps/s and the latest evaluation; stops on Ctrl-C.
struct Bar {
    bar: Option<ProgressBar>,
    stop: Arc<AtomicBool>,
    last_eval: Option<EvaluationRow>,
}

impl Bar {
    fn message(&self) -> String {
        self.last_eval.map_or(String::new(), |e| {
            format!(
                "eval R {:.0}, success {:.0}%",
                e.mean_return,
                100.0 * e.success_rate
            )
        })
    }
}

impl Observer for Bar {
    fn on_start(&mut self, start: u64, total: u64) {
        if let Some(bar) = &self.bar {
            bar.set_length(total);
            bar.set_position(start);
        }
    }

    fn on_step(&mut self, timesteps: u64) {
        if let Some(bar) = &self.bar {
            bar.set_position(timesteps);
        }
    }

    fn on_update(&mut self, p: &Progress) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!(
                "{:.0} steps/s {}",
                p.timesteps_per_second,
                self.message()
            ));
        }
    }

    fn on_evaluation(&mut self, row: &EvaluationRow) {
        self.last_eval = Some(*row);
        match &self.bar {
            Some(bar) => bar.set_message(self.message()),
            None => eprintln!("{} timesteps: {}", row.timesteps, self.message()),
        }
    }

    fn should_stop(&mut self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Runs `snake-cli train`.
pub fn run(args: &TrainArgs) -> Result<()> {
    let mut layers = Vec::new();
    if let Some(path) = &args.config {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read config file {}", path.display()))?;
        layers.push(config::parse_yaml(&text).with_context(|| path.display().to_string())?);
    }
    layers.push(config::parse_overrides(&args.set)?);
    layers.push(flag_layer(args));
    let (config, run_dir) = if args.resume {
        let run_dir = args
            .run_dir
            .clone()
            .expect("clap requires --run-dir with --resume");
        let (_, saved) = snake_rl::rundir::RunDir::open(&run_dir)?;
        let mut base = serde_json::to_value(saved).expect("serialises");
        for layer in &layers {
            config::merge(&mut base, layer);
        }
        (RunConfig::from_layers(&[base])?, run_dir)
    } else {
        let config = RunConfig::from_layers(&layers)?;
        let run_dir = args.run_dir.clone().unwrap_or_else(|| {
            PathBuf::from("runs").join(format!(
                "native-{}-{}-{}-seed{}",
                config.arch, config.joints, config.preset, config.seed
            ))
        });
        (config, run_dir)
    };
    if config.trainer != config::TrainerKind::Native {
        bail!(
            "trainer {} needs Python: run it with `snakesim train` (snake-cli trains with the native trainer only)",
            config.trainer.name()
        );
    }
    let (resolved, resume_from) = trainer::prepare(&config, &run_dir, args.resume)?;
    let env = resolved.env_config()?;
    let body = match &env.robot {
        Some(robot) => format!("robot {} ({} joints)", robot.path().display(), env.joints()),
        None => format!("{} joints, preset {}", resolved.joints, resolved.preset),
    };
    say!(
        "run {}: PPO-{}, {body}, {} timesteps, {} envs, seed {}{}",
        run_dir.display(),
        resolved.arch,
        resolved.timesteps,
        resolved.n_envs,
        resolved.seed,
        resume_from.map_or(String::new(), |(s, _)| format!(" (resuming from {s})"))
    )?;

    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || flag.store(true, Ordering::Relaxed))
        .context("cannot install the Ctrl-C handler")?;
    let show = !args.no_progress && std::io::IsTerminal::is_terminal(&std::io::stderr());
    let bar = show.then(|| {
        let bar = ProgressBar::new(resolved.timesteps);
        bar.set_style(
            ProgressStyle::with_template(
                "train {bar:30} {human_pos}/{human_len} [{elapsed_precise}<{eta_precise}] {msg}",
            )
            .expect("a valid template"),
        );
        bar
    });
    let mut observer = Bar {
        bar,
        stop,
        last_eval: None,
    };
    let session = Session {
        config,
        run_dir: run_dir.clone(),
        resume: args.resume,
        versions: Map::new(),
    };
    let outcome = trainer::train(&session, &mut observer);
    if let Some(bar) = &observer.bar {
        bar.finish_and_clear();
    }
    match outcome? {
        Outcome::Interrupted(s, path) => {
            bail!(
                "interrupted at {} timesteps; saved {} and {}/model.safetensors; continue with: \
                 snake-cli train --run-dir {} --resume",
                s.timesteps,
                path.display(),
                run_dir.display(),
                run_dir.display()
            )
        }
        Outcome::Finished(s) => {
            say!(
                "trained {} timesteps in {:.1} s: {:.0} timesteps/s ({:.0} without evaluations; rollouts {:.1} s, \
                 updates {:.1} s, {} threads); memory {:.1} MiB after the first update, {:.1} MiB at the end",
                s.timesteps - s.start_timesteps,
                s.seconds,
                s.timesteps_per_second(),
                s.training_timesteps_per_second(),
                s.rollout_seconds,
                s.update_seconds,
                s.threads,
                s.rss_mib.0,
                s.rss_mib.1
            )?;
            if let Some(e) = s.last_evaluation {
                say!(
                    "evaluation at {} timesteps ({} episodes): mean return {:.1} ± {:.1}, success rate {:.2}, \
                     mean steps to goal {}",
                    e.timesteps,
                    resolved.eval_episodes,
                    e.mean_return,
                    e.std_return,
                    e.success_rate,
                    e.mean_steps_to_goal.map_or("-".into(), |v| format!("{v:.0}"))
                )?;
            }
            say!(
                "wrote {}/model.safetensors, evaluations.csv, config.yaml, versions.json, tb/, checkpoints/",
                run_dir.display()
            )?;
            Ok(())
        }
    }
}
