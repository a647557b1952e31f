//! Stable-Baselines3's initialisation: every weight orthogonal with its role's gain, every bias 0,
//! `log_std` 0 (a standard deviation of 1).

use nalgebra::DMatrix;
use rand::Rng;
use rand_distr::StandardNormal;

use super::network::ActorCritic;

/// `torch.nn.init.orthogonal_` for a `rows x cols` weight: the Q factor of a standard-normal matrix
/// (transposed first when it is wide), with the signs of R's diagonal folded in, times `gain`.
pub fn orthogonal<R: Rng>(rng: &mut R, rows: usize, cols: usize, gain: f64) -> Vec<f32> {
    let wide = rows < cols;
    let (m, n) = if wide { (cols, rows) } else { (rows, cols) };
    let normal = DMatrix::<f64>::from_fn(m, n, |_, _| rng.sample(StandardNormal));
    let qr = normal.qr();
    let mut q = qr.q();
    let r = qr.r();
    for j in 0..n {
        let sign = r[(j, j)].signum();
        q.column_mut(j).scale_mut(sign);
    }
    let q = if wide { q.transpose() } else { q };
    // Row-major rows x cols.
    let mut out = Vec::with_capacity(rows * cols);
    for i in 0..rows {
        for j in 0..cols {
            out.push((q[(i, j)] * gain) as f32);
        }
    }
    out
}

/// A freshly initialised parameter buffer for `net`.
pub fn init_params<R: Rng>(net: &ActorCritic, rng: &mut R) -> Vec<f32> {
    let mut params = vec![0.0f32; net.len()];
    for (d, role) in net.layers() {
        let w = orthogonal(rng, d.outputs, d.inputs, role.gain());
        params[d.weight..d.weight + w.len()].copy_from_slice(&w);
    }
    params
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn gram(w: &[f32], rows: usize, cols: usize, by_rows: bool) -> Vec<f64> {
        let n = if by_rows { rows } else { cols };
        let at = |i: usize, j: usize| w[i * cols + j] as f64;
        let mut g = vec![0.0; n * n];
        for a in 0..n {
            for b in 0..n {
                g[a * n + b] = if by_rows {
                    (0..cols).map(|k| at(a, k) * at(b, k)).sum()
                } else {
                    (0..rows).map(|k| at(k, a) * at(k, b)).sum()
                };
            }
        }
        g
    }

    #[test]
    fn orthogonal_rows_or_columns_with_the_gain() {
        let mut rng = rand_chacha::ChaCha12Rng::seed_from_u64(1);
        // Tall (columns orthonormal), wide (rows orthonormal), square.
        for (rows, cols, gain) in [(64, 12, 2f64.sqrt()), (5, 64, 0.01), (64, 64, 1.0)] {
            let w = orthogonal(&mut rng, rows, cols, gain);
            let by_rows = rows <= cols;
            let n = rows.min(cols);
            let g = gram(&w, rows, cols, by_rows);
            for a in 0..n {
                for b in 0..n {
                    let expected = if a == b { gain * gain } else { 0.0 };
                    assert!((g[a * n + b] - expected).abs() < 1e-5 * gain * gain.max(1.0));
                }
            }
        }
    }
}
