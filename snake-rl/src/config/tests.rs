//! The run configuration's tests.

use super::*;
use crate::nn::Arch;

fn error(yaml: &str) -> String {
    RunConfig::from_yaml(yaml).unwrap_err().to_string()
}

#[test]
fn defaults_are_table_1() {
    let c = RunConfig::default();
    let p = &c.ppo;
    assert_eq!(p.learning_rate, Schedule::Constant(3e-4));
    assert_eq!((p.n_steps, p.batch_size, p.n_epochs), (4096, 64, 10));
    assert_eq!((p.gamma, p.gae_lambda), (0.99, 0.95));
    assert_eq!(p.clip_range, Schedule::Constant(0.2));
    assert_eq!((p.ent_coef, p.vf_coef, p.max_grad_norm), (0.0, 0.5, 0.5));
    assert!(c.validate().is_ok());
}

#[test]
fn yaml_round_trips() {
    let c = RunConfig::from_yaml(
        "joints: 10\narch: large\npreset: snakebot-gym\ntimesteps: 2e7\nppo: {learning_rate: lin_1e-3, \
         target_kl: 0.02}\nenv: {goal: [3, -4], reward: {progress_weight: 2}}",
    )
    .unwrap();
    assert_eq!(c.timesteps, 20_000_000);
    assert_eq!(c.ppo.learning_rate, Schedule::Linear(1e-3));
    let again = RunConfig::from_yaml(&c.to_yaml()).unwrap();
    assert_eq!(again, c);
    assert_eq!(c.env_config().unwrap().goal, (3.0, -4.0));
}

#[test]
fn arch_takes_widths_as_sb3_net_arch() {
    use crate::nn::NetArch;
    let c = RunConfig::from_yaml("arch: {pi: [256, 256], vf: [128]}\nlog_std_init: -0.5").unwrap();
    let net = NetArch {
        shared: vec![],
        pi: vec![256, 256],
        vf: vec![128],
    };
    assert_eq!(c.arch, Arch::Custom(net));
    assert_eq!(c.log_std_init, -0.5);
    assert_eq!(c.arch.to_string(), "pi [256, 256], vf [128]");
    assert_eq!(RunConfig::from_yaml(&c.to_yaml()).unwrap(), c);
    assert_eq!(c.arch.to_meta().parse::<Arch>().unwrap(), c.arch);
    // The paper's widths are the paper's networks, by name.
    let large = "arch: {shared: [128, 128], pi: [64, 64], vf: [64, 64]}";
    assert_eq!(RunConfig::from_yaml(large).unwrap().arch, Arch::Large);
    assert_eq!(RunConfig::from_yaml("arch: {}").unwrap().arch, Arch::Small);
    assert_eq!(Arch::Large.to_meta(), "large");
    // Widths of some parts over a named network change those parts only.
    let layers = [
        serde_json::json!({"arch": "large"}),
        serde_json::json!({"arch": {"pi": [256]}}),
    ];
    let c = RunConfig::from_layers(&layers).unwrap();
    assert_eq!(
        c.arch.net(),
        NetArch {
            shared: vec![128, 128],
            pi: vec![256],
            vf: vec![64, 64]
        }
    );
}

