//! Skin friction (issue 27) against independent references: pybullet's Coulomb friction for a block on
//! a slope, Coulomb's holding condition, and the gait's dependence on the skin's anisotropy.

use nalgebra::Vector3;
use serde::Serialize;
use snake_core::world::{BoxChain, Dynamics, World};
use snake_core::{
    quaternion_from_euler, Gait, LateralUndulation, Preset, SkinAxis, SkinFriction, Snake,
    StartPose,
};
use snakesim_tests::{read_csv, run_reference_script};

const SLOPE_DEG: f64 = 10.0;
const HALF_EXTENTS: [f64; 3] = [0.1, 0.03, 0.02];
const MASS: f64 = 0.2;
/// The box's x axis points downhill (-y).
const YAW: f64 = -std::f64::consts::FRAC_PI_2;
const GROUND_FRICTION: f64 = 1.0;
/// Two seconds of 1/240 s steps.
const STEPS: usize = 480;

#[derive(Serialize)]
struct SlopeSpec {
    slope_deg: f64,
    half_extents: [f64; 3],
    mass: f64,
    yaw: f64,
    ground_friction: f64,
    steps: usize,
    frictions: Vec<f64>,
}

/// The box of the pybullet reference with skin friction instead of its lateral friction; returns the
/// distance its centre moves in the plane in [`STEPS`] steps.
fn slide_with_skin(skin: SkinFriction) -> f64 {
    let mut world = World::new().unwrap();
    let plane = world.add_plane().unwrap();
    let ground = Dynamics {
        lateral_friction: Some(GROUND_FRICTION),
        ..Dynamics::default()
    };
    world.change_dynamics(plane, None, &ground).unwrap();
    let slope = SLOPE_DEG.to_radians();
    world
        .set_gravity(Vector3::new(0.0, -9.81 * slope.sin(), -9.81 * slope.cos()))
        .unwrap();
    let q = quaternion_from_euler(0.0, 0.0, YAW);
    let body = world
        .add_box_chain(&BoxChain {
            half_extents: HALF_EXTENTS,
            base_mass: MASS,
            base_position: [0.0, 0.0, HALF_EXTENTS[2]],
            base_orientation: q,
            links: vec![],
        })
        .unwrap();
    world
        .set_skin_friction(body, None, &skin, SkinAxis::X)
        .unwrap();
    let start = world.base_state(body).unwrap().pose.position;
    for _ in 0..STEPS {
        world.step().unwrap();
    }
    let end = world.base_state(body).unwrap().pose.position;
    (end - start).xy().norm()
}

fn skin(forward: f64, backward: f64, transverse: f64, axis: SkinAxis) -> SkinFriction {
    SkinFriction {
        axis: Some(axis),
        ..SkinFriction::new(forward, backward, transverse)
    }
}

/// Head first, tail first and sideways, the box slides as pybullet's box with isotropic friction equal
/// to the coefficient of that direction: within 5 % of its distance over 2 s.
#[test]
fn slope_slides_as_coulomb_with_the_matching_coefficient() {
    let (forward, backward, transverse) = (0.05, 0.1, 0.15);
    assert!(
        transverse < SLOPE_DEG.to_radians().tan(),
        "every case slides"
    );
    // The box's x axis points downhill: skin axis x slides head first, -x tail first, y sideways.
    let cases = [
        ("head first", SkinAxis::X, forward),
        ("tail first", SkinAxis::NegX, backward),
        ("sideways", SkinAxis::Y, transverse),
        // An axis normal to the ground leaves every direction in the plane transverse.
        ("axis normal to the ground", SkinAxis::Z, transverse),
    ];
    let spec = SlopeSpec {
        slope_deg: SLOPE_DEG,
        half_extents: HALF_EXTENTS,
        mass: MASS,
        yaw: YAW,
        ground_friction: GROUND_FRICTION,
        steps: STEPS,
        frictions: cases.iter().map(|c| c.2).collect(),
    };
    let Some(dir) = run_reference_script("skin_slope_reference.py", &spec, "skin-slope") else {
        return;
    };
    let table = read_csv(&dir.join("slope.csv"));
    std::fs::remove_dir_all(&dir).ok();
    for ((name, axis, mu), row) in cases.iter().zip(&table.rows) {
        let reference = row[2];
        let ours = slide_with_skin(skin(forward, backward, transverse, *axis));
        let error = (ours - reference).abs() / reference;
        eprintln!(
            "{name}: mu {mu}: pybullet {reference:.4} m, skin {ours:.4} m ({:.2} %)",
            100.0 * error
        );
        assert!(
            error < 0.05,
            "{name} (mu {mu}): skin friction moved {ours} m, pybullet's Coulomb friction {reference} m"
        );
    }
}

