//! Skin friction against Hu, Nirody, Scott and Shelley's quasi-static model of slithering (PNAS
//! 106:10081, 2009), implemented independently of Bullet in `tests/reference/hu_model_reference.py`.
//! A 17-link snake runs a slow sine gait with skin friction; its own shape over time (each link's
//! position and skin axis) goes to the model, which predicts the body's velocity from the balance of
//! friction forces and torques alone.
//!
//! NOT YET A VALIDATION: the test prints the comparison and asserts nothing, and is ignored. Measured
//! (`cargo test --release -p snakesim-tests --test hu_model -- --ignored --nocapture`), the model and
//! the simulation agree in trend (speed rising with mu_t/mu_f) but not in value: at mu_t/mu_f = 1 the
//! simulated snake moves 0.075-0.081 m/s against the model's 0.009-0.022, at 10 0.18-0.20 against 0.29.
//! The likely cause is the model's equal weight per element: the cubes are as tall as they are long
//! (0.5 m), so friction at the ground (up to 5 m g) moves their weight between their corners, which the
//! model, as Hu et al. wrote it, does not see. Next: feed the model each contact's normal force
//! (Bullet's), or a flat, light link whose tipping moment is small, before choosing a tolerance.

use serde::Serialize;
use snake_core::{Gait, LateralUndulation, Preset, SkinFriction, Snake, StartPose, WorldSpec};
use snakesim_tests::run_reference_script;

const JOINTS: usize = 16;
/// The gait's period, s: slow, so that inertia stays small beside friction (see the tolerance).
const PERIOD: f64 = 6.0;
/// Steps between shape samples (1/60 s).
const SAMPLE: usize = 4;
const MU_F: f64 = 0.5;
const RATIOS_T: [f64; 6] = [1.0, 1.5, 2.0, 3.0, 5.0, 10.0];
const RATIOS_B: [f64; 2] = [1.0, 1.5];

#[derive(Serialize)]
struct Case {
    forward: f64,
    backward: f64,
    transverse: f64,
    sample_dt: f64,
    positions: Vec<Vec<[f64; 2]>>,
    axes: Vec<Vec<[f64; 2]>>,
}

#[derive(Serialize)]
struct Spec {
    cases: Vec<Case>,
}

#[derive(serde::Deserialize)]
struct ModelResult {
    model_velocity: [f64; 2],
    model_rotation: f64,
    worst_residual: f64,
}

/// One period of warm-up (the gait's amplitude ramps in), then one period sampled. Returns the case
/// and the simulated body's mean velocity over the sampled period, from the links' mean position.
fn simulate(forward: f64, backward: f64, transverse: f64) -> (Case, [f64; 2]) {
    let mut config = Preset::Paper.config(JOINTS);
    config.skin_friction = Some(SkinFriction::new(forward, backward, transverse));
    // A ground of friction 1 leaves the skin's coefficients as written.
    let world = WorldSpec {
        ground_friction: Some(1.0),
        ..WorldSpec::default()
    };
    let mut snake =
        Snake::in_world(&config, StartPose::resting(config.half_extent), &world).unwrap();
    let mut gait = LateralUndulation::default();
    gait.period = PERIOD;
    gait.dt = config.dt;
    let mut targets = vec![0.0; config.joints];
    let period_steps = (PERIOD / config.dt).round() as usize;
    let (mut positions, mut axes) = (Vec::new(), Vec::new());
    for step in 0..2 * period_steps + 2 * SAMPLE {
        if step >= period_steps && (step - period_steps).is_multiple_of(SAMPLE) {
            let poses = snake.cube_poses().unwrap();
            // Each cube rests on its four bottom corners, where Bullet's contacts are: they are the
            // model's elements, so that a cube turning about its own centre (its corners slide) is
            // in the model too. A cube as one point element would miss that friction torque.
            let h = config.half_extent;
            let (mut p_row, mut a_row) = (Vec::new(), Vec::new());
            for p in &poses {
                // The skin axis: the built-in snake's head direction, -y in each cube's frame.
                let a = p.orientation * nalgebra::Vector3::new(0.0, -1.0, 0.0);
                for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                    let c = p.position + p.orientation * nalgebra::Vector3::new(sx * h, sy * h, -h);
                    p_row.push([c.x, c.y]);
                    a_row.push([a.x, a.y]);
                }
            }
            positions.push(p_row);
            axes.push(a_row);
        }
        gait.next_targets(&mut targets);
        snake.set_targets(&targets).unwrap();
        snake.step().unwrap();
    }
    // The model's mean covers samples 1 .. n-2 (central differences): so does this displacement.
    let centre = |k: usize| {
        let p: &Vec<[f64; 2]> = &positions[k];
        let n = p.len() as f64;
        [
            p.iter().map(|q| q[0]).sum::<f64>() / n,
            p.iter().map(|q| q[1]).sum::<f64>() / n,
        ]
    };
    let n = positions.len();
    let span = (n - 3) as f64 * SAMPLE as f64 * config.dt;
    let (a, b) = (centre(1), centre(n - 2));
    let velocity = [(b[0] - a[0]) / span, (b[1] - a[1]) / span];
    let case = Case {
        forward,
        backward,
        transverse,
        sample_dt: SAMPLE as f64 * config.dt,
        positions,
        axes,
    };
    (case, velocity)
}

#[test]
#[ignore = "diagnostic: the comparison does not agree yet; see the module comment"]
fn mean_velocity_against_hu_et_al_model() {
    let mut cases = Vec::new();
    let mut simulated = Vec::new();
    for rb in RATIOS_B {
        for rt in RATIOS_T {
            let (case, v) = simulate(MU_F, MU_F * rb, MU_F * rt);
            cases.push(case);
            simulated.push((rb, rt, v));
        }
    }
    let Some(dir) = run_reference_script("hu_model_reference.py", &Spec { cases }, "hu-model")
    else {
        return;
    };
    let results: Vec<ModelResult> =
        serde_json::from_str(&std::fs::read_to_string(dir.join("hu_model.json")).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    for ((rb, rt, v), m) in simulated.iter().zip(&results) {
        let diff =
            ((v[0] - m.model_velocity[0]).powi(2) + (v[1] - m.model_velocity[1]).powi(2)).sqrt();
        println!(
            "mu_b/mu_f {rb} mu_t/mu_f {rt}: simulated ({:.4}, {:.4}) m/s, model ({:.4}, {:.4}) m/s, rotation {:.4} rad/s, |diff| {diff:.4}, residual {:.1e}",
            v[0], v[1], m.model_velocity[0], m.model_velocity[1], m.model_rotation, m.worst_residual
        );
    }
}