#[test]
fn errors_name_the_key_path() {
    assert!(error("bogus: 1").starts_with("bogus: unknown field `bogus`, expected one of"));
    assert!(error("ppo: {n_stepz: 1}").starts_with("ppo.n_stepz: unknown field `n_stepz`"));
    assert!(error("ppo: {learning_rate: 0}").starts_with("ppo.learning_rate: must be positive"));
    assert!(error("ppo: {learning_rate: abc}").starts_with("ppo.learning_rate: expected a number"));
    assert!(error("ppo: {n_epochs: 0}").starts_with("ppo.n_epochs: must be in [1,"));
    assert!(error("ppo: {n_steps: 2.5}").starts_with(
        "ppo.n_steps: invalid type: floating point `2.5`, expected a non-negative integer"
    ));
    assert!(
        error("ppo: {batch_size: 100000}").starts_with("ppo.batch_size: must be in [2, n_steps")
    );
    assert!(error("n_envs: -1")
        .starts_with("n_envs: invalid value: integer `-1`, expected a non-negative integer"));
    assert!(error("seed: 4294967296").starts_with("seed: must be in [0, 4294967295]"));
    assert!(error("arch: huge").starts_with("arch: unknown variant `huge`"));
    assert!(error("arch: {pi: []}").starts_with("arch.pi: must have 1 to 8 layers, got 0"));
    assert!(error("arch: {shared: [64, 0]}")
        .starts_with("arch.shared: layer widths must be in [1, 1024], got 0"));
    assert!(error("arch: {pi: [64, 1025]}")
        .starts_with("arch.pi: layer widths must be in [1, 1024], got 1025"));
    assert!(error("arch: {vf: [1, 1, 1, 1, 1, 1, 1, 1, 1]}")
        .starts_with("arch.vf: must have 1 to 8 layers, got 9"));
    assert!(error("arch: {heads: [64]}").starts_with("arch.heads: unknown field `heads`"));
    assert!(error("arch: {pi: [-1]}").starts_with("arch.pi[0]: invalid value"));
    assert!(error("arch: 3").starts_with("arch: invalid type: integer `3`"));
    assert!(error("log_std_init: 3").starts_with("log_std_init: must be in [-20, 2], got 3"));
    assert!(error("env: {reward: {progress_weight: a}}")
        .starts_with("env.reward.progress_weight: invalid type"));
    assert!(error("env: {goal: [true, false]}").starts_with("env.goal[0]: invalid type: boolean"));
    assert!(error("env: {max_episode_steps: 2.9}")
        .starts_with("env.max_episode_steps: invalid type: floating point"));
    assert!(error("env: {joints: 3}").starts_with("env.joints: set joints at the top level"));
    assert!(
        error("env: {snake: {link_mass: -1}}").starts_with("env.snake.link_mass: must be positive")
    );
    assert!(error("env: {goal_radius: -1}").starts_with("env.goal_radius: must be in [0, 10000]"));
    assert!(error("- 1").starts_with("a configuration must be a mapping"));
    assert!(error("ppo: [1").starts_with("not valid YAML (line 2, column 1): did not find"));
}

#[test]
fn energy_ramp_anneals_the_weight_in_and_is_checked() {
    let c = RunConfig::from_yaml(
        "energy_ramp: [100, 300]\nenv: {task: goal, reward: {energy_weight: 0.04}}",
    )
    .unwrap();
    let w = c.env_config().unwrap().reward.energy_weight;
    assert_eq!(w, 0.04);
    assert_eq!(c.energy_weight_at(0, w), 0.0);
    assert_eq!(c.energy_weight_at(99, w), 0.0);
    assert_eq!(c.energy_weight_at(100, w), 0.0);
    assert_eq!(c.energy_weight_at(200, w), 0.02);
    assert_eq!(c.energy_weight_at(300, w), 0.04);
    assert_eq!(c.energy_weight_at(10_000, w), 0.04);
    let step =
        RunConfig::from_yaml("energy_ramp: [50, 50]\nenv: {reward: {energy_weight: 0.5}}").unwrap();
    assert_eq!(
        (
            step.energy_weight_at(49, 0.5),
            step.energy_weight_at(50, 0.5)
        ),
        (0.0, 0.5)
    );
    assert_eq!(RunConfig::default().energy_weight_at(0, 0.3), 0.3);
    assert!(
        error("energy_ramp: [300, 100]\nenv: {reward: {energy_weight: 1}}")
            .starts_with("energy_ramp: expected [from, to] timesteps with from <= to")
    );
    assert!(
        error("energy_ramp: [0, 100]").starts_with("energy_ramp: env.reward.energy_weight is 0")
    );
    assert!(
        error("trainer: sb3\nenergy_ramp: [0, 1]\nenv: {reward: {energy_weight: 1}}")
            .starts_with("energy_ramp: only the native trainer")
    );
    assert!(error("energy_ramp: [-1, 2]").starts_with("energy_ramp"));
    assert!(IDENTITY_KEYS.contains(&"energy_ramp"));
}

