//! Dense layers over a flat parameter buffer: forward and backward passes for a batch of rows, with
//! the matrix products done by ndarray (which hands them to matrixmultiply's packed AVX/FMA kernels).
//!
//! Layouts follow PyTorch's `nn.Linear`: a layer's weight is `outputs x inputs`, row-major, followed
//! by its `outputs` biases; activations are `rows x width`, row-major (one sample per row).

use ndarray::linalg::general_mat_mul;
use ndarray::{ArrayView2, ArrayViewMut2};

/// Where one dense layer's weight and bias live in the flat parameter buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dense {
    /// Input width.
    pub inputs: usize,
    /// Output width.
    pub outputs: usize,
    /// Offset of the `outputs x inputs` weight.
    pub weight: usize,
    /// Offset of the `outputs` biases.
    pub bias: usize,
}

impl Dense {
    /// A layer whose weight starts at `offset`, its bias right after it.
    pub fn at(offset: usize, inputs: usize, outputs: usize) -> Self {
        Dense {
            inputs,
            outputs,
            weight: offset,
            bias: offset + inputs * outputs,
        }
    }

    /// Parameters of the layer (weight and bias).
    pub fn len(&self) -> usize {
        self.outputs * (self.inputs + 1)
    }

    /// Whether the layer has no parameters (never, for a built network).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The offset just past the layer's bias.
    pub fn end(&self) -> usize {
        self.bias + self.outputs
    }

    fn weight<'a>(&self, params: &'a [f32]) -> ArrayView2<'a, f32> {
        let w = &params[self.weight..self.weight + self.outputs * self.inputs];
        ArrayView2::from_shape((self.outputs, self.inputs), w).expect("weight slice has its shape")
    }

    /// `y = x W^T + b` for `rows` rows of `x`.
    pub fn forward(&self, params: &[f32], x: &[f32], rows: usize, y: &mut [f32]) {
        let bias = &params[self.bias..self.bias + self.outputs];
        let y = &mut y[..rows * self.outputs];
        for row in y.chunks_exact_mut(self.outputs) {
            row.copy_from_slice(bias);
        }
        let x = ArrayView2::from_shape((rows, self.inputs), &x[..rows * self.inputs])
            .expect("input has rows x inputs values");
        let mut y = ArrayViewMut2::from_shape((rows, self.outputs), y).expect("output shape");
        general_mat_mul(1.0, &x, &self.weight(params).t(), 1.0, &mut y);
    }

    /// Gradients of the layer from `dy` (dL/dy, `rows x outputs`) and its input `x`: writes dL/dW and
    /// dL/db into `grads` (overwriting), and dL/dx into `dx` when given.
    pub fn backward(
        &self,
        params: &[f32],
        x: &[f32],
        dy: &[f32],
        rows: usize,
        grads: &mut [f32],
        dx: Option<&mut [f32]>,
    ) {
        let x = ArrayView2::from_shape((rows, self.inputs), &x[..rows * self.inputs])
            .expect("input shape");
        let dy = ArrayView2::from_shape((rows, self.outputs), &dy[..rows * self.outputs])
            .expect("gradient shape");
        {
            let dw = &mut grads[self.weight..self.weight + self.outputs * self.inputs];
            let mut dw =
                ArrayViewMut2::from_shape((self.outputs, self.inputs), dw).expect("weight shape");
            general_mat_mul(1.0, &dy.t(), &x, 0.0, &mut dw);
        }
        let db = &mut grads[self.bias..self.bias + self.outputs];
        db.fill(0.0);
        for row in dy.rows() {
            for (b, g) in db.iter_mut().zip(row) {
                *b += g;
            }
        }
        if let Some(dx) = dx {
            let mut dx =
                ArrayViewMut2::from_shape((rows, self.inputs), &mut dx[..rows * self.inputs])
                    .expect("input gradient shape");
            general_mat_mul(1.0, &dy, &self.weight(params), 0.0, &mut dx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same products written out as loops.
    fn naive_forward(params: &[f32], d: &Dense, x: &[f32], rows: usize) -> Vec<f32> {
        let mut y = vec![0.0; rows * d.outputs];
        for r in 0..rows {
            for o in 0..d.outputs {
                let mut s = params[d.bias + o] as f64;
                for i in 0..d.inputs {
                    s += params[d.weight + o * d.inputs + i] as f64 * x[r * d.inputs + i] as f64;
                }
                y[r * d.outputs + o] = s as f32;
            }
        }
        y
    }

    fn close(a: &[f32], b: &[f32]) {
        for (x, y) in a.iter().zip(b) {
            assert!((x - y).abs() <= 1e-5 * (1.0 + y.abs()), "{x} vs {y}");
        }
    }

    #[test]
    fn forward_and_backward_match_loops() {
        let d = Dense::at(3, 5, 4);
        let params: Vec<f32> = (0..d.end())
            .map(|i| ((i * 37 % 11) as f32 - 5.0) / 7.0)
            .collect();
        let rows = 3;
        let x: Vec<f32> = (0..rows * 5)
            .map(|i| ((i * 13 % 7) as f32 - 3.0) / 5.0)
            .collect();
        let mut y = vec![0.0; rows * 4];
        d.forward(&params, &x, rows, &mut y);
        close(&y, &naive_forward(&params, &d, &x, rows));

        let dy: Vec<f32> = (0..rows * 4).map(|i| (i as f32 - 6.0) / 4.0).collect();
        let mut grads = vec![9.0; d.end()];
        let mut dx = vec![0.0; rows * 5];
        d.backward(&params, &x, &dy, rows, &mut grads, Some(&mut dx));
        for o in 0..4 {
            let db: f32 = (0..rows).map(|r| dy[r * 4 + o]).sum();
            close(&[grads[d.bias + o]], &[db]);
            for i in 0..5 {
                let dw: f32 = (0..rows).map(|r| dy[r * 4 + o] * x[r * 5 + i]).sum();
                close(&[grads[d.weight + o * 5 + i]], &[dw]);
            }
        }
        for r in 0..rows {
            for i in 0..5 {
                let g: f32 = (0..4)
                    .map(|o| dy[r * 4 + o] * params[d.weight + o * 5 + i])
                    .sum();
                close(&[dx[r * 5 + i]], &[g]);
            }
        }
        assert_eq!(
            grads[..3],
            [9.0, 9.0, 9.0],
            "outside the layer is untouched"
        );
    }
}
