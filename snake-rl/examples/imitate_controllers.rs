//! The controllers a run's `init` imitates, alone: success and mean return over episodes of the
//! paper's env (PPO-small's `snakebot-gym` preset), the steered one at several gains.
//!
//! `cargo run --release -p snake-rl --example imitate_controllers -- [JOINTS] [EPISODES]`

use snake_core::controllers::{Imitable, JointsSine, JOINTS_STEER_GAIN};
use snake_core::{StepBuffers, VecSnakeEnv};
use snake_rl::config::RunConfig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let joints: usize = args.get(1).map_or(Ok(10), |a| a.parse())?;
    let episodes: usize = args.get(2).map_or(Ok(16), |a| a.parse())?;
    let config = RunConfig::from_yaml(&format!("joints: {joints}\npreset: snakebot-gym"))?;
    let env = config.env_config()?;
    let mut rows = vec![(Imitable::Sine, 0.0)];
    for gain in [0.05, 0.1, JOINTS_STEER_GAIN, 0.3, 0.6, -0.15] {
        rows.push((Imitable::SteeredSine, gain));
    }
    println!("joints {joints}, {episodes} episodes (seed 7)");
    for (kind, gain) in rows {
        let started = std::time::Instant::now();
        let mut envs = VecSnakeEnv::new(env.clone(), episodes)?;
        let mut c = JointsSine::new(kind, &env, episodes)?.with_steer_gain(gain);
        let mut out = StepBuffers::for_envs(&envs);
        envs.reset(Some(7), &mut out.obs)?;
        let mut actions = vec![0.0f32; episodes * env.action_dim()];
        let mut results = vec![None; episodes];
        while results.iter().any(Option::is_none) {
            c.act(&out.obs, &mut actions);
            for f in envs.step_into(&actions, &mut out)?.iter() {
                c.reset(f.env);
                results[f.env].get_or_insert((
                    f.info.success,
                    f.info.episode_return,
                    f.info.episode_step,
                ));
            }
        }
        let n = episodes as f64;
        let success = results.iter().flatten().filter(|r| r.0).count() as f64 / n;
        let ret = results.iter().flatten().map(|r| r.1).sum::<f64>() / n;
        let steps = results.iter().flatten().map(|r| r.2 as f64).sum::<f64>() / n;
        println!(
            "{:<13} gain {gain:>5}: success {success:.2}, mean return {ret:>9.1}, mean length {steps:>6.0} ({:.1} s)",
            kind.name(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
