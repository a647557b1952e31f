//! snake-rl's PPO against Stable-Baselines3 2.x and PyTorch (`reference/ppo_reference.py`).
//!
//! For the same weights and the same minibatch, the action means, log-probabilities, entropies,
//! values, the loss terms, every parameter's gradient and the parameters after the Adam step must
//! equal what SB3's own `PPO.train()` computes, in float32, to within 1e-5 relative. Adam over several
//! steps is compared with `torch.optim.Adam(eps=1e-5)`, GAE with SB3's `RolloutBuffer`, observation
//! and reward normalisation with SB3's `VecNormalize`.

use std::collections::BTreeMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha12Rng;
use serde::Serialize;
use serde_json::{json, Value};
use snake_rl::buffer::RolloutBuffer;
use snake_rl::nn::{init_params, ActorCritic, Arch, NetArch, Workspace};
use snake_rl::normalize::Normalizer;
use snake_rl::optim::Adam;
use snake_rl::ppo::loss::{gaussian_entropy, gaussian_log_prob};
use snake_rl::ppo::{Learner, LossScratch, LossSettings, UpdateSettings};
use snakesim_tests::run_reference_script;

/// The relative tolerance of every comparison (float32 results of different summation orders).
const RTOL: f64 = 1e-5;

/// Compares two tensors: the largest elementwise difference must be within RTOL of the tensor's
/// largest magnitude (the max-norm relative error). Elementwise relative errors would be meaningless
/// for elements that are cancelling sums far below their terms (float32 rounding is relative to the
/// terms, not to the sum).
fn assert_close(what: &str, ours: &[f32], reference: &[f64]) {
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert_close_at_scale(what, ours, reference, scale);
}

/// [`assert_close`] with the scale given: for a sum that cancels, the magnitude of its terms.
fn assert_close_at_scale(what: &str, ours: &[f32], reference: &[f64], scale: f64) {
    assert_eq!(ours.len(), reference.len(), "{what}: lengths differ");
    let (worst, at) = ours
        .iter()
        .zip(reference)
        .enumerate()
        .map(|(i, (&a, &b))| ((f64::from(a) - b).abs(), i))
        .fold((0.0, 0), |m, x| if x.0 > m.0 { x } else { m });
    if std::env::var_os("SNAKESIM_SHOW_ERRORS").is_some() {
        eprintln!(
            "{what}: max-norm relative error {:.2e}",
            worst / scale.max(f64::MIN_POSITIVE)
        );
    }
    assert!(
        worst <= RTOL * scale,
        "{what}[{at}]: ours {:e}, reference {:e}: difference {worst:e} exceeds {RTOL:e} x the tensor's \
         largest magnitude {scale:e}",
        ours[at],
        reference[at]
    );
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("a list")
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect()
}

#[derive(Serialize)]
struct Settings {
    learning_rate: f64,
    clip_range: f64,
    clip_range_vf: Option<f64>,
    normalize_advantage: bool,
    ent_coef: f64,
    vf_coef: f64,
    max_grad_norm: f64,
}

/// A PPO case: random weights (biases and log_std too, so every gradient is exercised), a minibatch
/// whose ratios straddle the clip range, and the settings.
struct PpoCase {
    name: String,
    net: ActorCritic,
    params: Vec<f32>,
    rows: usize,
    obs: Vec<f32>,
    actions: Vec<f32>,
    old_log_prob: Vec<f32>,
    advantages: Vec<f32>,
    returns: Vec<f32>,
    old_values: Vec<f32>,
    settings: Settings,
    /// `init.anchor`'s weight and the anchor action of each row, if the case keeps an anchor.
    anchor: Option<(f32, Vec<f32>)>,
}

