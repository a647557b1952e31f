//! Memory stays flat over many short episodes: every reset builds a new Bullet world and drops the
//! old one, so a leak in either would grow the resident set with the episode count.
//!
//! `cargo test --release -p snakesim-tests --test env_memory -- --nocapture` prints the figures.
//! The long run is ignored by default; `SNAKESIM_LEAK_STEPS` sets its length:
//! `SNAKESIM_LEAK_STEPS=1000000 cargo test --release -p snakesim-tests --test env_memory -- --ignored --nocapture`.

use snake_core::{EnvConfig, ResetOptions, SnakeEnv};

/// Resident set size of this process in bytes (`VmRSS` of `/proc/self/status`, which is
/// `/proc/self/statm`'s resident pages already in kB, so no page size is assumed).
fn rss_bytes() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").expect("/proc/self/status (Linux)");
    let line = status
        .lines()
        .find(|l| l.starts_with("VmRSS:"))
        .expect("a VmRSS line");
    let kib: u64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    kib * 1024
}

const MIB: f64 = 1024.0 * 1024.0;

/// Runs `steps` env steps over episodes of `episode_steps`, with random actions; returns
/// (episodes, RSS after warm-up, RSS at the end, largest RSS seen after warm-up).
fn churn(steps: u64, episode_steps: u64, warm_up: u64) -> (u64, u64, u64, u64) {
    // Resting on the plane from the start (the paper's 0.25 m drop takes 54 steps), so that every
    // step of these short episodes has ground contacts.
    let mut config = EnvConfig {
        max_episode_steps: episode_steps,
        ..EnvConfig::snakebot_gym(5)
    };
    config.start.z = 0.25;
    let mut env = SnakeEnv::new(config).unwrap();
    let mut obs = vec![0.0f32; env.observation_dim()];
    env.reset_into(Some(0), ResetOptions::default(), &mut obs)
        .unwrap();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut action = [0.0f32; 5];
    let (mut episodes, mut after_warm_up, mut peak) = (1, 0, 0);
    for step in 1..=steps {
        for a in &mut action {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            *a = ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0;
        }
        let out = env.step_into(&action, &mut obs).unwrap();
        if out.terminated || out.truncated {
            env.reset_into(None, ResetOptions::default(), &mut obs)
                .unwrap();
            episodes += 1;
        }
        if step == warm_up {
            after_warm_up = rss_bytes();
        }
        if step > warm_up && step % 1000 == 0 {
            peak = peak.max(rss_bytes());
        }
    }
    (episodes, after_warm_up, rss_bytes(), peak)
}

fn report(steps: u64, (episodes, warm, end, peak): (u64, u64, u64, u64)) {
    println!(
        "{steps} steps, {episodes} episodes: RSS after warm-up {:.2} MiB, at the end {:.2} MiB \
         (peak {:.2} MiB, growth {:+.2} MiB)",
        warm as f64 / MIB,
        end as f64 / MIB,
        peak as f64 / MIB,
        (end as f64 - warm as f64) / MIB
    );
}

#[test]
fn rss_stays_flat_over_thousands_of_episodes() {
    // 200k steps in 4,000 episodes of 50 steps (each reset builds a new world): about 25 s in release.
    let steps = 200_000;
    let result = churn(steps, 50, 20_000);
    report(steps, result);
    let (episodes, warm, _end, peak) = result;
    assert!(episodes >= 4_000);
    // Allow allocator noise, not a leak: a leak of even 300 bytes per episode would add over 1 MiB.
    let growth = peak.saturating_sub(warm) as f64 / MIB;
    assert!(growth < 1.0, "RSS grew by {growth:.2} MiB after warm-up");
}

#[test]
#[ignore = "long: a million steps by default (SNAKESIM_LEAK_STEPS)"]
fn rss_stays_flat_over_a_million_steps() {
    let steps = std::env::var("SNAKESIM_LEAK_STEPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1_000_000);
    let result = churn(steps, 50, 50_000);
    report(steps, result);
    let (_, warm, _, peak) = result;
    let growth = peak.saturating_sub(warm) as f64 / MIB;
    assert!(growth < 1.0, "RSS grew by {growth:.2} MiB after warm-up");
}
