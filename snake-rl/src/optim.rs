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
        let t = self.step as f64;
        let bias_correction1 = 1.0 - self.beta1.powf(t);
        let bias_correction2 = 1.0 - self.beta2.powf(t);
        let step_size = (lr / bias_correction1) as f32;
        let bc2_sqrt = bias_correction2.sqrt() as f32;
        let w1 = (1.0 - self.beta1) as f32;
        let beta2 = self.beta2 as f32;
        let w2 = (1.0 - self.beta2) as f32;
        let eps = self.eps as f32;
        let (exp_avg, exp_avg_sq) = (&mut self.exp_avg, &mut self.exp_avg_sq);
        crate::simd::dispatch(|| {
            for (((p, g), m), v) in params
                .iter_mut()
                .zip(grads)
                .zip(exp_avg.iter_mut())
                .zip(exp_avg_sq.iter_mut())
            {
                // exp_avg.lerp_(grad, 1 - beta1): torch's lerp for a weight below 0.5.
                *m += w1 * (g - *m);
                *v = *v * beta2 + w2 * (g * g);
                let denom = v.sqrt() / bc2_sqrt + eps;
                *p += -step_size * (*m / denom);
            }
        });
    }
}

/// `torch.nn.utils.clip_grad_norm_(max_norm)`: scales all gradients by
/// `min(1, max_norm / (total_norm + 1e-6))`; returns the total norm before clipping. `tensors` are the
/// (offset, length) ranges whose norms make up the total, as torch takes the norm of the per-tensor
/// norms.
pub fn clip_grad_norm(grads: &mut [f32], tensors: &[(usize, usize)], max_norm: f64) -> f32 {
    let mut total = 0.0f64;
    for &(offset, len) in tensors {
        let norm = crate::simd::dispatch(|| sum_of_squares(&grads[offset..offset + len])).sqrt() as f32;
        total += f64::from(norm) * f64::from(norm);
    }
    let total = total.sqrt() as f32;
    let coef = (max_norm as f32 / (total + 1e-6)).min(1.0);
    crate::simd::dispatch(|| {
        for g in grads.iter_mut() {
            *g *= coef;
        }
    });
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
    acc.iter().sum::<f64>() + tail.iter().map(|&g| f64::from(g) * f64::from(g)).sum::<f64>()
}