fn ppo_case(
    name: &str,
    arch: Arch,
    obs_dim: usize,
    act_dim: usize,
    rows: usize,
    settings: Settings,
    seed: u64,
) -> PpoCase {
    let net = ActorCritic::new(arch, obs_dim, act_dim);
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    let mut params = init_params(&net, &mut rng);
    for t in net.tensors() {
        if t.name.ends_with(".bias") || t.name == "log_std" {
            for p in &mut params[t.offset..t.offset + t.len()] {
                *p = rng.gen_range(-0.3..0.3);
            }
        }
    }
    // Make the action means large enough to matter.
    let obs: Vec<f32> = (0..rows * obs_dim)
        .map(|_| rng.gen_range(-2.0..2.0))
        .collect();
    let mut ws = net.workspace(rows);
    net.forward(&params, &obs, rows, &mut ws);
    let o = net.log_std_offset();
    let actions: Vec<f32> = (0..rows * act_dim)
        .map(|k| ws.mean[k] + params[o + k % act_dim].exp() * rng.gen_range(-1.5f32..1.5))
        .collect();
    let mut scratch = LossScratch::default();
    gaussian_log_prob(
        &ws.mean,
        &params[o..o + act_dim],
        &actions,
        rows,
        &mut scratch,
    );
    // Ratios exp(+-0.4): about half the rows outside [0.8, 1.2].
    let old_log_prob = scratch
        .log_prob
        .iter()
        .map(|lp| lp + rng.gen_range(-0.4..0.4))
        .collect();
    let old_values: Vec<f32> = ws.value[..rows]
        .iter()
        .map(|v| v + rng.gen_range(-0.5..0.5))
        .collect();
    PpoCase {
        name: name.into(),
        params,
        rows,
        obs,
        actions,
        old_log_prob,
        advantages: (0..rows).map(|_| rng.gen_range(-3.0..5.0)).collect(),
        returns: (0..rows).map(|_| rng.gen_range(-2.0..2.0)).collect(),
        old_values,
        settings,
        net,
        anchor: None,
    }
}

/// [`ppo_case`] with an anchor of `weight` to given actions (random, within the action space).
fn anchored(mut case: PpoCase, weight: f32, seed: u64) -> PpoCase {
    let mut rng = ChaCha12Rng::seed_from_u64(seed);
    let targets = (0..case.rows * case.net.act_dim())
        .map(|_| rng.gen_range(-1.0..1.0))
        .collect();
    case.name.push_str("-anchor");
    case.anchor = Some((weight, targets));
    case
}

fn ppo_spec(c: &PpoCase) -> Value {
    let tensors: BTreeMap<String, Vec<f32>> = c
        .net
        .tensors()
        .into_iter()
        .map(|t| {
            (
                t.name.clone(),
                c.params[t.offset..t.offset + t.len()].to_vec(),
            )
        })
        .collect();
    json!({
        "kind": "ppo", "name": c.name, "arch": c.net.arch(),
        "obs_dim": c.net.obs_dim(), "act_dim": c.net.act_dim(), "rows": c.rows,
        "tensors": tensors, "obs": c.obs, "actions": c.actions, "old_log_prob": c.old_log_prob,
        "advantages": c.advantages, "returns": c.returns, "old_values": c.old_values,
        "settings": c.settings,
        "anchor": c.anchor.as_ref().map(|(w, t)| json!({"weight": w, "targets": t})),
    })
}

