//! The distance to the goal as the paper's Python computes it, and the reward terms.

use serde::{Deserialize, Serialize};

/// In which precision the goal-minus-position differences of the paper's reward are taken.
///
/// The paper's env computes `-hypot(goal[0] - state[0], goal[1] - state[1])`, where `goal` holds
/// Python numbers and `state` is the `float32` observation. What `python number - np.float32` gives
/// depends on the numpy version:
///
/// - numpy >= 2 (NEP 50, "weak" Python scalars): the Python number is converted to `float32` and the
///   difference is a `float32`, rounded to 24 bits ([`DistancePrecision::Float32`]);
/// - numpy 1.x (legacy promotion; a Python int/float next to a numpy scalar is int64/float64): the
///   difference is a `float64` ([`DistancePrecision::Float64`]).
///
/// Either way `math.hypot` then works in double precision on the differences.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DistancePrecision {
    /// numpy >= 2 (the reference environment's numpy 2.x): `float32` differences.
    #[default]
    Float32,
    /// numpy 1.x (the paper's own 2021 setup): `float64` differences.
    Float64,
}

impl DistancePrecision {
    /// The configuration name (`float32` or `float64`).
    pub fn name(self) -> &'static str {
        match self {
            DistancePrecision::Float32 => "float32",
            DistancePrecision::Float64 => "float64",
        }
    }
}

/// Distance from the base (as the `float32` observation holds it) to the goal, computed as the
/// paper's `hypot(goal_x - state[0], goal_y - state[1])` with the given numpy semantics.
pub fn paper_distance(goal: (f64, f64), x: f32, y: f32, precision: DistancePrecision) -> f64 {
    let (dx, dy) = match precision {
        // NEP 50: the Python scalar becomes a float32 first, then one float32 subtraction.
        DistancePrecision::Float32 => (((goal.0 as f32) - x) as f64, ((goal.1 as f32) - y) as f64),
        DistancePrecision::Float64 => (goal.0 - x as f64, goal.1 - y as f64),
    };
    python_hypot(dx, dy)
}

/// CPython 3.11's `math.hypot(x, y)`, bit for bit.
///
/// glibc's `hypot` differs from it in about 0.2% of random inputs by one ulp, so the paper's reward
/// can only be reproduced with CPython's own algorithm (`vector_norm` in `Modules/mathmodule.c`,
/// 3.10/3.11): lossless power-of-two scaling, Veltkamp-Dekker splitting for exact squares,
/// compensated (Neumaier) summation and one differential correction of the square root.
pub fn python_hypot(x: f64, y: f64) -> f64 {
    let (x, y) = (x.abs(), y.abs());
    let mut max = 0.0;
    let mut found_nan = false;
    for v in [x, y] {
        found_nan |= v.is_nan();
        if v > max {
            max = v;
        }
    }
    vector_norm([x, y], max, found_nan)
}

/// Smallest positive normal double (C's `DBL_MIN`).
const DBL_MIN: f64 = f64::MIN_POSITIVE;

fn vector_norm(vec: [f64; 2], max: f64, found_nan: bool) -> f64 {
    // 2^27 + 1, the Veltkamp-Dekker splitting constant for doubles.
    const T27: f64 = 134217729.0;
    if max.is_infinite() {
        return max;
    }
    if found_nan {
        return f64::NAN;
    }
    if max == 0.0 {
        return max;
    }
    let max_e = frexp_exponent(max);
    if max_e < -1023 {
        // ldexp(1.0, -max_e) would overflow: convert subnormals to normals first.
        return DBL_MIN * vector_norm([vec[0] / DBL_MIN, vec[1] / DBL_MIN], max / DBL_MIN, false);
    }
    let scale = exp2i(-max_e);
    let (mut csum, mut frac1, mut frac2, mut frac3) = (1.0f64, 0.0f64, 0.0f64, 0.0f64);
    for v in vec {
        let x = v * scale; // lossless scaling
        let t = x * T27;
        let hi = t - (t - x); // Veltkamp-Dekker splitting
        let lo = x - hi;
        let sq = hi * hi; // lossless squaring
        let old = csum;
        csum += sq;
        frac1 += (old - csum) + sq; // lossless addition
        let cross = 2.0 * hi * lo;
        let old = csum;
        csum += cross;
        frac2 += (old - csum) + cross;
        frac3 += lo * lo;
    }
    let h = (csum - 1.0 + (frac1 + frac2 + frac3)).sqrt();
    let t = h * T27;
    let hi = t - (t - h);
    let lo = h - hi;
    let x = -hi * hi;
    let old = csum;
    csum += x;
    frac1 += (old - csum) + x;
    let x = -2.0 * hi * lo;
    let old = csum;
    csum += x;
    frac2 += (old - csum) + x;
    let x = -lo * lo;
    let old = csum;
    csum += x;
    frac3 += (old - csum) + x;
    let x = csum - 1.0 + (frac1 + frac2 + frac3);
    (h + x / (2.0 * h)) / scale
}

