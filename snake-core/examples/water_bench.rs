//! Step cost in water (issue 60): `cargo run --release -p snake-core --example water_bench [STEPS]
//! [ROUNDS]` (defaults 2400 steps, 7 rounds). Drives robots/mamba-10.yaml (9 yaw joints, 10 links)
//! with Kelasidi et al.'s lateral undulation (alpha 30 deg, omega 70 deg/s, delta 40 deg) in three ways,
//! alternating so that drift hits all alike, and prints the medians and minima of microseconds per
//! physics step:
//!
//! - `plain`: on the flat plane, no water (the plain step: ground contacts, no media);
//! - `water`: floating in worlds/pool.yaml (no contacts; water's wrench on every link every step);
//! - `hook`: water's part alone, `MediaState::states` + `wrenches` on the swimming robot's state
//!   (what the per-step hook adds to a step).
//!
//! The ratios printed are `water / plain` and `(plain + hook) / plain`, the cost of the same contacts
//! with water added on top.

use std::path::Path;
use std::time::Instant;

use snake_core::gait::{JointRoles, Swim, SwimParams, SwimPattern};
use snake_core::{Robot, RobotSpec, Simulation, WorldRef, WorldSpec};

fn robot(spec: &RobotSpec, world: &WorldSpec, z: f64) -> Robot {
    let start = snake_core::StartPose {
        z,
        ..spec.default_start()
    };
    Robot::in_world(spec, start, world).expect("robot")
}

fn run(robot: &mut Robot, swim: &Swim, steps: usize) -> f64 {
    let mut targets = vec![0.0; robot.joints()];
    let start = Instant::now();
    for _ in 0..steps {
        swim.targets_at(robot.time() + robot.dt(), &mut targets);
        robot.set_targets(&targets).expect("targets");
        robot.step().expect("step");
    }
    start.elapsed().as_secs_f64() / steps as f64 * 1e6
}

fn hook(robot: &Robot, steps: usize) -> f64 {
    let mut media = robot.media().expect("water").clone();
    let start = Instant::now();
    let mut sink = 0.0;
    for _ in 0..steps {
        let states =
            snake_core::media::MediaState::states(robot.world(), robot.body()).expect("states");
        let w = media.wrenches(&states, robot.world().gravity());
        sink += w[0].force.x;
    }
    std::hint::black_box(sink);
    start.elapsed().as_secs_f64() / steps as f64 * 1e6
}

fn stats(v: &mut [f64]) -> (f64, f64) {
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0])
}

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let steps = args.first().copied().unwrap_or(2400);
    let rounds = args.get(1).copied().unwrap_or(7);
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let spec = RobotSpec::load(&root.join("robots/mamba-10.yaml")).expect("mamba-10");
    let pool = WorldRef::load(&root.join("worlds/pool.yaml")).expect("pool");
    let plane = WorldSpec::default();
    let params = SwimParams {
        alpha: 30f64.to_radians(),
        omega: 70f64.to_radians(),
        delta: 40f64.to_radians(),
        offset: 0.0,
        ramp: 2.0,
    };
    let swim = Swim::new(
        SwimPattern::Lateral,
        params,
        &JointRoles::of_urdf(&spec.urdf),
    )
    .expect("gait");
    let (mut plain, mut water, mut hooks) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..rounds {
        // On the plane the body rests on the ground (its axis one radius up).
        plain.push(run(&mut robot(&spec, &plane, 0.045), &swim, steps));
        let mut swimmer = robot(&spec, pool.spec(), spec.default_start().z);
        water.push(run(&mut swimmer, &swim, steps));
        hooks.push(hook(&swimmer, steps));
    }
    let (p, p0) = stats(&mut plain);
    let (w, w0) = stats(&mut water);
    let (h, h0) = stats(&mut hooks);
    println!("mamba-10 (9 joints, 10 links), {steps} steps x {rounds} rounds, us per physics step (median, min)");
    println!("plain (flat plane, no water) {p:8.2} {p0:8.2}");
    println!("water (floating in the pool) {w:8.2} {w0:8.2}");
    println!("hook  (water's part alone)   {h:8.2} {h0:8.2}");
    println!(
        "ratios: water / plain {:.2}x; (plain + hook) / plain {:.3}x (median), {:.3}x (min)",
        w / p,
        (p + h) / p,
        (p0 + h0) / p0
    );
}
