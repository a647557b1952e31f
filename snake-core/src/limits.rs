//! Limits on what a configuration, a reset or a command may ask for. Each keeps a typo or a hostile
//! value from giving silently non-finite numbers, physics that no longer resolves the snake, or a call
//! that never returns; everything that checks a size, a range or a duration takes it from here.

/// Most joints a snake may have. Bullet's cost per physics step grows much faster than the joints
/// (the cube snake on this project's 2-core machine, release build: 64 joints ~3 ms a step, 128 ~40 ms,
/// 256 ~1.3 s, 512 ~13 s): at 128 the longest run ([`MAX_RUN_SECONDS`], 864,000 steps) takes about
/// 10 hours; at 512 it would take about 4 months.
pub const MAX_JOINTS: usize = 128;

/// Largest |x| or |y| of a start position or a goal, metres (10 km). Far inside what double-precision
/// physics resolves (at 10 km a position is exact to ~2e-12 m, against cubes of 0.25 m; at 1e18 m the
/// contacts no longer work and the snake leaves the plane), and where the float32 observation still
/// resolves ~1 mm.
pub const MAX_POSITION: f64 = 1.0e4;

/// Highest start height of the base, metres (the snake drops onto the plane from there).
pub const MAX_START_HEIGHT: f64 = 100.0;

/// Largest |yaw| of a start pose, radians.
pub const MAX_YAW: f64 = 1.0e3;

/// Largest |weight| of a reward term and of the success reward: with distances below ~3e4 m, episodes
/// below [`MAX_EPISODE_STEPS`] and bounded torques, every reward and return stays finite.
pub const MAX_REWARD_WEIGHT: f64 = 1.0e6;

/// Largest `action_scale` (radians of joint target per unit of action).
pub const MAX_ACTION_SCALE: f64 = 100.0;

/// Most env steps of an episode.
pub const MAX_EPISODE_STEPS: u64 = 10_000_000;

/// Most physics steps per env step (1 s of simulated time at 240 Hz): one `step()` call stays short
/// enough to be interrupted between calls.
pub const MAX_PHYSICS_STEPS_PER_ENV_STEP: u32 = 240;

/// Most environments of one batched env.
pub const MAX_ENVS: usize = 1024;

/// Longest simulated duration of one command-line run, seconds (one hour: 864,000 physics steps).
pub const MAX_RUN_SECONDS: f64 = 3600.0;

/// Longest simulated duration of one Rerun recording (all its episodes together), seconds: a viewer
/// holds the whole recording in memory, and a file takes about 11 MB per simulated minute of a
/// 10-joint snake logged at every 1/240 s physics step (more in the viewer's memory).
pub const MAX_RECORDING_SECONDS: f64 = 600.0;

/// Most values in a model's observation or action (a snake of `MAX_JOINTS` joints has about 1000): a
/// model file that declares more is refused before anything is allocated for it.
pub const MAX_SPACE_SIZE: usize = 1 << 16;

/// Most frames of a replay animation (`snakesim replay --out x.gif`): frames are held in memory until
/// the file is written.
pub const MAX_REPLAY_FRAMES: u64 = 600;

/// Frame rates of a replay animation, frames per second.
pub const REPLAY_FPS: (f64, f64) = (0.1, 50.0);

/// Most moments in a replay figure (`--panels`).
pub const MAX_REPLAY_PANELS: u64 = 24;

/// Most episodes in one Rerun recording of an agent (`snakesim replay --episodes`).
pub const MAX_RECORDING_EPISODES: u64 = 100;

/// Most links of a URDF robot (its root included): as many bodies as the built-in snake may have.
pub const MAX_ROBOT_LINKS: usize = MAX_JOINTS + 1;

/// Most `<collision>` shapes of one URDF link.
pub const MAX_SHAPES_PER_LINK: usize = 64;

/// Largest URDF or robot file read, bytes (16 MiB).
pub const MAX_URDF_BYTES: u64 = 16 << 20;

