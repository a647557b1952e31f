//! `snake-cli`: run the snake's gait, run the environment, benchmark.

mod atlas;
mod bench;
mod env_run;
mod flags;
mod output;
mod plot;
mod probe;
mod python;
mod recording;
mod run;
mod targets;
mod trace;
mod train;
mod trajectory;

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// snakesim: the "Simulating Snakes" robot on Bullet, bit for bit as pybullet 3.2.7 moves it.
#[derive(Parser)]
#[command(name = "snake-cli", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a gait (or joint targets) on the built-in snake or a URDF robot and report its motion;
    /// optionally write the trajectory (CSV), a plot (PNG) and a Rerun recording (.rrd).
    Run(run::RunArgs),
    /// Run every robot x gait x ground briefly and write the gait atlas (docs/gaits.md and its path
    /// pictures).
    Atlas(atlas::AtlasArgs),
    /// Run episodes of the RL environment with a fixed policy (random, zero or the gait).
    Env(env_run::EnvArgs),
    /// Measure physics steps per second (and pybullet's, when its reference environment exists).
    Bench(bench::BenchArgs),
    /// Train PPO with the native trainer (the paper's settings by default); no Python needed.
    Train(train::TrainArgs),
    /// Li et al.'s plate experiment in a world's granular medium: the force on a thin plate at an
    /// angle, depth and speed, beside the law integrated over it.
    Probe(probe::ProbeArgs),
}

fn main() -> ExitCode {
    let command = Cli::command().mut_subcommand("train", train::with_flags);
    let matches = command.get_matches();
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => e.exit(),
    };
    let result = match cli.command {
        Command::Run(args) => run::run(&args).map(|()| ExitCode::SUCCESS),
        Command::Atlas(args) => atlas::atlas(&args).map(|()| ExitCode::SUCCESS),
        Command::Env(args) => env_run::run(&args).map(|()| ExitCode::SUCCESS),
        Command::Bench(args) => bench::bench(&args).map(|()| ExitCode::SUCCESS),
        Command::Probe(args) => probe::probe(&args).map(|()| ExitCode::SUCCESS),
        Command::Train(args) => train::run(
            &args,
            matches
                .subcommand_matches("train")
                .expect("the train subcommand's matches"),
        ),
    };
    match result {
        Ok(code) => code,
        // Whoever read our output has gone (`snake-cli env ... | head -1`): stop quietly, as Unix tools do.
        Err(err) if output::is_closed_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            // One line: the error and its causes, for people and for scripts.
            // At most MAX_ERROR_CHARS, escaped: the causes may quote a user's value at any length.
            eprintln!("error: {}", snake_core::error::one_line(format!("{err:#}")));
            ExitCode::FAILURE
        }
    }
}
