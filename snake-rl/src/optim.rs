//! The optimiser step of SB3's PPO: gradients clipped to a global norm (`clip_grad_norm_`), then
//! Adam (`torch.optim.Adam`, eps 1e-5 as SB3 sets it), both over the flat parameter buffer in one pass
//! each.

use serde::{Deserialize, Serialize};

/// Adam's state: first and second moments of every parameter, and the step count.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Adam {
    /// Exponential average of the gradients.
    pub exp_avg: Vec<f32>,
    /// Exponential average of the squared gradients.
    pub exp_avg_sq: Vec<f32>,
    /// Steps taken.
    pub step: u64,
    /// beta1 (0.9).
    pub beta1: f64,
    /// beta2 (0.999).
    pub beta2: f64,
    /// eps (1e-5, SB3's choice for PPO; torch's default is 1e-8).
    pub eps: f64,
}

impl Adam {
    /// Zeroed state for `len` parameters with SB3's settings.
    pub fn new(len: usize) -> Self {
        Adam {
            exp_avg: vec![0.0; len],
            exp_avg_sq: vec![0.0; len],
            step: 0,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-5,
        }
    }

    /// One step at learning rate `lr`, as torch's single-tensor Adam (no weight decay, no amsgrad):
    /// the scalars in double as Python computes them, the tensor arithmetic in float32.
    pub fn step(&mut self, params: &mut [f32], grads: &[f32], lr: f64) {
        self.step += 1;
        let step = AdamStep::new(self.hyper(), lr, self.step);
        step.apply(params, grads, &mut self.exp_avg, &mut self.exp_avg_sq);
    }

    /// beta1, beta2 and eps.
    pub fn hyper(&self) -> (f64, f64, f64) {
        (self.beta1, self.beta2, self.eps)
    }
}

/// The scalars of Adam's step number `t` (from 1) at learning rate `lr`, ready to update any range
/// of the parameters (two threads can update two ranges of one step).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdamStep {
    step_size: f32,
    bc2_sqrt: f32,
    w1: f32,
    beta2: f32,
    w2: f32,
    eps: f32,
}

impl AdamStep {
    /// Step `t` with Adam's `(beta1, beta2, eps)` at learning rate `lr`.
    pub fn new((beta1, beta2, eps): (f64, f64, f64), lr: f64, t: u64) -> Self {
        let t = t as f64;
        let bias_correction1 = 1.0 - beta1.powf(t);
        let bias_correction2 = 1.0 - beta2.powf(t);
        AdamStep {
            step_size: (lr / bias_correction1) as f32,
            bc2_sqrt: bias_correction2.sqrt() as f32,
            w1: (1.0 - beta1) as f32,
            beta2: beta2 as f32,
            w2: (1.0 - beta2) as f32,
            eps: eps as f32,
        }
    }

    /// Updates `params` and their moments from `grads` (all four of one length).
    pub fn apply(
        &self,
        params: &mut [f32],
        grads: &[f32],
        exp_avg: &mut [f32],
        exp_avg_sq: &mut [f32],
    ) {
        let s = *self;
        crate::simd::dispatch(|| {
            for (((p, g), m), v) in params
                .iter_mut()
                .zip(grads)
                .zip(exp_avg.iter_mut())
                .zip(exp_avg_sq.iter_mut())
            {
                // exp_avg.lerp_(grad, 1 - beta1): torch's lerp for a weight below 0.5.
                *m += s.w1 * (g - *m);
                *v = *v * s.beta2 + s.w2 * (g * g);
                let denom = v.sqrt() / s.bc2_sqrt + s.eps;
                *p += -s.step_size * (*m / denom);
            }
        });
    }
}

/// The sum over `tensors` ((offset, length) ranges of `grads`) of their squared norms, each norm
/// rounded to float32 as torch's `clip_grad_norm_` computes the per-tensor norms it then combines.
pub fn squared_norms(grads: &[f32], tensors: &[(usize, usize)]) -> f64 {
    tensors
        .iter()
        .map(|&(offset, len)| {
            let norm = crate::simd::dispatch(|| sum_of_squares(&grads[offset..offset + len])).sqrt()
                as f32;
            f64::from(norm) * f64::from(norm)
        })
        .sum()
}

/// `min(1, max_norm / (total_norm + 1e-6))`: the factor `clip_grad_norm_` scales gradients by.
pub fn clip_coefficient(total_norm: f32, max_norm: f64) -> f32 {
    (max_norm as f32 / (total_norm + 1e-6)).min(1.0)
}

/// Multiplies every gradient by `coef`.
pub fn scale(grads: &mut [f32], coef: f32) {
    crate::simd::dispatch(|| {
        for g in grads.iter_mut() {
            *g *= coef;
        }
    });
}

/// `torch.nn.utils.clip_grad_norm_(max_norm)`: scales all gradients by
/// `min(1, max_norm / (total_norm + 1e-6))`; returns the total norm before clipping. `tensors` are the
/// (offset, length) ranges whose norms make up the total, as torch takes the norm of the per-tensor
/// norms.
pub fn clip_grad_norm(grads: &mut [f32], tensors: &[(usize, usize)], max_norm: f64) -> f32 {
    let total = squared_norms(grads, tensors).sqrt() as f32;
    scale(grads, clip_coefficient(total, max_norm));
    total
}

/// Sum of squares in double, over 8 interleaved partial sums so that it vectorises.
#[inline(always)]
fn sum_of_squares(values: &[f32]) -> f64 {
    let mut acc = [0.0f64; 8];
    let chunks = values.chunks_exact(8);
    let tail = chunks.remainder();
    for c in chunks {
        for (a, &g) in acc.iter_mut().zip(c) {
            *a += f64::from(g) * f64::from(g);
        }
    }
    acc.iter().sum::<f64>()
        + tail
            .iter()
            .map(|&g| f64::from(g) * f64::from(g))
            .sum::<f64>()
}
