//! `snake-cli probe`: Li et al.'s plate experiment in the granular medium of a world file
//! (`snake_core::media::probe`): the force on a thin plate at an angle, depth and velocity, per unit
//! area too, beside the law integrated over the plate. How a user fits `zeta` to their own sand.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use snake_core::media::probe::{granular, probe as run_probe, Plate};
use snake_core::WorldSpec;

use crate::output::say;

/// Arguments of `snake-cli probe`.
#[derive(Args, Debug)]
pub struct ProbeArgs {
    /// World file with a granular medium (`media: [{medium: granular, ...}]`); the first one is probed.
    #[arg(long)]
    pub world: PathBuf,
    /// The plate's LENGTH,WIDTH in metres (length in the plane of motion).
    #[arg(long, value_name = "LENGTH,WIDTH", value_delimiter = ',', num_args = 1)]
    pub plate: Vec<f64>,
    /// Angle of attack beta, degrees, in [-90, 90] (Li et al. 2013's convention).
    #[arg(long, allow_negative_numbers = true)]
    pub beta: f64,
    /// Intrusion angle gamma, degrees below the horizontal, in [-90, 90] (90: straight down).
    #[arg(long, allow_negative_numbers = true)]
    pub gamma: f64,
    /// Depth of the plate's centre below the surface, metres.
    #[arg(long)]
    pub depth: f64,
    /// Speed, m/s (the law is rate-independent: it sets only how fast the elastic part fills).
    #[arg(long, default_value_t = 0.01)]
    pub speed: f64,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `snake-cli probe`.
pub fn probe(args: &ProbeArgs) -> Result<()> {
    let [length, width] = args.plate[..] else {
        anyhow::bail!(
            "--plate: expected LENGTH,WIDTH (two numbers), got {} values",
            args.plate.len()
        );
    };
    let plate = Plate {
        length,
        width,
        beta: args.beta,
        gamma: args.gamma,
        depth: args.depth,
        speed: args.speed,
    };
    let flag = |name: &str| match name {
        "length" | "width" => format!("--plate {name}"),
        other => format!("--{other}"),
    };
    plate.check(flag)?;
    let spec = WorldSpec::load(&args.world)?;
    let medium =
        granular(&spec.media).with_context(|| format!("--world {}", args.world.display()))?;
    let r =
        run_probe(medium, &plate).with_context(|| format!("--world {}", args.world.display()))?;
    if args.json {
        let text = serde_json::to_string_pretty(&serde_json::json!({
            "world": args.world,
            "plate": {"length": length, "width": width, "beta": args.beta, "gamma": args.gamma,
                      "depth": args.depth, "speed": args.speed},
            "zeta": medium.zeta,
            "result": r,
        }))?;
        say!("{text}")?;
    } else {
        say!(
            "plate {length} x {width} m, beta {} deg, gamma {} deg, depth {} m, in zeta {} N/m^3\n\
             force     x {:+.6} N  z {:+.6} N\n\
             per area  x {:+.3} N/m^2  z {:+.3} N/m^2\n\
             the law   x {:+.6} N  z {:+.6} N  (alpha_x {:.4}, alpha_z {:.4}; {} elements)",
            args.beta,
            args.gamma,
            args.depth,
            medium.zeta,
            r.force_x,
            r.force_z,
            r.stress_x,
            r.stress_z,
            r.law_x,
            r.law_z,
            r.alpha_x,
            r.alpha_z,
            r.elements
        )?;
    }
    Ok(())
}