/// Where the coefficient of the direction the box would slide exceeds tan(slope), it holds, whatever
/// the other two coefficients (Coulomb: a block holds while mu >= tan(slope)).
#[test]
fn slope_holds_where_the_coefficient_exceeds_the_tangent() {
    let (low, high) = (0.05, 0.3);
    let tan = SLOPE_DEG.to_radians().tan();
    assert!(low < tan && high > tan);
    let cases = [
        ("head first", skin(high, low, low, SkinAxis::X)),
        ("tail first", skin(low, high, low, SkinAxis::NegX)),
        ("sideways", skin(low, low, high, SkinAxis::Y)),
    ];
    for (name, s) in cases {
        let moved = slide_with_skin(s);
        // A held box creeps only by the solver's residual: well under a millimetre in 2 s, against the
        // ~2.4 m it slides with the low coefficient.
        assert!(moved < 1e-3, "{name}: held box moved {moved} m");
    }
}

/// Distance the built-in 10-joint snake's sine gait covers in `seconds` with the given skin.
fn gait_distance(skin: SkinFriction, seconds: f64) -> f64 {
    let mut config = Preset::Paper.config(10);
    config.skin_friction = Some(skin);
    let mut snake = Snake::new(&config, StartPose::resting(config.half_extent)).unwrap();
    let mut gait = LateralUndulation::default();
    gait.dt = config.dt;
    let mut targets = vec![0.0; config.joints];
    let start = snake.base_state().unwrap().pose.position;
    for _ in 0..(seconds / config.dt).round() as usize {
        gait.next_targets(&mut targets);
        snake.set_targets(&targets).unwrap();
        snake.step().unwrap();
    }
    (snake.base_state().unwrap().pose.position - start)
        .xy()
        .norm()
}

/// Hu et al.: the gait needs the transverse/forward anisotropy. With isotropic skin of the transverse
/// coefficient, the sine gait travels less than a tenth as far as with skin 0.05 / 0.05 / 5.
#[test]
fn isotropic_skin_loses_the_gaits_progress() {
    let anisotropic = gait_distance(SkinFriction::new(0.05, 0.05, 5.0), 10.0);
    let isotropic = gait_distance(SkinFriction::new(5.0, 5.0, 5.0), 10.0);
    eprintln!("10 s of the sine gait: skin 0.05/0.05/5 {anisotropic:.3} m, 5/5/5 {isotropic:.3} m");
    assert!(
        anisotropic > 5.0,
        "the anisotropic skin moves the snake: {anisotropic} m"
    );
    assert!(
        isotropic < 0.1 * anisotropic,
        "isotropic skin {isotropic} m against anisotropic {anisotropic} m"
    );
}

/// The native trainer's side: a run config's `env.snake.skin_friction` reaches the env it builds, its
/// YAML round trip keeps it, and a saved policy's metadata (what evaluate and replay rebuild the env
/// from) carries it.
#[test]
fn run_configs_and_saved_policies_carry_skin_friction() {
    use snake_rl::config::RunConfig;
    use snake_rl::model::{load_policy, save_policy, SavedPolicy};
    use snake_rl::nn::{ActorCritic, Arch};

    let skin = SkinFriction {
        axis: Some(SkinAxis::NegY),
        ..SkinFriction::new(0.05, 0.1, 5.0)
    };
    let run = RunConfig::from_yaml(
        "joints: 4\nenv:\n  snake:\n    skin_friction: {forward: 0.05, backward: 0.1, transverse: 5, axis: -y}\n",
    )
    .unwrap();
    assert_eq!(run.env_config().unwrap().snake.skin_friction, Some(skin));
    let again = RunConfig::from_yaml(&run.to_yaml()).unwrap();
    assert_eq!(again.env_config().unwrap().snake.skin_friction, Some(skin));

    let spec = snake_rl::model::EnvSpec {
        joints: run.joints,
        preset: run.preset,
        env: run.env.clone(),
    };
    let config = spec.config().unwrap();
    let net = ActorCritic::new(Arch::Small, config.observation_dim(), config.action_dim());
    let policy = SavedPolicy {
        params: vec![0.0; net.len()],
        net,
        obs_rms: None,
        env: spec,
        steer_assist: None,
        timesteps: 0,
    };
    let dir = std::env::temp_dir().join(format!("snakesim-skin-model-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("model.safetensors");
    save_policy(&path, &policy).unwrap();
    let loaded = load_policy(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(loaded.env.config().unwrap().snake.skin_friction, Some(skin));
    assert_eq!(loaded, policy);

    let bad = RunConfig::from_yaml(
        "env:\n  snake:\n    skin_friction: {forward: 0.05, backward: -1, transverse: 5}\n",
    )
    .and_then(|r| r.env_config())
    .unwrap_err()
    .to_string();
    assert_eq!(
        bad,
        "env.snake.skin_friction.backward: must be finite and in [0, 10], got -1.0"
    );
}
