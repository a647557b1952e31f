//! Step cost with randomized physics (every parameter, non-zero width) against the plain env, in
//! one process, alternating: `cargo run --release -p snake-core --example randomize_bench`.

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

fn main() {
    let plain = EnvConfig::for_task(Task::Goal, Preset::Paper, 10);
    let randomized = EnvConfig {
        randomize: Some(Randomize {
            ground_friction: Some([0.3, 0.9]),
            mass_scale: Some([0.8, 1.2]),
            effort_scale: Some([0.7, 1.0]),
            kp_scale: Some([0.9, 1.1]),
            kd_scale: Some([0.9, 1.1]),
            latency_steps: Some([1.0, 2.0]),
            obs_noise: Some([0.005, 0.01]),
            skin_friction_scale: None,
        }),
        ..plain.clone()
    };
    let steps = 20_000;
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..7 {
        a.push(run(&plain, steps));
        b.push(run(&randomized, steps));
    }
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    println!(
        "plain      us/step min {:.2} median {:.2} all {a:.2?}",
        a[0], a[3]
    );
    println!(
        "randomized us/step min {:.2} median {:.2} all {b:.2?}",
        b[0], b[3]
    );
    println!("ratio min {:.3} median {:.3}", b[0] / a[0], b[3] / a[3]);
}