/// The exponent `e` of C's `frexp(v)` (`v = m 2^e`, `0.5 <= |m| < 1`) for finite non-zero `v`.
fn frexp_exponent(v: f64) -> i32 {
    let biased = ((v.to_bits() >> 52) & 0x7ff) as i32;
    if biased == 0 {
        // Subnormal: scale into the normal range (exactly) and correct.
        frexp_exponent(v * exp2i(54)) - 54
    } else {
        biased - 1022
    }
}

/// `2^e` exactly, for `-1074 <= e <= 1023` (C's `ldexp(1.0, e)`).
fn exp2i(e: i32) -> f64 {
    debug_assert!((-1074..=1023).contains(&e));
    if e >= -1022 {
        f64::from_bits(((e + 1023) as u64) << 52)
    } else {
        f64::from_bits(1u64 << (e + 1074))
    }
}

/// Each term of one step's reward; the reward is their sum.
///
/// Terms whose weight is 0 (the default) are exactly 0 and are not added, so the paper's reward
/// keeps its bits.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct RewardTerms {
    /// The paper's term: minus `distance_weight` times the distance to the goal (the paper: weight 1),
    /// or the success reward (100) on the step that ends within the goal radius.
    pub goal: f64,
    /// `progress_weight * (previous distance - distance)`: positive when the base approached the goal.
    /// With `progress_around_craters` the distances are measured along the shortest way around the
    /// craters (`snake_core::route_distance`).
    pub progress: f64,
    /// `-smoothness_weight * sum_i (a_i - previous a_i)^2` over the action clipped to [-1, 1] (in the
    /// `joints` mode with `action_scale` 1, the joint targets in radians); the previous action of an
    /// episode's first step is 0.
    pub smoothness: f64,
    /// `-energy_weight * sum over the step's physics steps and joints of |torque_j * velocity_j| * dt`:
    /// the mechanical work (J) of the motors, torque after each physics step times the joint velocity.
    pub energy: f64,
}

/// What one step's reward is computed from.
#[derive(Debug, Clone, Copy)]
pub struct RewardInputs<'a> {
    /// The base ended the step within the goal radius.
    pub success: bool,
    /// Distance to the goal after the step ([`paper_distance`]).
    pub distance: f64,
    /// The distance the progress term measures after the step: `distance`, or with
    /// `progress_around_craters` or `progress_around_ridges` the way around the craters or ridges.
    pub progress_distance: f64,
    /// The same before the step.
    pub previous_progress_distance: f64,
    /// The step's action, clipped to [-1, 1].
    pub action: &'a [f64],
    /// The previous step's (zeros on an episode's first step).
    pub previous_action: &'a [f64],
    /// The motors' mechanical work over the step, J.
    pub work: f64,
}

impl RewardTerms {
    /// One step's reward terms (Gymnasium's `_get_rew`: the reward is [`RewardTerms::total`], the
    /// terms go to `info`). Terms whose weight is 0 stay exactly 0.
    pub fn compute(weights: &RewardConfig, step: &RewardInputs<'_>) -> Self {
        let mut terms = RewardTerms {
            goal: if step.success {
                weights.success_reward
            } else {
                -(weights.distance_weight * step.distance)
            },
            ..RewardTerms::default()
        };
        if weights.progress_weight != 0.0 {
            terms.progress = weights.progress_weight
                * (step.previous_progress_distance - step.progress_distance);
        }
        if weights.smoothness_weight != 0.0 {
            let change: f64 = step
                .action
                .iter()
                .zip(step.previous_action)
                .map(|(a, p)| (a - p) * (a - p))
                .sum();
            terms.smoothness = -weights.smoothness_weight * change;
        }
        if weights.energy_weight != 0.0 {
            terms.energy = -weights.energy_weight * step.work;
        }
        terms
    }

