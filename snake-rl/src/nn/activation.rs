//! The tanh activation of the hidden layers, forward and backward.
//!
//! libm's `tanhf` costs ~15 ns a call and is not vectorised; a PPO-small minibatch evaluates 16,384 of
//! them, which made tanh most of an update's time. [`tanh`] here is branch-free arithmetic that the
//! compiler vectorises, within 2 ulp of the exact value (tested against double-precision tanh):
//!
//! - |x| < 0.625: `x * p(x^2)`, p a degree-5 polynomial (Chebyshev fit of tanh(x)/x on the interval,
//!   4e-9 relative error before rounding);
//! - otherwise: `1 - 2 / (exp(2|x|) + 1)` with |x| clamped to 9.1 (beyond, tanh rounds to 1 in float32),
//!   and `exp` by range reduction `y = k ln 2 + r`, |r| <= ln(2)/2, and a degree-7 Taylor polynomial.

/// Where the polynomial hands over to the exponential form.
const SMALL: f32 = 0.625;
/// Beyond this tanh rounds to 1 in float32: 1 - tanh(9.1) = 2.5e-8, below half the ulp under 1
/// (2.98e-8); tanh(9) itself still rounds to 0.99999994.
const SATURATE: f32 = 9.1;
/// Coefficients of tanh(x)/x as a polynomial in u = x^2, constant term first.
const P: [f32; 6] = [
    1.0,
    -0.333_332_6,
    0.133_311_5,
    -0.053_722_68,
    0.020_595_68,
    -0.005_664_775,
];
/// 1.5 * 2^23: adding and subtracting it rounds a float32 of magnitude < 2^22 to an integer.
const ROUND: f32 = 12_582_912.0;

/// exp(y) for y in [0, 18.2] (the range tanh needs), branch-free.
#[inline(always)]
fn exp_small_range(y: f32) -> f32 {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    // ln 2 split so that k * LN2_HI is exact for the k used here.
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    let kr = y * LOG2E + ROUND;
    let k = kr - ROUND;
    let r = (y - k * LN2_HI) - k * LN2_LO;
    // Taylor series of exp to r^7 (|r| <= 0.347: truncation error < 5e-9).
    let mut p = 1.0 / 5040.0;
    p = p * r + 1.0 / 720.0;
    p = p * r + 1.0 / 120.0;
    p = p * r + 1.0 / 24.0;
    p = p * r + 1.0 / 6.0;
    p = p * r + 0.5;
    p = p * r + 1.0;
    p = p * r + 1.0;
    // 2^k from the bits of `kr`: its low mantissa bits hold k (plus the rounding constant's bits),
    // which avoids a float-to-int conversion the vector units do slowly.
    let biased = kr.to_bits().wrapping_sub(ROUND.to_bits()).wrapping_add(127);
    p * f32::from_bits(biased << 23)
}

/// tanh(x) in float32, within 2 ulp; NaN stays NaN.
#[inline(always)]
pub fn tanh(x: f32) -> f32 {
    let ax = x.abs();
    let u = x * x;
    let mut p = P[5];
    p = p * u + P[4];
    p = p * u + P[3];
    p = p * u + P[2];
    p = p * u + P[1];
    p = p * u + P[0];
    let near_zero = x * p;
    let e = exp_small_range(2.0 * if ax < SATURATE { ax } else { SATURATE });
    // x's sign onto the positive result with one bitwise or.
    let far = f32::from_bits((1.0 - 2.0 / (e + 1.0)).to_bits() | (x.to_bits() & 0x8000_0000));
    let t = if ax < SMALL { near_zero } else { far };
    if x.is_nan() {
        x
    } else {
        t
    }
}

/// `x <- tanh(x)` elementwise, compiled for the CPU's widest vectors (AVX2 where there is one,
/// chosen at run time: [`crate::simd`]).
pub fn tanh_in_place(x: &mut [f32]) {
    crate::simd::dispatch(|| {
        for v in x {
            *v = tanh(*v);
        }
    });
}

/// `d <- d * (1 - y^2)`: the gradient through tanh, from its output `y` (as PyTorch's `tanh_backward`).
pub fn tanh_backward_in_place(d: &mut [f32], y: &[f32]) {
    crate::simd::dispatch(|| {
        for (g, y) in d.iter_mut().zip(y) {
            *g *= 1.0 - y * y;
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance in units of the last place between two float32 of the same sign.
    fn ulps(a: f32, b: f32) -> u32 {
        if a == b {
            return 0;
        }
        assert_eq!(a.is_sign_negative(), b.is_sign_negative(), "{a} vs {b}");
        a.to_bits().abs_diff(b.to_bits())
    }

    #[test]
    fn within_two_ulp_of_double_precision_tanh() {
        let mut worst = (0, 0.0f32);
        let mut check = |x: f32| {
            let exact = (x as f64).tanh() as f32;
            let d = ulps(tanh(x), exact);
            if d > worst.0 {
                worst = (d, x);
            }
        };
        // Every float32 in [2^-20, 10) with a stride, both signs, plus the hand-over points.
        let mut bits = 1e-6f32.to_bits();
        while f32::from_bits(bits) < 10.0 {
            let x = f32::from_bits(bits);
            check(x);
            check(-x);
            bits += 97;
        }
        for x in [
            SMALL,
            SMALL.next_down(),
            SMALL.next_up(),
            SATURATE,
            20.0,
            88.0,
            1e30,
        ] {
            check(x);
            check(-x);
        }
        assert!(worst.0 <= 2, "{} ulp at x = {:e}", worst.0, worst.1);
    }

    #[test]
    fn special_values() {
        assert_eq!(tanh(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(tanh(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(tanh(1e-30), 1e-30);
        assert_eq!(tanh(f32::INFINITY), 1.0);
        assert_eq!(tanh(f32::NEG_INFINITY), -1.0);
        assert!(tanh(f32::NAN).is_nan());
    }
}
