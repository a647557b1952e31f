//! The policy of a native checkpoint as a model file, as a finished run writes its
//! `model.safetensors` (the same writer): for shipping a run's policy at a checkpoint, such as the
//! fitted policy alone of a run with `init` (`checkpoints/model_0_steps.safetensors`).
//!
//! `cargo run --release -p snake-rl --example checkpoint_policy -- CHECKPOINT OUT.safetensors`

use std::path::PathBuf;

use snake_rl::model;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [from, to] = args.as_slice() else {
        return Err("usage: checkpoint_policy CHECKPOINT OUT.safetensors".into());
    };
    let checkpoint = model::load_checkpoint(&PathBuf::from(from))?;
    model::save_policy(&PathBuf::from(to), &checkpoint.policy)?;
    println!(
        "wrote {to}: the policy of {from} ({} timesteps, saved for: {})",
        checkpoint.policy.timesteps, checkpoint.reason
    );
    Ok(())
}
