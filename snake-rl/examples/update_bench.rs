//! Time of PPO updates with the hand-written networks:
//! `cargo run --release -p snake-rl --example update_bench [-- BATCH ITERS]`.
//!
//! First one minibatch update (forward, loss, backward, gradient clipping, Adam), split into its
//! parts, on one thread; then a whole update of the paper's settings (10 epochs over a rollout of
//! 16 envs x 4096 steps in minibatches of 64) on 1 and 2 threads, and on 2 threads again with
//! `init.anchor`'s term in the loss (weight 1000, anchor actions stored with the rollout).

use std::time::Instant;

use rand::{Rng, SeedableRng};
use snake_rl::buffer::RolloutBuffer;
use snake_rl::nn::{init_params, ActorCritic, Arch};
use snake_rl::optim::{clip_grad_norm, Adam};
use snake_rl::ppo::{loss, Learner, LossScratch, LossSettings, Minibatch, UpdateSettings};

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a number"))
        .collect();
    let rows = args.first().copied().unwrap_or(64);
    let iters = args.get(1).copied().unwrap_or(20_000);
    for (arch, obs_dim, act_dim) in [
        (Arch::Small, 12, 5),
        (Arch::Large, 12, 5),
        (Arch::Small, 22, 10),
    ] {
        let net = ActorCritic::new(arch.clone(), obs_dim, act_dim);
        let mut rng = rand_chacha::ChaCha12Rng::seed_from_u64(0);
        let mut params = init_params(&net, &mut rng);
        let obs: Vec<f32> = (0..rows * obs_dim)
            .map(|_| rng.gen_range(-1.0..1.0))
            .collect();
        let actions: Vec<f32> = (0..rows * act_dim)
            .map(|_| rng.gen_range(-1.0..1.0))
            .collect();
        let old: Vec<f32> = (0..rows).map(|_| rng.gen_range(-6.0..-4.0)).collect();
        let adv: Vec<f32> = (0..rows).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let ret: Vec<f32> = (0..rows).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let batch = Minibatch {
            obs: &obs,
            actions: &actions,
            old_log_prob: &old,
            advantages: &adv,
            returns: &ret,
            old_values: &ret,
            anchors: &[],
            rows,
        };
        let settings = LossSettings {
            clip_range: 0.2,
            clip_range_vf: None,
            ent_coef: 0.0,
            vf_coef: 0.5,
            normalize_advantage: true,
            anchor_weight: 0.0,
        };
        let mut ws = net.workspace(rows);
        let mut scratch = LossScratch::default();
        let mut grads = vec![0.0; net.len()];
        let mut adam = Adam::new(net.len());
        let tensors: Vec<(usize, usize)> =
            net.tensors().iter().map(|t| (t.offset, t.len())).collect();
        let mut phase = [0.0f64; 4];
        let start = Instant::now();
        for _ in 0..iters {
            let t0 = Instant::now();
            loss::forward(
                &net,
                &params,
                &batch,
                rows,
                &settings,
                &mut ws,
                &mut scratch,
            );
            let t1 = Instant::now();
            loss::backward(&net, &params, &obs, &mut ws, &scratch, &mut grads);
            let t2 = Instant::now();
            clip_grad_norm(&mut grads, &tensors, 0.5);
            let t3 = Instant::now();
            adam.step(&mut params, &grads, 3e-4);
            let t4 = Instant::now();
            phase[0] += (t1 - t0).as_secs_f64();
            phase[1] += (t2 - t1).as_secs_f64();
            phase[2] += (t3 - t2).as_secs_f64();
            phase[3] += (t4 - t3).as_secs_f64();
        }
        let per = start.elapsed().as_secs_f64() / iters as f64 * 1e6;
        let us = |s: f64| s / iters as f64 * 1e6;
        println!(
            "{arch:5} obs {obs_dim:2} act {act_dim:2} batch {rows}: {per:7.1} us/update (forward+loss {:.1}, backward {:.1}, clip {:.1}, adam {:.1}); {} params",
            us(phase[0]), us(phase[1]), us(phase[2]), us(phase[3]), net.len()
        );
    }
    if std::env::var_os("UPDATE_BENCH_MINIBATCH_ONLY").is_none() {
        full_updates();
    }
}

/// One full update of the paper's settings over a random rollout, on `threads` threads, with an
/// anchor term of `anchor_weight` when it is not 0; seconds.
fn full_update(
    arch: Arch,
    obs_dim: usize,
    act_dim: usize,
    threads: usize,
    anchor_weight: f32,
) -> f64 {
    let (n_steps, n_envs) = (4096, 16);
    let net = ActorCritic::new(arch.clone(), obs_dim, act_dim);
    let mut rng = rand_chacha::ChaCha12Rng::seed_from_u64(1);
    let params = init_params(&net, &mut rng);
    let mut buffer = RolloutBuffer::new(n_steps, n_envs, obs_dim, act_dim);
    if anchor_weight != 0.0 {
        buffer = buffer.with_anchors();
    }
    for _ in 0..n_steps {
        let obs: Vec<f32> = (0..n_envs * obs_dim)
            .map(|_| rng.gen_range(-1.0..1.0))
            .collect();
        let act: Vec<f32> = (0..n_envs * act_dim)
            .map(|_| rng.gen_range(-1.0..1.0))
            .collect();
        let r: Vec<f32> = (0..n_envs).map(|_| rng.gen_range(-1.0..0.0)).collect();
        let lp: Vec<f32> = (0..n_envs).map(|_| rng.gen_range(-6.0..-4.0)).collect();
        if anchor_weight != 0.0 {
            let anchors: Vec<f32> = (0..n_envs * act_dim)
                .map(|_| rng.gen_range(-1.0..1.0))
                .collect();
            buffer.set_anchors(&anchors);
        }
        buffer.add(&obs, &act, &r, &vec![false; n_envs], &r, &lp);
    }
    buffer.compute_returns_and_advantage(&vec![0.0; n_envs], &vec![false; n_envs], 0.99, 0.95);
    let settings = UpdateSettings {
        n_epochs: 10,
        batch_size: 64,
        loss: LossSettings {
            clip_range: 0.2,
            clip_range_vf: None,
            ent_coef: 0.0,
            vf_coef: 0.5,
            normalize_advantage: true,
            anchor_weight,
        },
        max_grad_norm: 0.5,
        target_kl: None,
        learning_rate: 3e-4,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut learner = Learner::new(net, params, threads);
    let start = Instant::now();
    learner
        .update(&buffer, &settings, &mut rng, Some(&pool))
        .expect("finite");
    start.elapsed().as_secs_f64()
}

fn full_updates() {
    for (arch, obs_dim, act_dim) in [
        (Arch::Small, 12, 5),
        (Arch::Large, 12, 5),
        (Arch::Small, 22, 10),
    ] {
        let t1 = full_update(arch.clone(), obs_dim, act_dim, 1, 0.0);
        let t2 = full_update(arch.clone(), obs_dim, act_dim, 2, 0.0);
        let anchored = full_update(arch.clone(), obs_dim, act_dim, 2, 1000.0);
        println!(
            "{arch:5} obs {obs_dim:2} act {act_dim:2}: full update (10,240 minibatches) {t1:.2} s on 1 thread, {t2:.2} s on 2 \
             ({:.1} / {:.1} us per minibatch); anchored, 2 threads: {anchored:.2} s",
            t1 / 10240.0 * 1e6,
            t2 / 10240.0 * 1e6
        );
    }
}