#[test]
fn overrides_nest_and_merge() {
    let o = parse_overrides(&[
        "ppo.learning_rate=3e-4",
        "env.reward.progress_weight=1",
        "joints=7",
    ])
    .unwrap();
    let base = parse_yaml("env: {reward: {smoothness_weight: 0.5}}").unwrap();
    let c = RunConfig::from_layers(&[base, o]).unwrap();
    assert_eq!(c.ppo.learning_rate, Schedule::Constant(3e-4));
    assert_eq!(c.joints, 7);
    let r = c.env_config().unwrap().reward;
    assert_eq!((r.progress_weight, r.smoothness_weight), (1.0, 0.5));
    assert!(parse_overrides(&["ppo.n_steps"]).is_err());
    assert!(parse_overrides(&["ppo..n=1"]).is_err());
}

#[test]
fn env_keywords() {
    let kw = |text: &str| -> Map<String, Value> { serde_json::from_str(text).unwrap() };
    let c = env_from_keywords(&kw(
        r#"{"joints": 7, "preset": "snakebot-gym", "goal": [1, 2]}"#,
    ))
    .unwrap();
    assert_eq!(
        (c.joints(), c.snake.link_mass, c.goal),
        (7, 1.0, (1.0, 2.0))
    );
    assert_eq!(
        env_from_keywords(&Map::new()).unwrap(),
        EnvConfig::default()
    );
    let e = |text: &str| env_from_keywords(&kw(text)).unwrap_err().0;
    assert!(e(r#"{"joints": 2.5}"#).starts_with("joints: invalid type: floating point `2.5`"));
    assert!(e(r#"{"joints": 0}"#).starts_with("joints: must be in [1, 128], got 0"));
    assert!(e(r#"{"joints": true}"#).starts_with("joints: invalid type: boolean"));
    assert!(e(r#"{"preset": "x"}"#).starts_with("preset: unknown variant `x`"));
    assert!(e(r#"{"action_scale": "2"}"#).starts_with("action_scale: invalid type: string"));
    let d = env_keyword_defaults(Task::Paper);
    assert_eq!(d["joints"], 5);
    assert_eq!(d["max_episode_steps"], 5000);
    assert!(!d.contains_key("snake"));
    let g = env_keyword_defaults(Task::Goal);
    assert_eq!(g["max_episode_steps"], 600);
    assert_eq!(g["action"]["mode"], "gait");
    // A goal-task table over the task's defaults; null switches the goal distribution off.
    let c = env_from_keywords(&kw(
        r#"{"task": "goal", "joints": 10, "goal_distribution": {"distance": [2, 3]}}"#,
    ))
    .unwrap();
    let goals = c.goal_distribution.unwrap();
    assert_eq!(goals.distance, [2.0, 3.0]);
    assert_eq!(goals.bearing, [-std::f64::consts::PI, std::f64::consts::PI]);
    assert_eq!(
        (c.joints(), c.action_dim(), c.max_episode_steps),
        (10, 3, 600)
    );
    let c = env_from_keywords(&kw(r#"{"task": "goal", "goal_distribution": null}"#)).unwrap();
    assert_eq!(c.goal_distribution, None);
    assert_eq!(
        env_from_keywords(&kw("{}")).unwrap(),
        EnvConfig::default(),
        "the paper's env without keywords"
    );
    assert!(e(r#"{"task": "run"}"#).starts_with("task: unknown variant `run`"));
}

#[test]
fn identity_keys_are_found() {
    let a = RunConfig::default();
    let mut b = a.clone();
    b.timesteps = 5;
    assert_eq!(a.identity_difference(&b), None);
    b.ppo.gamma = 0.9;
    assert_eq!(a.identity_difference(&b).unwrap().0, "ppo");
}
