//! The hand-written PPO update against the same update written with a tensor crate with autograd
//! (candle, CPU backend), on one thread each:
//!
//! ```text
//! cargo run --release -p snake-rl --example candle_update_bench --features candle-bench [-- ITERS]
//! ```
//!
//! For each shape of `update_bench` (PPO-small and PPO-large on 12 observations and 5 actions,
//! PPO-small on 22 and 10; minibatches of 64), the network is built in candle from the hand-written
//! network's flat parameter buffer (`init_params` and the tensor table `ActorCritic::tensors`), so
//! that both compute the same function. One minibatch update is then, on both sides: the forward pass
//! and SB3's PPO loss (diagonal Gaussian log-probability, advantages normalised per minibatch, clipped
//! surrogate with clip 0.2, value MSE with `vf_coef` 0.5, no entropy bonus), the backward pass (candle's
//! autograd; the hand-written gradient of `snake_rl::ppo::loss`), gradient clipping to a global norm of
//! 0.5 (`torch.nn.utils.clip_grad_norm_`) and one Adam step (lr 3e-4, betas 0.9/0.999, eps 1e-5; in
//! candle, `candle_nn::AdamW` with no weight decay, which is Adam).
//!
//! Before any timing, one update of both on the same parameters and minibatch must agree, by the
//! rules of the workspace's `tests/ppo_reference.rs` (float32 results of different summation orders):
//!
//! - the loss within 1e-5 relative;
//! - the clipped gradients within 1e-5 of each tensor's largest magnitude; for the output layers'
//!   biases, whose gradients are sums over the rows that can cancel far below their terms (float32
//!   rounding is relative to the terms), of the magnitude of those terms if that is larger;
//! - the parameters after Adam within 1e-5 of each tensor's largest magnitude, plus what the gradient's
//!   tolerance `d` becomes through Adam's first step, `lr * eps / (|g| + eps)^2 * d`: that step is
//!   about `-lr * g / (|g| + eps)`, steep where `|g|` is near eps, as for some of the zero-initialised
//!   biases here. The gradients are checked as well because the step is about `-lr * sign(g)` elsewhere,
//!   so the parameters alone would hide a wrong gradient.
//!
//! Each line prints the largest differences relative to each tensor's largest magnitude, and the pass
//! or fail under these tolerances. On a disagreement the example exits with status 1 without timing.
//!
//! Then `ITERS` updates (default 5,000) of each are timed, after a short warm-up, and the example
//! prints microseconds per minibatch update, the ratio candle / hand-written, the time one full
//! update of the paper's settings (10 epochs x 16 envs x 4096 steps / 64 = 10,240 minibatches) would
//! take at that rate, and each side's time split into forward+loss, backward, clip and Adam. candle's
//! forward+loss includes making the minibatch's tensors from its slices, as a trainer would for each
//! gathered minibatch.
//!
//! Threads: candle's CPU backend hands each matrix product to `gemm` with
//! `candle_core::utils::get_num_threads()` rayon threads, which it reads from `RAYON_NUM_THREADS`
//! (`num_cpus::get()` when unset) before every product; the other operations used here run on the
//! calling thread. `main` sets `RAYON_NUM_THREADS=1` (whatever it was) before anything else runs and
//! checks that candle sees 1. The hand-written side is single-threaded here: matrixmultiply is built
//! without its `threading` feature and the minibatch path does not use rayon.
//!
//! Instruction sets: `gemm` (candle's matrix products), matrixmultiply and the hand-written
//! elementwise loops pick AVX2/FMA at run time, but candle's own elementwise kernels are compiled for
//! the build's target features: the x86-64 baseline unless the build says otherwise. The first line
//! printed says which (`candle_core::utils::with_avx()`). To give candle AVX2 throughout, build with
//! `RUSTFLAGS="-C target-cpu=native"` (best in a target directory of its own, as it rebuilds every
//! crate).

use std::collections::HashMap;
use std::error::Error;
use std::process::ExitCode;
use std::time::Instant;

use candle_core::backprop::GradStore;
use candle_core::{Device, Tensor, Var};
use candle_nn::{AdamW, Linear, Module, Optimizer, ParamsAdamW};
use rand::{Rng, SeedableRng};
use snake_rl::nn::{init_params, ActorCritic, Arch, Workspace};
use snake_rl::optim::{clip_coefficient, clip_grad_norm, Adam};
use snake_rl::ppo::loss::{self, LOG_SQRT_2PI};
use snake_rl::ppo::{LossScratch, LossSettings, Minibatch};