/// Most rows of a joint-targets CSV (`snake-cli run --targets`): an hour of 1/240 s steps.
pub const MAX_TARGET_ROWS: usize = 864_000;

/// Range of a library gait's wave amplitudes, radians: up to a right angle, the yaw-pitch robot's joint
/// range (a larger target only presses the joint against its limit).
pub const GAIT_AMPLITUDE: (f64, f64) = (0.0, std::f64::consts::FRAC_PI_2);

/// Range of a library gait's spatial frequency, radians per module: beyond pi a wave samples its own
/// alias (a wave of -2 pi + s per module is the same joint angles as s).
pub const GAIT_SPATIAL: (f64, f64) = (-std::f64::consts::PI, std::f64::consts::PI);

/// Range of a library gait's period, seconds: from 12 physics steps per cycle (at 1/240 s) to ten
/// minutes.
pub const GAIT_PERIOD: (f64, f64) = (0.05, 600.0);

/// Range of a library gait's phase between its pitch and yaw waves, radians (one turn each way).
pub const GAIT_PHASE: (f64, f64) = (-std::f64::consts::TAU, std::f64::consts::TAU);

/// Range of a library gait's pitch wave cycles per gait cycle.
pub const GAIT_PITCH_RATE: (f64, f64) = (0.0, 8.0);

/// Range of a library gait's constant yaw or pitch offset (steering included), radians.
pub const GAIT_OFFSET: (f64, f64) = (-std::f64::consts::FRAC_PI_2, std::f64::consts::FRAC_PI_2);

/// Range of the sine wave's (snake.py's) wave length and segment length, metres, and of its
/// start-up ramp, segments.
pub const GAIT_LENGTH: (f64, f64) = (0.0, 1.0e3);

/// Range of a library gait's start-up ramp, seconds.
pub const GAIT_RAMP: (f64, f64) = (0.0, 600.0);

/// Largest heightfield CSV or world file read, bytes (64 MiB: a full [`MAX_HEIGHTFIELD_SAMPLES`] grid
/// written with ~20 characters a value).
pub const MAX_HEIGHTFIELD_BYTES: u64 = 64 << 20;

/// Most samples of a heightfield along x or along y.
pub const MAX_HEIGHTFIELD_SIDE: usize = 4096;

/// Most samples of a heightfield in all (2^21: ~17 MB of doubles in Bullet, plus its accelerator).
pub const MAX_HEIGHTFIELD_SAMPLES: usize = 1 << 21;

/// Most noise values behind one generated rough ground (its lattice: one value a `wavelength`, over
/// the grid's extent, drawn before any height): a wavelength far below the spacing would otherwise ask
/// for gigabytes (1e-9 m asked for more than memory holds). 64 MiB of doubles.
pub const MAX_NOISE_LATTICE: usize = 4 * MAX_HEIGHTFIELD_SAMPLES;

/// Largest |height| of a heightfield sample, and |z| of an obstacle, metres.
pub const MAX_TERRAIN_HEIGHT: f64 = 1.0e3;

/// Most obstacles of one world, pegs included: each is a static body in Bullet's broadphase.
pub const MAX_OBSTACLES: usize = 10_000;

/// Most craters a rough ground may have (`terrain.rough.craters.count`).
pub const MAX_CRATERS: usize = 16;

/// Most ridges a rough ground may have (`terrain.rough.ridges.count`).
pub const MAX_RIDGES: usize = 16;

/// Largest size of an obstacle (a half extent, radius or height), a grid spacing or a scale, metres.
pub const MAX_OBSTACLE_SIZE: f64 = 1.0e3;

/// Largest |tilt| of a slope ground, degrees (steeper is a wall, better made of obstacles).
pub const MAX_SLOPE_DEGREES: f64 = 80.0;

/// Largest lateral friction coefficient of the ground or an obstacle.
pub const MAX_WORLD_FRICTION: f64 = 1.0e3;

