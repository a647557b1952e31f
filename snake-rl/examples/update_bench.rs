//! Time of one PPO minibatch update (forward, loss, backward, gradient clipping, Adam) with the
//! hand-written networks: `cargo run --release -p snake-rl --example update_bench [-- BATCH ITERS]`.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use snake_rl::nn::{init_params, ActorCritic, Arch};
use snake_rl::optim::{clip_grad_norm, Adam};
use snake_rl::ppo::{loss, LossScratch, LossSettings, Minibatch};

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
        let net = ActorCritic::new(arch, obs_dim, act_dim);
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
            rows,
        };
        let settings = LossSettings {
            clip_range: 0.2,
            clip_range_vf: None,
            ent_coef: 0.0,
            vf_coef: 0.5,
            normalize_advantage: true,
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
}
