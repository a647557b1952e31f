//! `snake-cli train`: PPO with the native trainer, from Rust alone (no Python needed).
//!
//! The configuration comes in layers: the defaults (the paper's Table 1, from `snake_rl::config`),
//! `--config FILE.yaml`, `--set KEY=VALUE`, then the flags below. The run directory has the layout
//! of every snakesim run (see `snake_rl::rundir`).

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::output::say;
use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::{Map, Value};
use snake_rl::config::{self, RunConfig};
use snake_rl::flags::{self, FlagValue, FLAGS};
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
    /// Where the run goes (default runs/ppo-ARCH-JOINTS-PRESET-seedSEED).
    #[arg(long)]
    pub run_dir: Option<PathBuf>,
    /// Continue the run in --run-dir from its latest checkpoint.
    #[arg(long, requires = "run_dir")]
    pub resume: bool,
    /// No progress bar (default: a bar when stderr is a terminal).
    #[arg(long)]
    pub no_progress: bool,
    // The run-configuration flags (--joints, --timesteps, ...) come from snake_rl::flags::FLAGS: see
    // `with_flags`.
}

/// Adds the run configuration's flags, defined once in `snake_rl::flags::FLAGS` (those of the SB3
/// trainer aside: it needs Python).
pub fn with_flags(cmd: clap::Command) -> clap::Command {
    FLAGS.iter().filter(|f| !f.sb3_only).fold(cmd, |cmd, f| {
        let arg = clap::Arg::new(f.key)
            .long(f.key.replace('_', "-"))
            .help(f.help());
        cmd.arg(match f.value {
            FlagValue::Integer { min, max } => arg
                .value_name(f.key.to_uppercase())
                .value_parser(move |text: &str| flags::parse_integer(text, min, max)),
            FlagValue::Choice(names) => {
                arg.value_parser(clap::builder::PossibleValuesParser::new(names()))
            }
            FlagValue::Switch => arg.action(clap::ArgAction::SetTrue),
            FlagValue::Text => arg.value_name(f.key.to_uppercase()),
        })
    })
}

/// The flags given on the command line, as one configuration layer.
fn flag_layer(matches: &clap::ArgMatches) -> Value {
    let mut m = Map::new();
    for f in FLAGS.iter().filter(|f| !f.sb3_only) {
        let value = match f.value {
            FlagValue::Integer { .. } => matches.get_one::<u64>(f.key).map(|v| Value::from(*v)),
            FlagValue::Switch => matches.get_flag(f.key).then_some(Value::Bool(true)),
            FlagValue::Choice(_) | FlagValue::Text => matches
                .get_one::<String>(f.key)
                .map(|v| Value::from(v.as_str())),
        };
        if let Some(v) = value {
            m.insert(f.key.to_owned(), v);
        }
    }
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

    fn on_note(&mut self, message: &str) {
        match &self.bar {
            Some(bar) => bar.suspend(|| eprintln!("note: {message}")),
            None => eprintln!("note: {message}"),
        }
    }

    fn should_stop(&mut self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Exit status after Ctrl-C (128 + SIGINT), as shells report it.
const INTERRUPTED: u8 = 130;

/// Runs `snake-cli train` (`matches`: its own, for the configuration flags): success, or 130 after
/// Ctrl-C (the state was saved).
pub fn run(args: &TrainArgs, matches: &clap::ArgMatches) -> Result<ExitCode> {
    let mut layers = Vec::new();
    if let Some(path) = &args.config {
        let text =
            snake_core::files::read_text(path, snake_core::limits::MAX_CONFIG_BYTES, "config file")
                .map_err(|e| anyhow::anyhow!(e.message()))?;
        layers.push(config::parse_yaml(&text).with_context(|| path.display().to_string())?);
    }
    layers.push(config::parse_overrides(&args.set)?);
    layers.push(flag_layer(matches));
    let (config, run_dir) = if args.resume {
        let run_dir = args
            .run_dir
            .clone()
            .expect("clap requires --run-dir with --resume");
        let (_, saved) = snake_rl::rundir::RunDir::open(&run_dir)?;
        let mut base = serde_json::to_value(saved).expect("serialises");
        for layer in &layers {
            config::merge_layer(&mut base, layer);
        }
        (RunConfig::from_layers(&[base])?, run_dir)
    } else {
        let config = RunConfig::from_layers(&layers)?;
        let run_dir = args
            .run_dir
            .clone()
            .unwrap_or_else(|| flags::default_run_dir(&config));
        (config, run_dir)
    };
    if config.trainer != config::TrainerKind::Native {
        bail!(
            "trainer {} needs Python: run it with `snakesim train` (snake-cli trains with the native trainer only)",
            config.trainer.name()
        );
    }
    // One writer per run directory: a second one is refused here, before anything is read or written.
    let lock = trainer::lock_run(&config, &run_dir, args.resume)?;
    let prepared = trainer::prepare(&config, &lock, args.resume)?;
    let resolved = prepared.config.clone();
    let env = resolved.env_config()?;
    let body = match &env.robot {
        Some(robot) => format!("robot {} ({} joints)", robot.path().display(), env.joints()),
        None => format!("{} joints, preset {}", resolved.joints, resolved.preset),
    };
    say!(
        "run {}: PPO-{}, {body}, {} timesteps, {} envs, seed {}{}",
        run_dir.display(),
        &resolved.arch,
        resolved.timesteps,
        resolved.n_envs,
        resolved.seed,
        prepared.resume.as_ref().map_or(String::new(), |p| format!(
            " (resuming from {})",
            p.timesteps
        ))
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
    let outcome = trainer::train_prepared(&session, &lock, prepared, &mut observer);
    if let Some(bar) = &observer.bar {
        bar.finish_and_clear();
    }
    match outcome? {
        Outcome::Interrupted(s, path) => {
            // Stopping was asked for, and what was trained is saved: no `error:`.
            eprintln!(
                "interrupted at {} timesteps; saved {} and {}/model.safetensors; continue with: \
                 snake-cli train --run-dir {} --resume",
                s.timesteps,
                path.display(),
                run_dir.display(),
                run_dir.display()
            );
            Ok(ExitCode::from(INTERRUPTED))
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
            Ok(ExitCode::SUCCESS)
        }
    }
}
