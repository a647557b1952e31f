//! Step cost with randomized physics (every parameter, non-zero width) against the plain env, in
//! one process, alternating: `cargo run --release -p snake-core --example randomize_bench [STEPS]
//! [ROUNDS]` (defaults 2000 env steps of the 10-joint goal env, 9 rounds: about two minutes on one
//! core). This VM's timings drift by tens of percent between runs: read the minimum.

use std::time::Instant;

use snake_core::{EnvConfig, Preset, Randomize, ResetOptions, SnakeEnv, Task};

fn run(config: &EnvConfig, steps: usize) -> f64 {
    let mut env = SnakeEnv::new(config.clone()).expect("env");
    let n = env.action_dim();
    let mut obs = vec![0.0f32; env.observation_dim()];
    env.reset_into(Some(1), ResetOptions::default(), &mut obs)
        .expect("reset");
    let start = Instant::now();
    for t in 0..steps {
        let action: Vec<f32> = (0..n).map(|j| ((t + j) as f32 * 0.1).sin()).collect();
        let out = env.step_into(&action, &mut obs).expect("step");
        if out.terminated || out.truncated {
            env.reset_into(None, ResetOptions::default(), &mut obs)
                .expect("reset");
        }
    }
    start.elapsed().as_secs_f64() / steps as f64 * 1e6
}

/// Median and minimum of `rounds` runs of each config, alternating so that drift hits all alike.
fn main() {
    let plain = EnvConfig::for_task(Task::Goal, Preset::Paper, 10);
    let with = |randomize: Randomize| EnvConfig {
        randomize: Some(randomize),
        ..plain.clone()
    };
    // The mechanism's cost: every key drawn and applied, the physics at its nominal values (the
    // plane's friction 0.5, scales 1), one step of latency and noise on every observation, so the
    // contacts are those of the plain env and only the randomization's own work differs.
    let mechanism = with(Randomize {
        ground_friction: Some([0.5, 0.5]),
        mass_scale: Some([1.0, 1.0]),
        effort_scale: Some([1.0, 1.0]),
        kp_scale: Some([1.0, 1.0]),
        kd_scale: Some([1.0, 1.0]),
        latency_steps: Some([1.0, 1.0]),
        obs_noise: Some([0.01, 0.01]),
        skin_friction_scale: None,
        current_speed: None,
        current_heading: None,
    });
    // A wide distribution: its physics itself costs more or less (other contacts), not the mechanism.
    let distribution = with(Randomize {
        ground_friction: Some([0.3, 0.9]),
        mass_scale: Some([0.8, 1.2]),
        effort_scale: Some([0.7, 1.0]),
        kp_scale: Some([0.9, 1.1]),
        kd_scale: Some([0.9, 1.1]),
        latency_steps: Some([1.0, 2.0]),
        obs_noise: Some([0.005, 0.01]),
        skin_friction_scale: None,
        current_speed: None,
        current_heading: None,
    });
    let mut args = std::env::args().skip(1);
    let steps: usize = args.next().map_or(2_000, |s| s.parse().expect("STEPS"));
    let rounds: usize = args.next().map_or(9, |s| s.parse().expect("ROUNDS"));
    let configs = [
        ("plain", &plain),
        ("mechanism", &mechanism),
        ("distribution", &distribution),
    ];
    let mut times = vec![Vec::new(); configs.len()];
    for _ in 0..rounds {
        for (t, (_, config)) in times.iter_mut().zip(&configs) {
            t.push(run(config, steps));
        }
    }
    for t in &mut times {
        t.sort_by(f64::total_cmp);
    }
    let (min0, med0) = (times[0][0], times[0][rounds / 2]);
    for ((name, _), t) in configs.iter().zip(&times) {
        let (min, med) = (t[0], t[rounds / 2]);
        println!(
            "{name:<12} us/env step min {min:8.1} median {med:8.1}   ratio to plain min {:.3} median {:.3}",
            min / min0,
            med / med0
        );
    }
}
