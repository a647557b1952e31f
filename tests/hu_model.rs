//! Skin friction against Hu, Nirody, Scott and Shelley's quasi-static model of slithering (PNAS
//! 106:10081, 2009), implemented independently of Bullet in `tests/reference/hu_model_reference.py`.
//! A flat, light 17-link snake (`robots/flat-17.yaml`) runs a slow sine gait with skin friction; its
//! own shape over time (each link's four bottom corners, where Bullet's contacts are, and its skin
//! axis) goes to the model, which predicts the body's velocity from the balance of friction forces and
//! torques alone. The model runs twice: as Hu et al. wrote it (equal weight on every element) and with
//! each element's friction scaled by the normal force Bullet gave it.
//!
//! Why the flat snake, with spring contacts: a jointed chain lying on a rigid plane on 4 corners per
//! link is statically indeterminate, and Bullet's solver put the whole weight on a few corners (73 %
//! of them carried nothing; one link carried six times its share). Uneven weight lets even isotropic
//! skin push the body along (Hu et al.'s own weight-redistribution effect), which is why the cube
//! snake moved 0.075 m/s with isotropic skin where the model said 0.009. Spring contacts
//! (`<stiffness>`/`<damping>` in flat-17.urdf) make the split follow the penetration, which is even
//! on flat ground; 4 mm thin links cannot tip their weight between corners; a 6 s period keeps
//! inertia small (see the tolerances).
//!
//! Figures: `SNAKESIM_PYTHON=... cargo test --release -p snakesim-tests --test hu_model -- --nocapture`.

use serde::Serialize;
use snake_core::{Gait, Robot, RobotGait, RobotSpec, Simulation, SkinFriction, WorldSpec};
use snakesim_tests::{repo_root, run_reference_script};

/// Steps between shape samples (1/60 s).
const SAMPLE: usize = 4;
const MU_F: f64 = 0.1;
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
    weights: Vec<Vec<f64>>,
}

#[derive(Serialize)]
struct Spec {
    cases: Vec<Case>,
}

#[derive(serde::Deserialize)]
struct Models {
    equal: ModelResult,
    weighted: ModelResult,
}

#[derive(serde::Deserialize)]
struct ModelResult {
    model_velocity: [f64; 2],
    worst_residual: f64,
    unconverged: usize,
    samples: usize,
}

/// The flat snake's box, m: each link's contacts are its four bottom corners.
const LINK: [f64; 3] = [0.1, 0.05, 0.004];

/// One period of warm-up (the gait's amplitude ramps in), then one period sampled. Returns the case
/// and the simulated body's mean velocity over the sampled period, from the elements' mean position.
fn simulate(forward: f64, backward: f64, transverse: f64) -> (Case, [f64; 2]) {
    let mut spec = RobotSpec::load(&repo_root().join("robots/flat-17.yaml")).unwrap();
    let skin = SkinFriction::new(forward, backward, transverse);
    spec.skin_friction = vec![Some(skin); spec.urdf.links.len()];
    // A ground of friction 1 leaves the skin's coefficients as written.
    let world = WorldSpec {
        ground_friction: Some(1.0),
        ..WorldSpec::default()
    };
    let start = spec.default_start();
    let mut robot = Robot::in_world(&spec, start, &world).unwrap();
    let wave = spec.gait.clone().expect("flat-17.yaml sets its gait");
    let period = wave.period;
    let mut gait = RobotGait::new(wave, &spec);
    let mut targets = vec![0.0; robot.joints()];
    let dt = robot.dt();
    let period_steps = (period / dt).round() as usize;
    let (mut positions, mut axes, mut weights) = (Vec::new(), Vec::new(), Vec::new());
    let [hx, hy, hz] = LINK.map(|v| v / 2.0);
    for step in 0..2 * period_steps + 2 * SAMPLE {
        if step >= period_steps && (step - period_steps).is_multiple_of(SAMPLE) {
            let (mut p_row, mut a_row) = (Vec::new(), Vec::new());
            let poses = robot.body_poses().unwrap();
            let mut w_row = vec![0.0; 4 * poses.len()];
            for c in robot.world().contacts(robot.body()).unwrap() {
                let k = (c.link + 1) as usize;
                let local =
                    poses[k].orientation.inverse() * (c.position_on_body - poses[k].position);
                let corner = 2 * usize::from(local.x > 0.0) + usize::from(local.y > 0.0);
                w_row[4 * k + corner] += c.normal_force;
            }
            weights.push(w_row);
            for p in poses {
                // The skin axis: +x of each link, the head direction.
                let a = p.orientation * nalgebra::Vector3::new(1.0, 0.0, 0.0);
                for (sx, sy) in [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)] {
                    let c =
                        p.position + p.orientation * nalgebra::Vector3::new(sx * hx, sy * hy, -hz);
                    p_row.push([c.x, c.y]);
                    a_row.push([a.x, a.y]);
                }
            }
            positions.push(p_row);
            axes.push(a_row);
        }
        gait.next_targets(&mut targets);
        robot.set_targets(&targets).unwrap();
        robot.step().unwrap();
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
    let span = (n - 3) as f64 * SAMPLE as f64 * dt;
    let (a, b) = (centre(1), centre(n - 2));
    let velocity = [(b[0] - a[0]) / span, (b[1] - a[1]) / span];
    let case = Case {
        forward,
        backward,
        transverse,
        sample_dt: SAMPLE as f64 * dt,
        positions,
        axes,
        weights,
    };
    (case, velocity)
}