/// Largest skin friction coefficient (forward, backward, transverse). Bullet clamps every combined lateral
/// friction (the product of two objects' coefficients) at 10, so against a ground of friction 1 a larger
/// coefficient would act as 10 anyway (on the default plane, friction 0.5, a coefficient of 10 acts as 5).
pub const MAX_SKIN_FRICTION: f64 = 10.0;

/// Largest angular frequency `omega` of the swimming gaits (`gait::swim`), rad/s: a cycle in a twentieth
/// of a second, the library's shortest period (`GAIT_PERIOD`'s low end; written as `40 pi` so that the
/// Python side reads the value from this source; a test holds it to `2 pi / GAIT_PERIOD.0`).
pub const MAX_SWIM_OMEGA: f64 = 40.0 * std::f64::consts::PI;

/// Largest density of a fluid medium, kg/m^3 (mercury is 13,534; anything denser is a typo).
pub const MAX_FLUID_DENSITY: f64 = 2.0e4;

/// Largest speed of a water current along any axis, m/s (the fastest tidal races run at about 7).
pub const MAX_CURRENT: f64 = 100.0;

/// Largest hydrodynamic coefficient (C_f, C_D, C_A, C_M, the linear weight); published values for
/// cylinders are 0.01 to about 2.
pub const MAX_HYDRO_COEFFICIENT: f64 = 1.0e3;

/// Largest maximum velocity of a robot's motors (a robot file's `max_velocity`), rad/s (m/s for a
/// prismatic joint). The limit clamps the motor's target velocity, so it matters only below the speeds
/// a joint reaches: at 1e4 rad/s a joint would turn 42 rad (almost 7 turns) in one 1/240 s step, ten
/// times an ungeared electric motor's no-load speed (10,000 rpm is ~1e3 rad/s; hobby and snake-robot
/// servos turn at ~5-10 rad/s), so a larger value is a typo rather than a servo.
pub const MAX_MOTOR_VELOCITY: f64 = 1.0e4;

/// Largest motor gain (`motors.kp`, `motors.kd`) or friction coefficient of a robot file's
/// (anisotropic, skin) a calibration fit may set (`snakesim calibrate`, [`crate::run_targets`]): far
/// beyond any servo's or surface's, small enough that the physics stays finite.
pub const MAX_FIT_VALUE: f64 = 1.0e6;

/// Most simulations of one calibration (`snakesim calibrate --max-evals`): 100,000 runs of an 8 s
/// log take about a day on one core, far beyond any fit that converges.
pub const MAX_CALIBRATION_EVALS: u64 = 100_000;

/// Most processes that simulate a calibration's candidates at once (`snakesim calibrate --workers`).
pub const MAX_CALIBRATION_WORKERS: u64 = 256;

/// Most env steps an action may reach the motors late (`randomize.latency_steps`): 32 env steps are
/// 0.13 s at the default 240 Hz, far beyond a real servo bus's few milliseconds; the delay line holds
/// this many actions per env.
pub const MAX_LATENCY_STEPS: u32 = 32;

/// Largest standard deviation of the observation noise (`randomize.obs_noise`), in the observation's
/// own units (metres, radians, rad/s): larger noise drowns every value the observation holds.
pub const MAX_OBS_NOISE: f64 = 10.0;

/// Largest factor of a randomized scale (`randomize.mass_scale`, `effort_scale`, `kp_scale`,
/// `kd_scale`, `skin_friction_scale`). A hundredfold mass or motor is another robot, not a perturbed
/// one.
pub const MAX_PHYSICS_SCALE: f64 = 100.0;