    /// The reward: the goal term plus every enabled shaping term.
    pub fn total(&self, weights: &RewardConfig) -> f64 {
        let mut reward = self.goal;
        if weights.progress_weight != 0.0 {
            reward += self.progress;
        }
        if weights.smoothness_weight != 0.0 {
            reward += self.smoothness;
        }
        if weights.energy_weight != 0.0 {
            reward += self.energy;
        }
        reward
    }
}

/// Optional shaping terms (all off by default: the paper's reward) and the distance arithmetic.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RewardConfig {
    /// Weight of minus the distance, the paper's reward (1.0); 0 leaves only the other terms.
    pub distance_weight: f64,
    /// Weight of the progress term (see [`RewardTerms::progress`]); 0 disables it.
    pub progress_weight: f64,
    /// Weight of the smoothness penalty (see [`RewardTerms::smoothness`]); 0 disables it.
    pub smoothness_weight: f64,
    /// Weight of the energy penalty (see [`RewardTerms::energy`]); 0 disables it.
    pub energy_weight: f64,
    /// Reward on the step that ends within the goal radius, replacing minus the distance (100).
    pub success_reward: f64,
    /// Precision of the goal-minus-position differences (see [`DistancePrecision`]).
    pub distance_precision: DistancePrecision,
    /// The progress term measures the distance along the shortest way around the rough ground's
    /// craters (each a disc of the crater's radius plus its `clearance`;
    /// `snake_core::route_distance`) instead of the straight line (false; left out when false).
    /// Success is still judged by the straight line.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub progress_around_craters: bool,
    /// The same around the rough ground's ridges (each a capsule: the ridge's footprint, half its
    /// crest plus a side either way of its crest line, widened by its `clearance`;
    /// `snake_core::Capsule::route_distance`); with both, the longer of the two ways (false; left
    /// out when false).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub progress_around_ridges: bool,
}

impl Default for RewardConfig {
    fn default() -> Self {
        RewardConfig {
            distance_weight: 1.0,
            progress_weight: 0.0,
            smoothness_weight: 0.0,
            energy_weight: 0.0,
            success_reward: 100.0,
            distance_precision: DistancePrecision::Float32,
            progress_around_craters: false,
            progress_around_ridges: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hypot_exact_cases() {
        assert_eq!(python_hypot(3.0, 4.0), 5.0);
        assert_eq!(python_hypot(-3.0, 4.0), 5.0);
        assert_eq!(python_hypot(0.0, 0.0), 0.0);
        assert_eq!(python_hypot(0.0, -2.5), 2.5);
        assert_eq!(python_hypot(f64::INFINITY, f64::NAN), f64::INFINITY);
        assert!(python_hypot(1.0, f64::NAN).is_nan());
        assert_eq!(python_hypot(5e-324, 0.0), 5e-324);
        assert_eq!(python_hypot(3e-320, 4e-320), 5e-320);
        assert_eq!(python_hypot(1e308, 1e308), 1.4142135623730951e308);
    }

    #[test]
    fn frexp_matches_c() {
        assert_eq!(frexp_exponent(1.0), 1);
        assert_eq!(frexp_exponent(0.5), 0);
        assert_eq!(frexp_exponent(0.75), 0);
        assert_eq!(frexp_exponent(f64::MIN_POSITIVE), -1021);
        assert_eq!(frexp_exponent(5e-324), -1073);
        assert_eq!(exp2i(-1074), 5e-324);
        assert_eq!(exp2i(1023), 2f64.powi(1023));
    }

    #[test]
    fn float32_and_float64_differences() {
        // 0.3f32 as f64 is not 0.3; -10 - that rounds differently in 24 and 53 bits.
        let x = 0.3f32;
        let f32_dist = paper_distance((-10.0, 0.0), x, 0.0, DistancePrecision::Float32);
        let f64_dist = paper_distance((-10.0, 0.0), x, 0.0, DistancePrecision::Float64);
        assert_eq!(f32_dist, (-10.0f32 - x).abs() as f64);
        assert_eq!(f64_dist, 10.0 + x as f64);
        assert_ne!(f32_dist, f64_dist);
    }
}