/// Rows of a minibatch (the paper's `batch_size`).
const ROWS: usize = 64;
/// Minibatches of one full update of the paper's settings: 10 epochs over 16 x 4096 steps.
const MINIBATCHES_PER_UPDATE: usize = 10 * 16 * 4096 / ROWS;
const CLIP_RANGE: f32 = 0.2;
const VF_COEF: f32 = 0.5;
const MAX_GRAD_NORM: f64 = 0.5;
const LEARNING_RATE: f64 = 3e-4;
/// Largest relative disagreement accepted between the two implementations.
const TOLERANCE: f64 = 1e-5;
/// Untimed updates before each timed run (first-touch allocations, caches, branch predictors).
const WARM_UP: usize = 100;

const SHAPES: [(Arch, usize, usize); 3] = [
    (Arch::Small, 12, 5),
    (Arch::Large, 12, 5),
    (Arch::Small, 22, 10),
];

type AnyResult<T> = Result<T, Box<dyn Error>>;

fn main() -> ExitCode {
    // Before anything else, so no other thread can be reading the environment while it changes.
    // candle reads the variable before every matrix product (see the module doc).
    std::env::set_var("RAYON_NUM_THREADS", "1");
    let iters = match std::env::args().nth(1).map(|a| a.parse::<usize>()) {
        None => 5_000,
        Some(Ok(n)) if n > 0 => n,
        Some(_) => {
            eprintln!("usage: candle_update_bench [ITERS], ITERS a positive integer");
            return ExitCode::from(2);
        }
    };
    match run(iters) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("candle_update_bench: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Checks every shape, then times them; `Ok(false)` when a check failed.
fn run(iters: usize) -> AnyResult<bool> {
    let threads = candle_core::utils::get_num_threads();
    if threads != 1 {
        return Err(format!("candle would use {threads} threads per matrix product, not 1").into());
    }
    println!(
        "candle CPU backend: {threads} thread per matrix product (RAYON_NUM_THREADS=1); candle's own \
         kernels compiled with AVX2: {}",
        candle_core::utils::with_avx()
    );

    let mut agree = true;
    for (arch, obs_dim, act_dim) in SHAPES {
        agree &= check(arch, obs_dim, act_dim)?;
    }
    if !agree {
        println!("FAILED: candle and the hand-written update disagree; nothing timed");
        return Ok(false);
    }

    println!(
        "\nminibatch of {ROWS}, {iters} updates each after {WARM_UP} untimed, one thread \
         (forward + loss + backward + clip + Adam)"
    );
    println!(
        "{:<22} {:>6} {:>15} {:>10} {:>7}   full update ({MINIBATCHES_PER_UPDATE} minibatches)",
        "shape", "params", "hand-written us", "candle us", "ratio"
    );
    let mut phases = Vec::new();
    for (arch, obs_dim, act_dim) in SHAPES {
        let name = shape_name(&arch, obs_dim, act_dim);
        let (net, params, data) = setup(arch, obs_dim, act_dim);
        let len = net.len();
        let mut hand = HandWritten::new(net.clone(), params.clone());
        let mut candle = Candle::new(&net, &params)?;
        let hand_phases = time(iters, |p| {
            hand.step(&data, p);
            Ok(())
        })?;
        let candle_phases = time(iters, |p| {
            candle.step(&data, p)?;
            Ok(())
        })?;
        let (h, c) = (
            hand_phases.iter().sum::<f64>(),
            candle_phases.iter().sum::<f64>(),
        );
        let full = |us: f64| us * MINIBATCHES_PER_UPDATE as f64 / 1e6;
        println!(
            "{name:<22} {len:>6} {h:>15.1} {c:>10.1} {:>6.1}x   hand-written {:.2} s, candle {:.2} s",
            c / h,
            full(h),
            full(c)
        );
        phases.push((name, hand_phases, candle_phases));
    }
    println!("\nus per update: forward+loss / backward / clip / adam");
    for (name, h, c) in phases {
        let f = |p: [f64; 4]| format!("{:.1} / {:.1} / {:.1} / {:.1}", p[0], p[1], p[2], p[3]);
        println!("{name:<22} hand-written {}; candle {}", f(h), f(c));
    }
    Ok(true)
}

fn shape_name(arch: &Arch, obs_dim: usize, act_dim: usize) -> String {
    format!("{:5} obs {obs_dim:2} act {act_dim:2}", arch.to_string())
}

/// `iters` calls of `step` after `WARM_UP` untimed ones; microseconds per call of each phase.
fn time(iters: usize, mut step: impl FnMut(&mut [f64; 4]) -> AnyResult<()>) -> AnyResult<[f64; 4]> {
    let mut phases = [0.0; 4];
    for _ in 0..WARM_UP {
        step(&mut phases)?;
    }
    phases = [0.0; 4];
    for _ in 0..iters {
        step(&mut phases)?;
    }
    Ok(phases.map(|s| s / iters as f64 * 1e6))
}

/// One random minibatch, drawn as `update_bench` draws it.
struct Data {
    obs: Vec<f32>,
    actions: Vec<f32>,
    old_log_prob: Vec<f32>,
    advantages: Vec<f32>,
    returns: Vec<f32>,
}

/// The network, its initial parameters and a minibatch, from the same seed as `update_bench`.
fn setup(arch: Arch, obs_dim: usize, act_dim: usize) -> (ActorCritic, Vec<f32>, Data) {
    let net = ActorCritic::new(arch, obs_dim, act_dim);
    let mut rng = rand_chacha::ChaCha12Rng::seed_from_u64(0);
    let params = init_params(&net, &mut rng);
    let mut draw = |n: usize, lo: f32, hi: f32| -> Vec<f32> {
        (0..n).map(|_| rng.gen_range(lo..hi)).collect()
    };
    let data = Data {
        obs: draw(ROWS * obs_dim, -1.0, 1.0),
        actions: draw(ROWS * act_dim, -1.0, 1.0),
        old_log_prob: draw(ROWS, -6.0, -4.0),
        advantages: draw(ROWS, -1.0, 1.0),
        returns: draw(ROWS, -1.0, 1.0),
    };
    (net, params, data)
}

/// The trainer's minibatch update (`Learner`'s, on one thread) over the hand-written networks.
struct HandWritten {
    net: ActorCritic,
    params: Vec<f32>,
    ws: Workspace,
    scratch: LossScratch,
    grads: Vec<f32>,
    adam: Adam,
    /// (offset, length) of every tensor, whose norms `clip_grad_norm` combines.
    tensors: Vec<(usize, usize)>,
    advantages: Vec<f32>,
    settings: LossSettings,
    /// The factor the last step's gradients were scaled by.
    clip_coefficient: f32,
}

impl HandWritten {
    fn new(net: ActorCritic, params: Vec<f32>) -> Self {
        HandWritten {
            ws: net.workspace(ROWS),
            scratch: LossScratch::default(),
            grads: vec![0.0; net.len()],
            adam: Adam::new(net.len()),
            tensors: net.tensors().iter().map(|t| (t.offset, t.len())).collect(),
            advantages: Vec::with_capacity(ROWS),
            settings: LossSettings {
                clip_range: CLIP_RANGE,
                clip_range_vf: None,
                ent_coef: 0.0,
                vf_coef: VF_COEF,
                normalize_advantage: true,
                anchor_weight: 0.0,
            },
            clip_coefficient: 1.0,
            net,
            params,
        }
    }

    /// One update on `data`; adds each phase's seconds to `phases`; returns the loss.
    fn step(&mut self, data: &Data, phases: &mut [f64; 4]) -> f32 {
        let t0 = Instant::now();
        // The trainer normalises the minibatch's advantages before the loss (`Learner::compute`).
        self.advantages.clear();
        self.advantages.extend_from_slice(&data.advantages);
        loss::normalize_advantages(&mut self.advantages);
        let batch = Minibatch {
            obs: &data.obs,
            actions: &data.actions,
            old_log_prob: &data.old_log_prob,
            advantages: &self.advantages,
            returns: &data.returns,
            old_values: &data.returns,
            anchors: &[],
            rows: ROWS,
        };
        let sums = loss::forward(
            &self.net,
            &self.params,
            &batch,
            ROWS,
            &self.settings,
            &mut self.ws,
            &mut self.scratch,
        );
        let o = self.net.log_std_offset();
        let entropy = loss::gaussian_entropy(&self.params[o..o + self.net.act_dim()]);
        let loss_value = sums.stats(ROWS, entropy, &self.settings).loss;
        let t1 = Instant::now();
        loss::backward(
            &self.net,
            &self.params,
            &data.obs,
            &mut self.ws,
            &self.scratch,
            &mut self.grads,
        );
        loss::add_entropy_gradient(&self.net, &self.settings, &mut self.grads);
        let t2 = Instant::now();
        let norm = clip_grad_norm(&mut self.grads, &self.tensors, MAX_GRAD_NORM);
        self.clip_coefficient = clip_coefficient(norm, MAX_GRAD_NORM);
        let t3 = Instant::now();
        self.adam.step(&mut self.params, &self.grads, LEARNING_RATE);
        let t4 = Instant::now();
        for (p, (a, b)) in phases
            .iter_mut()
            .zip([(t0, t1), (t1, t2), (t2, t3), (t3, t4)])
        {
            *p += (b - a).as_secs_f64();
        }
        loss_value
    }
}

/// The same network and update in candle: `Linear` layers and a `log_std` over one `Var` per tensor
/// of the hand-written network, autograd, `AdamW` without weight decay.
struct Candle {
    /// Every tensor, named and ordered as `ActorCritic::tensors` lists them.
    vars: Vec<(String, Var)>,
    shared: Vec<Linear>,
    pi: Vec<Linear>,
    vf: Vec<Linear>,
    action: Linear,
    value: Linear,
    log_std: Var,
    optimizer: AdamW,
    obs_dim: usize,
    act_dim: usize,
}

impl Candle {
    /// The network `net` with the parameters `params` (its flat buffer).
    fn new(net: &ActorCritic, params: &[f32]) -> candle_core::Result<Self> {
        let device = Device::Cpu;
        let vars = net
            .tensors()
            .into_iter()
            .map(|t| {
                let values = &params[t.offset..t.offset + t.len()];
                Ok((t.name, Var::from_slice(values, t.shape, &device)?))
            })
            .collect::<candle_core::Result<Vec<_>>>()?;
        let by_name: HashMap<&str, &Var> = vars.iter().map(|(n, v)| (n.as_str(), v)).collect();
        let var = |name: &str| {
            by_name
                .get(name)
                .map(|&v| v.clone())
                .ok_or_else(|| candle_core::Error::msg(format!("no tensor {name}")))
        };
        // A layer's tensors are clones of its `Var`s: the same storage and id, so the gradients and
        // the optimiser's in-place updates reach the layer.
        let linear = |prefix: &str| -> candle_core::Result<Linear> {
            let weight = var(&format!("{prefix}.weight"))?;
            let bias = var(&format!("{prefix}.bias"))?;
            Ok(Linear::new(
                weight.as_tensor().clone(),
                Some(bias.as_tensor().clone()),
            ))
        };
        // nn.Sequential(Linear, Tanh, ...): the linear layers are entries 0, 2, ... (SB3's names).
        let chain = |prefix: &str, depth: usize| {
            (0..depth)
                .map(|k| linear(&format!("{prefix}.{}", 2 * k)))
                .collect::<candle_core::Result<Vec<_>>>()
        };
        let arch = net.arch();
        let shared = chain("features_extractor.shared_net", arch.shared_widths().len())?;
        let pi = chain("mlp_extractor.policy_net", arch.pi_widths().len())?;
        let vf = chain("mlp_extractor.value_net", arch.vf_widths().len())?;
        let action = linear("action_net")?;
        let value = linear("value_net")?;
        let log_std = var("log_std")?;
        // Adam's betas and eps as the hand-written optimiser has them (SB3's for PPO).
        let (beta1, beta2, eps) = Adam::new(0).hyper();
        let optimizer = AdamW::new(
            vars.iter().map(|(_, v)| v.clone()).collect(),
            ParamsAdamW {
                lr: LEARNING_RATE,
                beta1,
                beta2,
                eps,
                weight_decay: 0.0,
            },
        )?;
        Ok(Candle {
            vars,
            shared,
            pi,
            vf,
            action,
            value,
            log_std,
            optimizer,
            obs_dim: net.obs_dim(),
            act_dim: net.act_dim(),
        })
    }

    /// Action means (`rows x act_dim`) and values (`rows`).
    fn forward(&self, obs: &Tensor) -> candle_core::Result<(Tensor, Tensor)> {
        let tanh_chain = |layers: &[Linear], x: &Tensor| {
            layers
                .iter()
                .try_fold(x.clone(), |h, layer| layer.forward(&h)?.tanh())
        };
        let trunk = tanh_chain(&self.shared, obs)?;
        let mean = self.action.forward(&tanh_chain(&self.pi, &trunk)?)?;
        let value = self.value.forward(&tanh_chain(&self.vf, &trunk)?)?;
        Ok((mean, value.squeeze(1)?))
    }

    /// SB3's PPO loss on one minibatch, as `PPO.train` writes it in torch.
    fn loss(&self, data: &Data) -> candle_core::Result<Tensor> {
        // A trainer hands candle each gathered minibatch as new tensors, so the copies are timed.
        let device = Device::Cpu;
        let obs = Tensor::from_slice(&data.obs, (ROWS, self.obs_dim), &device)?;
        let actions = Tensor::from_slice(&data.actions, (ROWS, self.act_dim), &device)?;
        let old_log_prob = Tensor::from_slice(&data.old_log_prob, ROWS, &device)?;
        let advantages = Tensor::from_slice(&data.advantages, ROWS, &device)?;
        let returns = Tensor::from_slice(&data.returns, ROWS, &device)?;

        let (mean, values) = self.forward(&obs)?;
        // torch's Normal(mean, exp(log_std)).log_prob(actions).sum(1):
        // -(a - mean)^2 / (2 var) - log(scale) - log(sqrt(2 pi)).
        let scale = self.log_std.exp()?;
        let var = scale.sqr()?;
        let log_scale = scale.log()?;
        let log_prob = ((actions - mean)?
            .sqr()?
            .neg()?
            .broadcast_div(&(var * 2.0)?)?
            .broadcast_sub(&log_scale)?
            - f64::from(LOG_SQRT_2PI))?
        .sum(1)?;

        // (A - mean) / (std + 1e-8), std unbiased (torch's `std()`; candle's `var` divides by n - 1).
        let advantages = advantages
            .broadcast_sub(&advantages.mean_keepdim(0)?)?
            .broadcast_div(&(advantages.var_keepdim(0)?.sqrt()? + 1e-8)?)?;
        let ratio = (log_prob - old_log_prob)?.exp()?;
        let clip = f64::from(CLIP_RANGE);
        let surrogate = (&advantages * &ratio)?;
        let clipped = (&advantages * ratio.clamp(1.0 - clip, 1.0 + clip)?)?;
        let policy_loss = surrogate.minimum(&clipped)?.mean_all()?.neg()?;
        let value_loss = (returns - values)?.sqr()?.mean_all()?;
        // The entropy term is left out: with ent_coef 0 it adds nothing to the loss or the gradient.
        policy_loss + (value_loss * f64::from(VF_COEF))?
    }

    /// One update on `data`; adds each phase's seconds to `phases`; returns the loss and the clipped
    /// gradients.
    fn step(
        &mut self,
        data: &Data,
        phases: &mut [f64; 4],
    ) -> candle_core::Result<(f32, GradStore)> {
        let t0 = Instant::now();
        let loss = self.loss(data)?;
        // The trainer reads the loss (for its statistics and the non-finite test).
        let loss_value = loss.to_scalar::<f32>()?;
        let t1 = Instant::now();
        let mut grads = loss.backward()?;
        let t2 = Instant::now();
        self.clip_grad_norm(&mut grads)?;
        let t3 = Instant::now();
        self.optimizer.step(&grads)?;
        let t4 = Instant::now();
        for (p, (a, b)) in phases
            .iter_mut()
            .zip([(t0, t1), (t1, t2), (t2, t3), (t3, t4)])
        {
            *p += (b - a).as_secs_f64();
        }
        Ok((loss_value, grads))
    }

    /// `torch.nn.utils.clip_grad_norm_(max_norm=0.5)`: the norm of the tensors' norms (each rounded to
    /// float32, as torch computes them), then every gradient times `min(1, 0.5 / (norm + 1e-6))`.
    fn clip_grad_norm(&self, grads: &mut GradStore) -> candle_core::Result<()> {
        let mut total = 0.0f64;
        for (name, var) in &self.vars {
            let Some(g) = grads.get(var) else {
                candle_core::bail!("no gradient for {name}");
            };
            let norm = g.sqr()?.sum_all()?.to_scalar::<f32>()?.sqrt();
            total += f64::from(norm) * f64::from(norm);
        }
        let total = total.sqrt() as f32;
        let coef = (MAX_GRAD_NORM as f32 / (total + 1e-6)).min(1.0);
        for (_, var) in &self.vars {
            if let Some(g) = grads.remove(var) {
                grads.insert(var, (g * f64::from(coef))?);
            }
        }
        Ok(())
    }
}

fn largest_magnitude(values: &[f32]) -> f64 {
    values.iter().fold(0.0, |m, &x| m.max(f64::from(x).abs()))
}

/// For a bias whose gradient is the sum over the rows of `d_out` (`rows x outputs`) times the clip
/// coefficient `coef`: the largest over its outputs of the sum of its terms' magnitudes.
fn bias_terms_scale(d_out: &[f32], outputs: usize, coef: f32) -> f64 {
    (0..outputs)
        .map(|j| {
            d_out
                .iter()
                .skip(j)
                .step_by(outputs)
                .map(|&d| f64::from(d).abs())
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
        * f64::from(coef)
}

/// The worst tensor so far: (figure, tensor name).
#[derive(Default)]
struct Worst(f64, String);

impl Worst {
    fn update(&mut self, value: f64, name: &str) {
        if value >= self.0 {
            *self = Worst(value, name.to_string());
        }
    }
}

/// One update of both on the same parameters and minibatch: the loss, the clipped gradients and the
/// parameters after Adam must agree (see the module doc). Prints the differences; `Ok(false)` on a
/// disagreement.
fn check(arch: Arch, obs_dim: usize, act_dim: usize) -> AnyResult<bool> {
    let (net, params, data) = setup(arch, obs_dim, act_dim);
    let mut hand = HandWritten::new(net.clone(), params.clone());
    let mut candle = Candle::new(&net, &params)?;
    let mut unused = [0.0; 4];
    let hand_loss = hand.step(&data, &mut unused);
    let (candle_loss, candle_grads) = candle.step(&data, &mut unused)?;

    let loss_diff = (f64::from(hand_loss) - f64::from(candle_loss)).abs()
        / f64::from(hand_loss).abs().max(f64::MIN_POSITIVE);
    // Gradients: the largest difference over the tolerance's scale. Parameters: the largest
    // difference relative to the tensor's largest magnitude, and over the tolerance.
    let mut grad_error = Worst::default();
    let mut param_error = Worst::default();
    let mut param_over_tolerance = Worst::default();
    let coef = hand.clip_coefficient;
    for (t, (name, var)) in net.tensors().iter().zip(&candle.vars) {
        let range = t.offset..t.offset + t.len();
        let (hand_grad, hand_param) = (&hand.grads[range.clone()], &hand.params[range]);
        let grad = candle_grads
            .get(var)
            .ok_or_else(|| format!("no candle gradient for {name}"))?
            .flatten_all()?
            .to_vec1::<f32>()?;
        let param = var.flatten_all()?.to_vec1::<f32>()?;

        let terms = match name.as_str() {
            "value_net.bias" => bias_terms_scale(&hand.ws.d_value[..ROWS], 1, coef),
            "action_net.bias" => bias_terms_scale(&hand.ws.d_mean[..ROWS * act_dim], act_dim, coef),
            _ => 0.0,
        };
        let grad_scale = largest_magnitude(hand_grad)
            .max(terms)
            .max(f64::MIN_POSITIVE);
        let grad_diff = hand_grad.iter().zip(&grad).fold(0.0f64, |m, (&a, &b)| {
            m.max((f64::from(a) - f64::from(b)).abs())
        });
        grad_error.update(grad_diff / grad_scale, name);

        let param_scale = largest_magnitude(hand_param).max(f64::MIN_POSITIVE);
        let (_, _, eps) = Adam::new(0).hyper();
        let d = TOLERANCE * grad_scale;
        let (mut diff, mut over) = (0.0f64, 0.0f64);
        for ((&a, &b), &g) in hand_param.iter().zip(&param).zip(hand_grad) {
            let adam = LEARNING_RATE * eps / (f64::from(g).abs() + eps).powi(2) * d;
            let e = (f64::from(a) - f64::from(b)).abs();
            diff = diff.max(e);
            over = over.max(e / (TOLERANCE * param_scale + adam));
        }
        param_error.update(diff / param_scale, name);
        param_over_tolerance.update(over, name);
    }
    let ok = loss_diff <= TOLERANCE && grad_error.0 <= TOLERANCE && param_over_tolerance.0 <= 1.0;
    println!(
        "check {}: loss {hand_loss:.7} hand-written, {candle_loss:.7} candle (relative difference \
         {loss_diff:.1e}); clipped gradients {:.1e} of their scale ({}); parameters after Adam \
         {:.1e} of the tensor's largest magnitude ({}), {:.2} of the tolerance ({}): {}",
        shape_name(arch, obs_dim, act_dim),
        grad_error.0,
        grad_error.1,
        param_error.0,
        param_error.1,
        param_over_tolerance.0,
        param_over_tolerance.1,
        if ok { "agree" } else { "DISAGREE" }
    );
    Ok(ok)
}