/// The gait's wave speed, m/s: the flat snake's wave length over its period (flat-17.yaml).
const WAVE_SPEED: f64 = 0.85 / 6.0;
/// Simulated against the model fed Bullet's own normal force per corner: 2 % of the wave speed. What
/// remains is inertia: the links' accelerations (lateral amplitude about 0.09 m at 2 pi / 6 s, about
/// 0.1 m/s^2) are up to a tenth of the smallest friction per unit mass (mu_f g = 0.98 m/s^2), and the
/// model has none. Measured: at most 0.0017 m/s with the 6 s period, 0.0002 m/s with 12 s (half the
/// speeds, a quarter of the accelerations), so the difference is inertia and shrinks as it does.
const TOL_WEIGHTED: f64 = 0.02 * WAVE_SPEED;
/// Simulated against Hu et al.'s model as written (equal weight on every corner): 4 % of the wave
/// speed. Spring contacts spread the weight evenly along the body (each link's mean within 20 % of its
/// share) but not evenly in time or between a link's corners, and the model cannot see that. Measured:
/// at most 0.0048 m/s (mu_t/mu_f = 3), the same at a 12 s period (0.0027 m/s at half the speed), so
/// it is the weight, not inertia.
const TOL_EQUAL: f64 = 0.04 * WAVE_SPEED;
/// Isotropic skin, "no net progress": under 4 % of the wave speed (measured 0.0033 m/s, backwards).
const TOL_STILL: f64 = 0.04 * WAVE_SPEED;

#[derive(Serialize)]
struct Row {
    backward_ratio: f64,
    transverse_ratio: f64,
    simulated: [f64; 2],
    model_equal: [f64; 2],
    model_weighted: [f64; 2],
}

#[test]
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
    let results: Vec<Models> =
        serde_json::from_str(&std::fs::read_to_string(dir.join("hu_model.json")).unwrap()).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let mut rows = Vec::new();
    let mut failures = Vec::new();
    for ((rb, rt, v), m) in simulated.iter().zip(&results) {
        let (e, w) = (e_of(m), w_of(m));
        // Newton's method may stall on a kink of the law (an element's sliding direction crossing its
        // axis) in a sample or two; at most 1 % of the samples, so it weighs at most 1 % in the mean.
        for r in [&m.equal, &m.weighted] {
            assert!(
                r.unconverged * 100 <= r.samples,
                "{rb}/{rt}: model unconverged in {} of {} samples (worst residual {:.1e})",
                r.unconverged,
                r.samples,
                r.worst_residual
            );
        }
        println!(
            "mu_b/mu_f {rb:<3} mu_t/mu_f {rt:<4}: simulated ({:+.4}, {:+.4}) m/s, Hu model equal weight ({:+.4}, {:+.4}), with Bullet's normal forces ({:+.4}, {:+.4})",
            v[0], v[1], e[0], e[1], w[0], w[1]
        );
        if dist(*v, w) > TOL_WEIGHTED {
            failures.push(format!(
                "{rb}/{rt}: |simulated - weighted model| {:.4} > {TOL_WEIGHTED:.4}",
                dist(*v, w)
            ));
        }
        if dist(*v, e) > TOL_EQUAL {
            failures.push(format!(
                "{rb}/{rt}: |simulated - equal-weight model| {:.4} > {TOL_EQUAL:.4}",
                dist(*v, e)
            ));
        }
        if *rt == 1.0 && v[0].hypot(v[1]) > TOL_STILL {
            failures.push(format!(
                "{rb}/{rt}: isotropic skin moves {:.4} m/s",
                v[0].hypot(v[1])
            ));
        }
        rows.push(Row {
            backward_ratio: *rb,
            transverse_ratio: *rt,
            simulated: *v,
            model_equal: e,
            model_weighted: w,
        });
    }
    // Hu et al.'s trend: forward speed (towards the head, +x) rises with mu_t/mu_f.
    for pair in simulated.windows(2) {
        let ((rb0, rt0, v0), (rb1, rt1, v1)) = (pair[0], pair[1]);
        if rb0 == rb1 && rt1 > rt0 && v1[0] <= v0[0] {
            failures.push(format!(
                "{rb0}: speed does not rise from mu_t/mu_f {rt0} to {rt1}"
            ));
        }
    }
    // For scripts/friction_figure.py (the plot in docs/friction.md).
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("hu_model.json");
    std::fs::write(&out, serde_json::to_string_pretty(&rows).unwrap()).unwrap();
    println!("wrote {}", out.display());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn e_of(m: &Models) -> [f64; 2] {
    m.equal.model_velocity
}

fn w_of(m: &Models) -> [f64; 2] {
    m.weighted.model_velocity
}