/// Smallest factor of a randomized scale, for the same reason as [`MAX_PHYSICS_SCALE`]: a hundredth
/// of the mass or the motor is another robot. Every value of `[MIN_PHYSICS_SCALE, MAX_PHYSICS_SCALE]`
/// builds a finite simulation of every shipped body (snake-core/tests/randomize.rs runs each scale's
/// ends, alone and together); a scale of 1e-300 made the first physics step non-finite, and a range
/// the validator accepts must never fail at a reset.
pub const MIN_PHYSICS_SCALE: f64 = 0.01;

/// Largest model file read (a snakesim `.safetensors`, a Stable-Baselines3 `.zip`, or one member of
/// such a zip once uncompressed), bytes (256 MiB: a network of the largest configurable width holds
/// far less).
pub const MAX_MODEL_BYTES: u64 = 256 << 20;

/// Largest small text or metadata file read (a run's config.yaml, a model's JSON, a VecNormalize
/// statistics file, a sweep manifest), bytes (16 MiB).
pub const MAX_CONFIG_BYTES: u64 = 16 << 20;

/// Largest CSV read back for a plot, a replay or a calibration (a trajectory, a training log), bytes
/// (1 GiB).
pub const MAX_CSV_BYTES: u64 = 1 << 30;

/// Longest line of a targets or log CSV, characters (a row of 137 numbers in shortest form is ~3 kB).
pub const MAX_CSV_LINE_CHARS: usize = 1 << 20;

/// Longest error message shown, characters (defined beside the errors, which every module uses).
pub use crate::error::MAX_ERROR_CHARS;

/// Deepest nesting of a YAML or XML file we read (flow brackets, block indentation levels or XML
/// elements): far beyond any real robot, world or run file, and shallow enough that every file within
/// the size caps parses in well under a second.
pub const MAX_NESTING: usize = 64;

/// Most attributes of one XML element (a URDF tag has at most a handful).
pub const MAX_XML_ATTRIBUTES: usize = 64;

/// Most media (granular or water) one world file may list.
pub const MAX_MEDIA: usize = 16;

/// Most surface elements a medium cuts one link into ([`crate::media::geometry`]): a 10-joint snake
/// at the most costs 45,000 element evaluations a step.
pub const MAX_MEDIUM_ELEMENTS: usize = 4096;

/// Range of a medium's surface element size, metres (`(low, high]`): 0.1 mm to 1 m.
pub const MEDIUM_ELEMENT: (f64, f64) = (1.0e-4, 1.0);

/// Largest strength `zeta` of a granular medium, N/m^3 (Li et al. 2013's media lie near 1e5 to 1e6;
/// 1e9 is a rock, not a granular medium).
pub const MAX_GRANULAR_ZETA: f64 = 1.0e9;

/// Largest body-grain friction coefficient of a granular medium.
pub const MAX_GRANULAR_FRICTION: f64 = 10.0;

/// Range of a granular medium's elastic displacement at yield, metres (`(low, high]`).
pub const GRANULAR_ELASTIC: (f64, f64) = (1.0e-6, 0.1);

/// Largest magnitude of a coefficient of a granular coefficient table (Li et al.'s lie within 0.4).
pub const MAX_GRANULAR_COEFFICIENT: f64 = 100.0;

/// Checks a joint count against `[1, MAX_JOINTS]`, the one check of it in Rust (snake files, env
/// keywords, run configurations and every command go through it); the error is about the key
/// `joints`. Below 1 it says `must be in [1, 128], got 0`, above `must be at most 128, got N` (the
/// wordings the CLI's and Python's tests name).
pub fn check_joints(joints: usize) -> crate::Result<()> {
    if joints < 1 {
        Err(crate::error::invalid_at(
            "joints",
            format!("must be in [1, {MAX_JOINTS}], got {joints}"),
        ))
    } else if joints > MAX_JOINTS {
        Err(crate::error::invalid_at(
            "joints",
            format!("must be at most {MAX_JOINTS}, got {joints}"),
        ))
    } else {
        Ok(())
    }
}