/// Our side of a PPO case: the forward quantities, then one update of one minibatch (the whole
/// buffer) on `threads` threads.
fn check_ppo(c: &PpoCase, reference: &Value, threads: usize) {
    let tag = format!("{} ({threads} thread(s))", c.name);
    let (rows, n) = (c.rows, c.net.act_dim());
    let mut ws: Workspace = c.net.workspace(rows);
    c.net.forward(&c.params, &c.obs, rows, &mut ws);
    let o = c.net.log_std_offset();
    let log_std = &c.params[o..o + n];
    let mut scratch = LossScratch::default();
    gaussian_log_prob(&ws.mean, log_std, &c.actions, rows, &mut scratch);
    assert_close(
        &format!("{tag} mean"),
        &ws.mean[..rows * n],
        &floats(&reference["mean"]),
    );
    assert_close(
        &format!("{tag} log_prob"),
        &scratch.log_prob,
        &floats(&reference["log_prob"]),
    );
    assert_close(
        &format!("{tag} values"),
        &ws.value[..rows],
        &floats(&reference["values"]),
    );
    let entropy = vec![gaussian_entropy(log_std); rows];
    assert_close(
        &format!("{tag} entropy"),
        &entropy,
        &floats(&reference["entropy"]),
    );

    let mut buffer = RolloutBuffer::new(rows, 1, c.net.obs_dim(), n);
    if c.anchor.is_some() {
        buffer = buffer.with_anchors();
    }
    for r in 0..rows {
        if let Some((_, targets)) = &c.anchor {
            buffer.set_anchors(&targets[r * n..(r + 1) * n]);
        }
        buffer.add(
            &c.obs[r * c.net.obs_dim()..(r + 1) * c.net.obs_dim()],
            &c.actions[r * n..(r + 1) * n],
            &[0.0],
            &[false],
            &[c.old_values[r]],
            &[c.old_log_prob[r]],
        );
    }
    buffer.advantages.copy_from_slice(&c.advantages);
    buffer.returns.copy_from_slice(&c.returns);
    let s = &c.settings;
    let settings = UpdateSettings {
        n_epochs: 1,
        batch_size: rows,
        loss: LossSettings {
            clip_range: s.clip_range as f32,
            clip_range_vf: s.clip_range_vf.map(|v| v as f32),
            ent_coef: s.ent_coef as f32,
            vf_coef: s.vf_coef as f32,
            normalize_advantage: s.normalize_advantage,
            anchor_weight: c.anchor.as_ref().map_or(0.0, |a| a.0),
        },
        max_grad_norm: s.max_grad_norm,
        target_kl: None,
        learning_rate: s.learning_rate,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut learner = Learner::new(c.net.clone(), c.params.clone(), threads);
    let stats = learner
        .update(
            &buffer,
            &settings,
            &mut ChaCha12Rng::seed_from_u64(0),
            Some(&pool),
        )
        .expect("finite");
    // The policy loss is a mean of surrogates A * ratio over advantages normalised to mean 0: it
    // cancels, so its rounding scale is the mean magnitude of those terms (and the total loss's too).
    let mut advantages = c.advantages.clone();
    if s.normalize_advantage {
        snake_rl::ppo::loss::normalize_advantages(&mut advantages);
    }
    let surrogate_scale = advantages
        .iter()
        .zip(scratch.log_prob.iter().zip(&c.old_log_prob))
        .map(|(a, (lp, old))| f64::from(a.abs() * (lp - old).exp()))
        .sum::<f64>()
        / rows as f64;
    let r = &reference["stats"];
    if c.anchor.is_some() {
        let reference = r["anchor_loss"].as_f64().unwrap();
        assert_close(
            &format!("{tag} anchor_loss"),
            &[stats.anchor_loss as f32],
            &[reference],
        );
    }
    for (name, ours, cancels) in [
        ("policy_gradient_loss", stats.policy_gradient_loss, true),
        ("value_loss", stats.value_loss, false),
        ("entropy_loss", stats.entropy_loss, false),
        ("approx_kl", stats.approx_kl, false),
        ("clip_fraction", stats.clip_fraction, false),
        ("loss", stats.loss, true),
    ] {
        let reference = r[name].as_f64().unwrap();
        let scale = if cancels {
            surrogate_scale.max(reference.abs())
        } else {
            reference.abs()
        };
        assert_close_at_scale(
            &format!("{tag} {name}"),
            &[ours as f32],
            &[reference],
            scale,
        );
    }
    for t in c.net.tensors() {
        let range = t.offset..t.offset + t.len();
        let grads = floats(&reference["grads"][&t.name]);
        assert_close(
            &format!("{tag} grad {}", t.name),
            &learner.last_gradient()[range.clone()],
            &grads,
        );
        // Adam's first step moves a parameter by -lr * g / (|g| + eps): a gradient known to within
        // d (RTOL x the tensor's largest gradient) gives the step to within lr * eps / (|g| + eps)^2 * d.
        // That, plus RTOL of the parameter tensor, is the tolerance of the parameters after the step.
        let after = floats(&reference["params_after"][&t.name]);
        let p_scale = after.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let d = RTOL * grads.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let eps = 1e-5;
        for (i, ((&ours, &theirs), &g)) in learner.params[range]
            .iter()
            .zip(&after)
            .zip(&grads)
            .enumerate()
        {
            let tol = RTOL * p_scale + s.learning_rate * eps / (g.abs() + eps).powi(2) * d;
            assert!(
                (f64::from(ours) - theirs).abs() <= tol,
                "{tag} param after Adam {}[{i}]: ours {ours:e}, reference {theirs:e} (tolerance {tol:e})",
                t.name
            );
        }
    }
}

#[test]
fn ppo_update_matches_sb3() {
    let default = || Settings {
        learning_rate: 3e-4,
        clip_range: 0.2,
        clip_range_vf: None,
        normalize_advantage: true,
        ent_coef: 0.0,
        vf_coef: 0.5,
        // Large enough not to clip: the raw gradient is compared.
        max_grad_norm: 1e9,
    };
    let cases = vec![
        ppo_case("small-5", Arch::Small, 12, 5, 64, default(), 1),
        ppo_case(
            "small-10-clipped",
            Arch::Small,
            22,
            10,
            64,
            Settings {
                clip_range_vf: Some(0.2),
                ent_coef: 0.01,
                max_grad_norm: 0.5,
                learning_rate: 1e-3,
                ..default()
            },
            2,
        ),
        ppo_case("large-5", Arch::Large, 12, 5, 64, default(), 3),
        // Widths of one's own (`arch: {shared, pi, vf}`): deeper, narrower and uneven heads, with and
        // without a trunk; SB3 builds them from the same mapping (`policy_kwargs`).
        ppo_case(
            "custom-heads-5",
            Arch::Custom(NetArch {
                shared: vec![],
                pi: vec![32, 16, 8],
                vf: vec![48],
            }),
            12,
            5,
            64,
            default(),
            5,
        ),
        ppo_case(
            "custom-trunk-10",
            Arch::Custom(NetArch {
                shared: vec![40],
                pi: vec![24],
                vf: vec![24, 12],
            }),
            22,
            10,
            64,
            Settings {
                ent_coef: 0.01,
                max_grad_norm: 0.5,
                ..default()
            },
            6,
        ),
        ppo_case(
            "large-10-odd-rows",
            Arch::Large,
            28,
            10,
            37,
            Settings {
                normalize_advantage: false,
                max_grad_norm: 0.5,
                ..default()
            },
            4,
        ),
        // `init.anchor`: the anchor's term joins the loss (PPO-small's two-thread update and the
        // row-split update of a shared trunk both carry it).
        anchored(
            ppo_case("small-10", Arch::Small, 22, 10, 64, default(), 7),
            0.5,
            8,
        ),
        anchored(
            ppo_case(
                "large-5",
                Arch::Large,
                12,
                5,
                37,
                Settings {
                    ent_coef: 0.01,
                    ..default()
                },
                9,
            ),
            2.0,
            10,
        ),
    ];
    let spec: Vec<Value> = cases.iter().map(ppo_spec).collect();
    let Some(dir) = run_reference_script("ppo_reference.py", &spec, "ppo") else {
        return;
    };
    for c in &cases {
        let text = std::fs::read_to_string(dir.join(format!("{}.json", c.name))).unwrap();
        let reference: Value = serde_json::from_str(&text).unwrap();
        for threads in [1, 2, 3] {
            check_ppo(c, &reference, threads);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn adam_matches_torch() {
    let mut rng = ChaCha12Rng::seed_from_u64(7);
    let len = 1000;
    let params: Vec<f32> = (0..len).map(|_| rng.gen_range(-1.0..1.0)).collect();
    // Gradients of very different scales over 25 steps, some exactly zero.
    let grads: Vec<Vec<f32>> = (0..25)
        .map(|k| {
            (0..len)
                .map(|i| {
                    if i % 17 == 0 {
                        0.0
                    } else {
                        rng.gen_range(-1.0..1.0) * 10f32.powi(k % 5 - 3)
                    }
                })
                .collect()
        })
        .collect();
    let spec =
        vec![json!({"kind": "adam", "name": "adam", "params": params, "grads": grads, "lr": 3e-4})];
    let Some(dir) = run_reference_script("ppo_reference.py", &spec, "adam") else {
        return;
    };
    let reference: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("adam.json")).unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let mut ours = params.clone();
    let mut adam = Adam::new(len);
    for g in &grads {
        adam.step(&mut ours, g, 3e-4);
    }
    assert_close("adam params", &ours, &floats(&reference["params"]));
    assert_close(
        "adam exp_avg",
        &adam.exp_avg,
        &floats(&reference["exp_avg"]),
    );
    assert_close(
        "adam exp_avg_sq",
        &adam.exp_avg_sq,
        &floats(&reference["exp_avg_sq"]),
    );
}

#[test]
fn gae_matches_sb3_rollout_buffer() {
    let (n_steps, n_envs) = (50, 4);
    let mut rng = ChaCha12Rng::seed_from_u64(11);
    let rewards: Vec<f32> = (0..n_steps * n_envs)
        .map(|_| rng.gen_range(-2.0..1.0))
        .collect();
    let values: Vec<f32> = (0..n_steps * n_envs)
        .map(|_| rng.gen_range(-5.0..5.0))
        .collect();
    // Episode starts (after terminations and truncations) scattered through the rollout, the first
    // step of every env a start, and the last step ending two envs' episodes.
    let starts: Vec<bool> = (0..n_steps * n_envs)
        .map(|i| i < n_envs || rng.gen_bool(0.08))
        .collect();
    let last_values: Vec<f32> = (0..n_envs).map(|_| rng.gen_range(-5.0..5.0)).collect();
    let dones = vec![true, false, true, false];
    let (gamma, gae_lambda) = (0.99, 0.95);
    let spec = vec![json!({
        "kind": "gae", "name": "gae", "n_steps": n_steps, "n_envs": n_envs, "gamma": gamma,
        "gae_lambda": gae_lambda, "rewards": rewards, "values": values,
        "episode_starts": starts.iter().map(|&s| if s { 1.0 } else { 0.0 }).collect::<Vec<f32>>(),
        "last_values": last_values, "dones": dones,
    })];
    let Some(dir) = run_reference_script("ppo_reference.py", &spec, "gae") else {
        return;
    };
    let reference: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("gae.json")).unwrap()).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let mut buffer = RolloutBuffer::new(n_steps, n_envs, 1, 1);
    for t in 0..n_steps {
        let range = t * n_envs..(t + 1) * n_envs;
        buffer.add(
            &vec![0.0; n_envs],
            &vec![0.0; n_envs],
            &rewards[range.clone()],
            &starts[range.clone()],
            &values[range.clone()],
            &vec![0.0; n_envs],
        );
    }
    buffer.compute_returns_and_advantage(&last_values, &dones, gamma, gae_lambda);
    // SB3 stores (n_steps, n_envs) arrays, step-major as ours: the same order.
    let (adv, ret) = (
        floats(&reference["advantages"]),
        floats(&reference["returns"]),
    );
    for (i, (a, r)) in buffer.advantages.iter().zip(&buffer.returns).enumerate() {
        assert_eq!(
            f64::from(*a),
            adv[i],
            "advantage {i}: ours {a}, SB3 {}",
            adv[i]
        );
        assert_eq!(
            f64::from(*r),
            ret[i],
            "return {i}: ours {r}, SB3 {}",
            ret[i]
        );
    }
}

#[test]
fn normalization_matches_vec_normalize() {
    let (obs_dim, n_envs, steps) = (6, 3, 40);
    let mut rng = ChaCha12Rng::seed_from_u64(5);
    let mut batch = |scale: f32| -> Vec<f32> {
        (0..obs_dim * n_envs)
            .map(|k| (k % obs_dim) as f32 * 3.0 + rng.gen_range(-1.0..1.0) * scale)
            .collect()
    };
    let reset_obs = batch(1.0);
    let mut records = Vec::new();
    for k in 0..steps {
        let obs = batch(1.0 + k as f32);
        records.push((
            obs,
            (0..n_envs)
                .map(|i| (i as f32 - 1.0) * 2.5 + k as f32 * 0.1)
                .collect::<Vec<f32>>(),
            (0..n_envs).map(|i| (k + i) % 7 == 0).collect::<Vec<bool>>(),
        ));
    }
    let gamma = 0.99;
    let spec = vec![json!({
        "kind": "normalize", "name": "normalize", "obs_dim": obs_dim, "n_envs": n_envs, "gamma": gamma,
        "reset_obs": reset_obs,
        "steps": records.iter().map(|(o, r, d)| json!({"obs": o, "rewards": r, "dones": d})).collect::<Vec<_>>(),
    })];
    let Some(dir) = run_reference_script("ppo_reference.py", &spec, "normalize") else {
        return;
    };
    let reference: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("normalize.json")).unwrap())
            .unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let mut norm = Normalizer::new(obs_dim, n_envs, gamma);
    let mut obs = reset_obs.clone();
    norm.obs_rms.update(&obs, n_envs);
    norm.reset_returns(n_envs);
    norm.normalize_obs(&mut obs);
    assert_close("reset obs", &obs, &floats(&reference["reset_obs"]));
    for (k, (o, r, d)) in records.iter().enumerate() {
        let mut obs = o.clone();
        norm.obs_rms.update(&obs, n_envs);
        norm.normalize_obs(&mut obs);
        let mut rewards = r.clone();
        norm.normalize_rewards(&mut rewards, d);
        assert_close(&format!("obs {k}"), &obs, &floats(&reference["obs"][k]));
        assert_close(
            &format!("rewards {k}"),
            &rewards,
            &floats(&reference["rewards"][k]),
        );
    }
    let f = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    assert_close(
        "obs mean",
        &f(&norm.obs_rms.mean),
        &floats(&reference["obs_mean"]),
    );
    assert_close(
        "obs var",
        &f(&norm.obs_rms.var),
        &floats(&reference["obs_var"]),
    );
    assert_close(
        "return var",
        &f(&norm.ret_rms.var),
        &floats(&reference["ret_var"]),
    );
}
