//! The update's three ways of running (one thread; PPO-small's two networks on two threads; each
//! minibatch's rows split across threads) are one algorithm: over several epochs of minibatches
//! they take the same gradient steps and end at the same parameters, up to float32 rounding of sums
//! taken in another order. (Each way is pinned to Stable-Baselines3 itself in ppo_reference.rs.)

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha12Rng;
use snake_rl::buffer::RolloutBuffer;
use snake_rl::nn::{init_params, ActorCritic, Arch};
use snake_rl::ppo::{Learner, LossSettings, UpdateSettings, UpdateStats};

fn buffer(obs_dim: usize, act_dim: usize, seed: u64) -> RolloutBuffer {
    let (n_steps, n_envs) = (96, 4);
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    let mut b = RolloutBuffer::new(n_steps, n_envs, obs_dim, act_dim);
    for _ in 0..n_steps {
        let obs: Vec<f32> = (0..n_envs * obs_dim)
            .map(|_| rng.gen_range(-2.0..2.0))
            .collect();
        let act: Vec<f32> = (0..n_envs * act_dim)
            .map(|_| rng.gen_range(-1.5..1.5))
            .collect();
        let rewards: Vec<f32> = (0..n_envs).map(|_| rng.gen_range(-3.0..1.0)).collect();
        let values: Vec<f32> = (0..n_envs).map(|_| rng.gen_range(-1.0..1.0)).collect();
        let log_probs: Vec<f32> = (0..n_envs).map(|_| rng.gen_range(-7.0..-4.0)).collect();
        let starts: Vec<bool> = (0..n_envs).map(|_| rng.gen_bool(0.05)).collect();
        b.add(&obs, &act, &rewards, &starts, &values, &log_probs);
    }
    b.compute_returns_and_advantage(&[0.5; 4], &[false, true, false, false], 0.99, 0.95);
    b
}

fn settings(target_kl: Option<f64>) -> UpdateSettings {
    UpdateSettings {
        n_epochs: 4,
        batch_size: 64,
        loss: LossSettings {
            clip_range: 0.2,
            clip_range_vf: Some(0.3),
            ent_coef: 0.01,
            vf_coef: 0.5,
            normalize_advantage: true,
            anchor_weight: 0.0,
        },
        max_grad_norm: 0.5,
        target_kl,
        learning_rate: 1e-3,
    }
}

fn run(arch: Arch, threads: usize, target_kl: Option<f64>) -> (Vec<f32>, UpdateStats) {
    let net = ActorCritic::new(arch, 12, 5);
    let params = init_params(&net, &mut ChaCha12Rng::seed_from_u64(3));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut learner = Learner::new(net, params, threads);
    let stats = learner
        .update(
            &buffer(12, 5, 9),
            &settings(target_kl),
            &mut ChaCha12Rng::seed_from_u64(1),
            Some(&pool),
        )
        .expect("finite");
    (learner.params, stats)
}

fn assert_close(a: &[f32], b: &[f32]) {
    let scale = b.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let worst = a
        .iter()
        .zip(b)
        .fold(0.0f32, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        worst <= 1e-5 * scale,
        "parameters differ by {worst:e} (scale {scale:e})"
    );
}

#[test]
fn two_networks_on_two_threads_is_the_sequential_update() {
    let (one, s1) = run(Arch::Small, 1, None);
    let (two, s2) = run(Arch::Small, 2, None);
    assert_eq!((s1.gradient_steps, s1.epochs), (24, 4));
    assert_eq!((s2.gradient_steps, s2.epochs), (24, 4));
    assert_close(&two, &one);
    assert!((s1.value_loss - s2.value_loss).abs() <= 1e-5 * s1.value_loss.abs());
}

#[test]
fn rows_split_across_threads_is_the_sequential_update() {
    let (one, _) = run(Arch::Large, 1, None);
    let (three, s) = run(Arch::Large, 3, None);
    assert_eq!(s.gradient_steps, 24);
    assert_close(&three, &one);
}

#[test]
fn the_kl_stop_happens_at_the_same_step() {
    // A target low enough to stop within the first epochs.
    let (one, s1) = run(Arch::Small, 1, Some(0.002));
    let (two, s2) = run(Arch::Small, 2, Some(0.002));
    assert!(s1.stopped_early && s2.stopped_early);
    assert!(s1.gradient_steps < 24, "{} steps", s1.gradient_steps);
    assert_eq!(
        (s1.gradient_steps, s1.epochs),
        (s2.gradient_steps, s2.epochs)
    );
    assert_close(&two, &one);
    assert!((s1.approx_kl - s2.approx_kl).abs() <= 1e-5 * s1.approx_kl.abs());
}