/// Checks that `value` lies in `[low, high]` (and is finite); the error names `what`. With the
/// other checks below, the one range check of the Rust crates: every range a value must lie in is
/// checked, and worded, here.
pub fn check_range(what: &str, value: f64, low: f64, high: f64) -> crate::Result<()> {
    range_problem(value, low, high, false).map_or(Ok(()), |detail| {
        Err(crate::error::invalid(format!("{what} {detail}")))
    })
}

/// [`check_range`] for the configuration value at the key path `key`: the error carries the path
/// ([`crate::Invalid::key`]) apart from what is wrong with it.
pub fn check_key_range(key: &str, value: f64, low: f64, high: f64) -> crate::Result<()> {
    range_problem(value, low, high, false)
        .map_or(Ok(()), |detail| Err(crate::error::invalid_at(key, detail)))
}

/// [`check_range`] over `(low, high]`: `low` itself refused (a size, a scale, a gain that must be
/// positive).
pub fn check_range_above(what: &str, value: f64, low: f64, high: f64) -> crate::Result<()> {
    range_problem(value, low, high, true).map_or(Ok(()), |detail| {
        Err(crate::error::invalid(format!("{what} {detail}")))
    })
}

/// [`check_key_range`] over `(low, high]`.
pub fn check_key_range_above(key: &str, value: f64, low: f64, high: f64) -> crate::Result<()> {
    range_problem(value, low, high, true)
        .map_or(Ok(()), |detail| Err(crate::error::invalid_at(key, detail)))
}

/// Checks a range `[low, high]` given for the value at the key path `key` (a randomized scale drawn
/// from it): both ends finite, `low <= high`, and both within `[bound_low, bound_high]`.
pub fn check_key_interval(
    key: &str,
    [low, high]: [f64; 2],
    bound_low: f64,
    bound_high: f64,
) -> crate::Result<()> {
    let shown = format!("[{}, {}]", short(low), short(high));
    let detail = if !(low.is_finite() && high.is_finite()) {
        format!("must be finite, got {shown}")
    } else if low > high {
        format!("must have low <= high, got {shown}")
    } else if low < bound_low || high > bound_high {
        format!(
            "must lie within {} <= low <= high <= {}, got {shown}",
            short(bound_low),
            short(bound_high)
        )
    } else {
        return Ok(());
    };
    Err(crate::error::invalid_at(key, detail))
}

/// What is wrong with `value` against `[low, high]` (`(low, high]` with `low_open`), if anything.
fn range_problem(value: f64, low: f64, high: f64, low_open: bool) -> Option<String> {
    let above_low = if low_open { value > low } else { value >= low };
    if value.is_finite() && above_low && value <= high {
        return None;
    }
    Some(format!(
        "must be in {}{}, {}], got {}",
        if low_open { '(' } else { '[' },
        short(low),
        short(high),
        short(value)
    ))
}

/// [`check_position`] for the configuration value at the key path `key`.
pub fn check_key_position(key: &str, x: f64, y: f64) -> crate::Result<()> {
    position_problem(x, y).map_or(Ok(()), |detail| Err(crate::error::invalid_at(key, detail)))
}

/// Checks a planar position (a goal, a start's x and y) against [`MAX_POSITION`].
pub fn check_position(what: &str, x: f64, y: f64) -> crate::Result<()> {
    position_problem(x, y).map_or(Ok(()), |detail| {
        Err(crate::error::invalid(format!("{what} {detail}")))
    })
}

/// What is wrong with a planar position, if anything.
fn position_problem(x: f64, y: f64) -> Option<String> {
    if !(x.is_finite() && y.is_finite()) {
        Some(format!("must be finite, got ({x:?}, {y:?})"))
    } else if x.abs() <= MAX_POSITION && y.abs() <= MAX_POSITION {
        None
    } else {
        Some(format!(
            "must have |x| and |y| at most {MAX_POSITION} m, got ({x:?}, {y:?})"
        ))
    }
}

/// A number for a message, short whatever its size (defined beside the errors, which write every
/// long number short).
pub use crate::error::short;

/// One limit's value in [`ALL`]: a count or size, or a real number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LimitValue {
    /// A count, size or duration in steps.
    Int(u64),
    /// A real bound (metres, seconds, a scale, ...).
    Float(f64),
}

/// Every limit of this module by name, the one table readers iterate (the Python side's `LIMITS`
/// is built from it): `MAX_X` is `x`, a `MIN_X` and `MAX_X` pair or a `(low, high)` range is `x_min`
/// and `x_max`. A test checks that every constant of this file is in it.
pub const ALL: &[(&str, LimitValue)] = {
    use LimitValue::{Float, Int};
    &[
        ("joints", Int(MAX_JOINTS as u64)),
        ("position", Float(MAX_POSITION)),
        ("start_height", Float(MAX_START_HEIGHT)),
        ("yaw", Float(MAX_YAW)),
        ("reward_weight", Float(MAX_REWARD_WEIGHT)),
        ("action_scale", Float(MAX_ACTION_SCALE)),
        ("episode_steps", Int(MAX_EPISODE_STEPS)),
        (
            "physics_steps_per_env_step",
            Int(MAX_PHYSICS_STEPS_PER_ENV_STEP as u64),
        ),
        ("envs", Int(MAX_ENVS as u64)),
        ("run_seconds", Float(MAX_RUN_SECONDS)),
        ("recording_seconds", Float(MAX_RECORDING_SECONDS)),
        ("space_size", Int(MAX_SPACE_SIZE as u64)),
        ("replay_frames", Int(MAX_REPLAY_FRAMES)),
        ("replay_fps_min", Float(REPLAY_FPS.0)),
        ("replay_fps_max", Float(REPLAY_FPS.1)),
        ("replay_panels", Int(MAX_REPLAY_PANELS)),
        ("recording_episodes", Int(MAX_RECORDING_EPISODES)),
        ("robot_links", Int(MAX_ROBOT_LINKS as u64)),
        ("shapes_per_link", Int(MAX_SHAPES_PER_LINK as u64)),
        ("urdf_bytes", Int(MAX_URDF_BYTES)),
        ("target_rows", Int(MAX_TARGET_ROWS as u64)),
        ("gait_amplitude_min", Float(GAIT_AMPLITUDE.0)),
        ("gait_amplitude_max", Float(GAIT_AMPLITUDE.1)),
        ("gait_spatial_min", Float(GAIT_SPATIAL.0)),
        ("gait_spatial_max", Float(GAIT_SPATIAL.1)),
        ("gait_period_min", Float(GAIT_PERIOD.0)),
        ("gait_period_max", Float(GAIT_PERIOD.1)),
        ("gait_phase_min", Float(GAIT_PHASE.0)),
        ("gait_phase_max", Float(GAIT_PHASE.1)),
        ("gait_pitch_rate_min", Float(GAIT_PITCH_RATE.0)),
        ("gait_pitch_rate_max", Float(GAIT_PITCH_RATE.1)),
        ("gait_offset_min", Float(GAIT_OFFSET.0)),
        ("gait_offset_max", Float(GAIT_OFFSET.1)),
        ("gait_length_min", Float(GAIT_LENGTH.0)),
        ("gait_length_max", Float(GAIT_LENGTH.1)),
        ("gait_ramp_min", Float(GAIT_RAMP.0)),
        ("gait_ramp_max", Float(GAIT_RAMP.1)),
        ("heightfield_bytes", Int(MAX_HEIGHTFIELD_BYTES)),
        ("heightfield_side", Int(MAX_HEIGHTFIELD_SIDE as u64)),
        ("heightfield_samples", Int(MAX_HEIGHTFIELD_SAMPLES as u64)),
        ("noise_lattice", Int(MAX_NOISE_LATTICE as u64)),
        ("terrain_height", Float(MAX_TERRAIN_HEIGHT)),
        ("obstacles", Int(MAX_OBSTACLES as u64)),
        ("craters", Int(MAX_CRATERS as u64)),
        ("ridges", Int(MAX_RIDGES as u64)),
        ("obstacle_size", Float(MAX_OBSTACLE_SIZE)),
        ("slope_degrees", Float(MAX_SLOPE_DEGREES)),
        ("world_friction", Float(MAX_WORLD_FRICTION)),
        ("skin_friction", Float(MAX_SKIN_FRICTION)),
        ("swim_omega", Float(MAX_SWIM_OMEGA)),
        ("fluid_density", Float(MAX_FLUID_DENSITY)),
        ("current", Float(MAX_CURRENT)),
        ("hydro_coefficient", Float(MAX_HYDRO_COEFFICIENT)),
        ("motor_velocity", Float(MAX_MOTOR_VELOCITY)),
        ("fit_value", Float(MAX_FIT_VALUE)),
        ("calibration_evals", Int(MAX_CALIBRATION_EVALS)),
        ("calibration_workers", Int(MAX_CALIBRATION_WORKERS)),
        ("latency_steps", Int(MAX_LATENCY_STEPS as u64)),
        ("obs_noise", Float(MAX_OBS_NOISE)),
        ("physics_scale_max", Float(MAX_PHYSICS_SCALE)),
        ("physics_scale_min", Float(MIN_PHYSICS_SCALE)),
        ("model_bytes", Int(MAX_MODEL_BYTES)),
        ("config_bytes", Int(MAX_CONFIG_BYTES)),
        ("csv_bytes", Int(MAX_CSV_BYTES)),
        ("csv_line_chars", Int(MAX_CSV_LINE_CHARS as u64)),
        ("nesting", Int(MAX_NESTING as u64)),
        ("xml_attributes", Int(MAX_XML_ATTRIBUTES as u64)),
        ("media", Int(MAX_MEDIA as u64)),
        ("medium_elements", Int(MAX_MEDIUM_ELEMENTS as u64)),
        ("medium_element_min", Float(MEDIUM_ELEMENT.0)),
        ("medium_element_max", Float(MEDIUM_ELEMENT.1)),
        ("granular_zeta", Float(MAX_GRANULAR_ZETA)),
        ("granular_friction", Float(MAX_GRANULAR_FRICTION)),
        ("granular_elastic_min", Float(GRANULAR_ELASTIC.0)),
        ("granular_elastic_max", Float(GRANULAR_ELASTIC.1)),
        ("granular_coefficient", Float(MAX_GRANULAR_COEFFICIENT)),
        ("error_chars", Int(crate::error::MAX_ERROR_CHARS as u64)),
    ]
};

#[cfg(test)]
mod table_tests {
    /// Every `pub const` of this file (but the table) is named in [`super::ALL`], and no name twice.
    #[test]
    fn every_limit_is_in_the_table() {
        let source = include_str!("limits.rs");
        let table = source.split("pub const ALL").nth(1).expect("the table");
        for line in source.lines() {
            let Some(rest) = line.strip_prefix("pub const ") else {
                continue;
            };
            let name = rest.split(':').next().unwrap_or_default();
            if name != "ALL" {
                let named = [")", " as", "."]
                    .iter()
                    .any(|end| table.contains(&format!("({name}{end}")));
                assert!(named, "{name} is not in limits::ALL");
            }
        }
        let mut names: Vec<&str> = super::ALL.iter().map(|(n, _)| *n).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), super::ALL.len(), "a name twice in limits::ALL");
    }

    /// The swimming gaits' fastest cycle is the library's shortest period.
    #[test]
    fn the_swim_omega_limit_is_the_shortest_period() {
        let period = std::f64::consts::TAU / super::MAX_SWIM_OMEGA;
        assert!((period - super::GAIT_PERIOD.0).abs() < 1e-15, "{period}");
    }
}
