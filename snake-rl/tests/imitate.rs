//! Initialisation by imitation (`init`): the fit, determinism, resume through it, bad input.

use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};
use snake_core::controllers::{Imitable, JointsSine};
use snake_core::imitation::Demonstrator;
use snake_core::{EnvConfig, StepBuffers, VecSnakeEnv};
use snake_rl::config::{InitConfig, RunConfig};
use snake_rl::imitate;
use snake_rl::model;
use snake_rl::nn::{init_params, ActorCritic};
use snake_rl::normalize::Normalizer;
use snake_rl::trainer::{self, InitProgress, Observer, Outcome, Session, Silent};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("snake-rl-init-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A run of about a second with an init of 512 controller steps.
fn tiny(extra: Value) -> RunConfig {
    let mut layer = json!({
        "timesteps": 1024, "n_envs": 2, "eval_freq": 512, "eval_episodes": 2, "checkpoint_freq": 512,
        "threads": 2, "ppo": {"n_steps": 256, "batch_size": 64, "n_epochs": 2},
        "env": {"max_episode_steps": 100},
        "init": {"imitate": "steered_sine", "steps": 512, "epochs": 3, "batch_size": 64, "critic": true},
    });
    snake_rl::config::merge(&mut layer, &extra);
    RunConfig::from_layers(&[layer]).expect("a valid configuration")
}

fn session(config: RunConfig, dir: &Path, resume: bool) -> Session {
    Session {
        config,
        run_dir: dir.to_path_buf(),
        resume,
        versions: Map::new(),
    }
}

fn params(dir: &Path) -> Vec<u32> {
    let p = model::load_policy(&dir.join("model.safetensors")).unwrap();
    p.params.iter().map(|x| x.to_bits()).collect()
}

/// `steps` steps of the steered sine driving 2 envs of `env` reset with `seed`, one thread.
fn steered_sine(
    env: &EnvConfig,
    steps: u64,
    seed: u64,
    normalizer: Option<&mut Normalizer>,
) -> imitate::Demonstrations {
    let mut envs = VecSnakeEnv::new(env.clone(), 2)
        .unwrap()
        .with_threads(1)
        .unwrap();
    let mut out = StepBuffers::for_envs(&envs);
    envs.reset(Some(seed), &mut out.obs).unwrap();
    let mut controller =
        Demonstrator::Joints(JointsSine::new(Imitable::SteeredSine, env, 2).unwrap());
    imitate::collect(
        &mut controller,
        &mut envs,
        &mut out,
        steps,
        0.99,
        normalizer,
        &mut |_| false,
    )
    .unwrap()
    .unwrap()
}

/// Behaviour cloning on a tiny env (3 joints, 2 envs x 2048 steps of the steered sine, PPO-small):
/// the mean squared error to the controller's actions falls from that of the untrained network
/// (means near 0: about the actions' mean square; measured 0.054) to below 1e-3 in 20 epochs
/// (measured 2e-5: a residual of 0.005 rad per joint on a wave of 0.4 rad; the bound leaves a
/// factor 50 for other platforms' rounding, and is still 50 times below the start). Figures with
/// `--nocapture`.
#[test]
fn behaviour_cloning_fits_the_controller() {
    let config =
        RunConfig::from_yaml("joints: 3\nn_envs: 2\nenv: {max_episode_steps: 500}").unwrap();
    let env = config.env_config().unwrap();
    let mut norm = Normalizer::new(env.observation_dim(), 2, 0.99);
    let data = steered_sine(&env, 4096, 3, Some(&mut norm));
    assert_eq!(data.rows, 4096);
    assert!(
        data.obs.iter().all(|x| x.abs() <= 10.0),
        "normalised observations"
    );
    let net = ActorCritic::new(config.arch.clone(), env.observation_dim(), env.action_dim());
    let mut rng = <rand_chacha::ChaCha12Rng as rand::SeedableRng>::seed_from_u64(1);
    let mut params = init_params(&net, &mut rng);
    let before = imitate::bc_loss(&net, &params, &data);
    let init = InitConfig {
        epochs: 20,
        batch_size: 64,
        critic: true,
        ..InitConfig::new(Imitable::SteeredSine)
    };
    let o = net.log_std_offset();
    let log_std = params[o..o + net.act_dim()].to_vec();
    let losses = imitate::fit(&net, &mut params, &data, &init, &mut rng, &mut |_| false).unwrap();
    let after = imitate::bc_loss(&net, &params, &data);
    println!(
        "bc mse before {before:.5}, after {after:.5}; critic loss first {:?}, last {:?}",
        losses[0].critic_loss,
        losses.last().unwrap().critic_loss
    );
    assert!(before > 0.02, "{before}");
    assert!(after < 1e-3, "mse after the fit {after}");
    assert!(losses.last().unwrap().critic_loss < losses[0].critic_loss);
    assert_eq!(
        params[o..o + net.act_dim()],
        log_std[..],
        "log_std is the trainer's to set"
    );
}

/// Behaviour cloning of a gait-action hand controller holding a harder wave (`init: {imitate: steer,
/// hold: {amplitude: 0.5, frequency: 1}}`) on the goal task (3 joints, 2 envs x 2048 steps): every
/// demonstrated action holds the wave exactly, and the fit's mean squared error falls from that of
/// the untrained network (means near 0: about (0.5^2 + 1^2 + steering^2) / 3, 0.42 or more) to
/// below 1e-3 in 40 epochs (measured 2.7e-4; the steering is a clipped angle of the goal vector,
/// harder to fit than a wave). Figures with `--nocapture`.
#[test]
fn behaviour_cloning_fits_a_held_wave_of_steer() {
    let config = RunConfig::from_yaml(
        "joints: 3\nn_envs: 2\nenv: {task: goal, max_episode_steps: 300}\n\
         init: {imitate: steer, hold: {amplitude: 0.5, frequency: 1.0}}",
    )
    .unwrap();
    let env = config.env_config().unwrap();
    let init = InitConfig {
        epochs: 40,
        batch_size: 64,
        ..config.init.clone().unwrap()
    };
    let mut envs = VecSnakeEnv::new(env.clone(), 2)
        .unwrap()
        .with_threads(1)
        .unwrap();
    let mut out = StepBuffers::for_envs(&envs);
    envs.reset(Some(5), &mut out.obs).unwrap();
    let mut controller = init.demonstrator(&env, 2).unwrap();
    let mut norm = Normalizer::new(env.observation_dim(), 2, 0.99);
    let data = imitate::collect(
        &mut controller,
        &mut envs,
        &mut out,
        4096,
        0.99,
        Some(&mut norm),
        &mut |_| false,
    )
    .unwrap()
    .unwrap();
    assert!(data
        .actions
        .chunks_exact(3)
        .all(|a| a[1] == 0.5 && a[2] == 1.0 && a[0].abs() <= 1.0));
    let net = ActorCritic::new(config.arch.clone(), env.observation_dim(), env.action_dim());
    let mut rng = <rand_chacha::ChaCha12Rng as rand::SeedableRng>::seed_from_u64(1);
    let mut params = init_params(&net, &mut rng);
    let before = imitate::bc_loss(&net, &params, &data);
    imitate::fit(&net, &mut params, &data, &init, &mut rng, &mut |_| false).unwrap();
    let after = imitate::bc_loss(&net, &params, &data);
    println!("steer holding (0.5, 1): bc mse before {before:.5}, after {after:.6}");
    assert!(before > 0.4, "{before}");
    assert!(after < 1e-3, "mse after the fit {after}");
}

#[test]
fn a_seed_gives_one_initialised_run() {
    let (a, b, c) = (scratch("same-a"), scratch("same-b"), scratch("none"));
    for dir in [&a, &b] {
        trainer::train(&session(tiny(json!({})), dir, false), &mut Silent).unwrap();
    }
    assert!(params(&a) == params(&b), "two initialised runs differ");
    let mut plain = tiny(json!({}));
    plain.init = None;
    trainer::train(&session(plain, &c, false), &mut Silent).unwrap();
    assert!(params(&a) != params(&c), "the init changed nothing");
    // The fitted policy's noise is init.log_std until PPO moves it; the row at 0 is the fitted
    // policy alone.
    let evals = std::fs::read_to_string(a.join("evaluations.csv")).unwrap();
    assert!(evals.lines().nth(1).unwrap().starts_with("0,"), "{evals}");
    // Its progress is in TensorBoard (the tags are plain bytes of the event records).
    let tb = a
        .join(snake_rl::rundir::TB_DIR)
        .join(snake_rl::rundir::TB_RUN);
    let events: Vec<u8> = std::fs::read_dir(&tb)
        .unwrap()
        .flat_map(|e| std::fs::read(e.unwrap().path()).unwrap())
        .collect();
    for tag in [
        "init/bc_loss",
        "init/critic_loss",
        "init/seconds",
        "init/controller_ep_rew_mean",
    ] {
        assert!(
            events.windows(tag.len()).any(|w| w == tag.as_bytes()),
            "{tag} is not logged"
        );
    }
    for d in [a, b, c] {
        std::fs::remove_dir_all(d).ok();
    }
}

/// Stops during the init once the controller has taken `at` steps, or (`at` = None) counts the
/// init's reports.
struct StopInInit(Option<u64>, usize);

impl Observer for StopInInit {
    fn on_init(&mut self, p: &InitProgress) {
        self.1 += 1;
        if let Some(at) = self.0 {
            if p.steps >= at {
                self.0 = Some(0);
            }
        }
    }

    fn should_stop(&mut self) -> bool {
        self.0 == Some(0)
    }

    fn on_note(&mut self, _message: &str) {}
}

/// Stops once the run has taken `.0` timesteps.
struct StopAt(u64, u64);

impl Observer for StopAt {
    fn on_step(&mut self, t: u64) {
        self.1 = t;
    }
    fn should_stop(&mut self) -> bool {
        self.1 >= self.0
    }
    fn on_note(&mut self, _message: &str) {}
}

#[test]
fn resume_goes_through_the_init() {
    let (whole, stopped) = (scratch("whole"), scratch("stopped"));
    trainer::train(&session(tiny(json!({})), &whole, false), &mut Silent).unwrap();
    // Stopped during the init: the checkpoint says so, and resuming starts the init over.
    let outcome = trainer::train(
        &session(tiny(json!({})), &stopped, false),
        &mut StopInInit(Some(200), 0),
    )
    .unwrap();
    let Outcome::Interrupted(s, path) = outcome else {
        panic!("not interrupted")
    };
    assert_eq!(s.timesteps, 0);
    assert!(model::load_checkpoint(&path).unwrap().init_pending);
    let mut count = StopInInit(None, 0);
    trainer::train(&session(tiny(json!({})), &stopped, true), &mut count).unwrap();
    assert!(count.1 > 0, "the init was not done again");
    assert!(
        params(&whole) == params(&stopped),
        "a run resumed in its init differs"
    );
    // The fitted policy alone is kept as the checkpoint at 0 timesteps.
    let fitted =
        model::load_checkpoint(&whole.join("checkpoints/model_0_steps.safetensors")).unwrap();
    assert!(!fitted.init_pending);
    assert_eq!(fitted.reason, "init");
    // Stopped after the init: its checkpoints hold the fitted policy, and resuming does not redo it.
    std::fs::remove_dir_all(&stopped).ok();
    let outcome = trainer::train(
        &session(tiny(json!({})), &stopped, false),
        &mut StopAt(700, 0),
    )
    .unwrap();
    let Outcome::Interrupted(s, path) = outcome else {
        panic!("not interrupted")
    };
    assert_eq!(s.timesteps, 512);
    assert!(!model::load_checkpoint(&path).unwrap().init_pending);
    let mut count = StopInInit(None, 0);
    trainer::train(&session(tiny(json!({})), &stopped, true), &mut count).unwrap();
    assert_eq!(count.1, 0, "the init was done again");
    for d in [whole, stopped] {
        std::fs::remove_dir_all(d).ok();
    }
}

#[test]
fn bad_init_tables_name_the_key() {
    let error = |yaml: &str| RunConfig::from_yaml(yaml).unwrap_err().to_string();
    let cases = [
        (
            "init: {imitate: wiggle}",
            "init.imitate: unknown controller 'wiggle' (expected one of: sine, steered_sine, gait, steer)",
        ),
        ("init: {steps: 10}", "init: missing field `imitate`"),
        (
            "init: {imitate: sine, steps: 0}",
            "init.steps: must be in [1, 4194304], got 0",
        ),
        (
            "init: {imitate: sine, steps: 4194305}",
            "init.steps: must be in [1, 4194304]",
        ),
        (
            "init: {imitate: sine, epochs: 0}",
            "init.epochs: must be in [1,",
        ),
        (
            "init: {imitate: sine, steps: 100, batch_size: 200}",
            "init.batch_size: must be at most init.steps",
        ),
        (
            "init: {imitate: sine, log_std: 5}",
            "init.log_std: must be in [-20, 2], got 5",
        ),
        (
            "init: {imitate: sine, learning_rate: 0}",
            "init.learning_rate: must be positive",
        ),
        (
            "init: {imitate: sine, anchor: -1}",
            "init.anchor: must be in [0, 1000000], got -1",
        ),
        (
            "init: {imitate: sine, anchor: lin_2e6}",
            "init.anchor: must be in [0, 1000000], got 2000000",
        ),
        (
            "init: {imitate: sine, anchor: lin_x}",
            "init.anchor: expected a number or lin_<number>",
        ),
        (
            "init: {imitate: sine, bogus: 1}",
            "init.bogus: unknown field `bogus`",
        ),
        (
            "init: {imitate: sine}\nenv: {task: goal}",
            "init.imitate: sine sets joint targets: it needs action mode 'joints', got 'gait'",
        ),
        (
            "init: {imitate: sine}\ntrainer: sb3",
            "init: only the native trainer",
        ),
        (
            "init: {imitate: steer}",
            "init.imitate: the gait-action controllers need action mode 'gait'",
        ),
        (
            "init: {imitate: sine, hold: {amplitude: 0.5}}",
            "init.hold: sine sets joint targets: only the gait-action controllers (gait, steer) hold",
        ),
        (
            "init: {imitate: steer, hold: {amplitude: 1.5}}\nenv: {task: goal}",
            "init.hold.amplitude: must be an action in [-1, 1], got 1.5",
        ),
        (
            "init: {imitate: steer, hold: {frequency: .nan}}\nenv: {task: goal}",
            "init.hold.frequency: must be a finite number, got .nan",
        ),
        (
            "init: {imitate: steer, hold: {amplitude: 0.5}}",
            "init.imitate: the gait-action controllers need action mode 'gait'",
        ),
        (
            "init: {imitate: steer, hold: {speed: 1}}\nenv: {task: goal}",
            "init.hold.speed: unknown field `speed`",
        ),
        (
            "init: {imitate: steer}\nenv: {task: goal}\nsteer_assist: {residual: true}",
            "init: a run with steer_assist cannot imitate a controller",
        ),
    ];
    for (yaml, start) in cases {
        let e = error(yaml);
        assert!(e.starts_with(start), "{yaml}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    // No init: nothing serialised, so run configurations and models written before it are unchanged.
    assert!(!RunConfig::default().to_yaml().contains("\ninit:"));
    let c = RunConfig::from_yaml("init: {imitate: steered_sine}").unwrap();
    assert_eq!(RunConfig::from_yaml(&c.to_yaml()).unwrap(), c);
    assert_eq!(
        RunConfig::default().identity_difference(&c).unwrap().0,
        "init"
    );
}

/// Mean squared difference of two policies' action means on 2048 steps of the steered sine, each
/// normalising the observations with its own statistics (as their model files act).
fn distance(config: &RunConfig, a: &Path, b: &Path) -> f64 {
    let data = steered_sine(&config.env_config().unwrap(), 2048, 77, None);
    let means = |file: &Path| {
        let policy = model::load_policy(file).unwrap();
        let mut obs = data.obs.clone();
        if let Some(rms) = &policy.obs_rms {
            rms.normalize(&mut obs);
        }
        let mut ws = policy.net.workspace(data.rows);
        policy.net.forward(&policy.params, &obs, data.rows, &mut ws);
        ws.mean[..data.rows * policy.net.act_dim()].to_vec()
    };
    let (x, y) = (means(a), means(b));
    x.iter()
        .zip(&y)
        .map(|(p, q)| f64::from((p - q) * (p - q)))
        .sum::<f64>()
        / x.len() as f64
}

/// `init.anchor`: a weight of 0 is PPO alone, bit for bit (the fitted policy acts beside the
/// rollouts but no term joins the loss); at a learning rate and noise that move PPO's policy, a
/// heavy anchor holds it near the fitted policy; the anchor's loss is logged; a run stopped after its
/// init resumes anchored to the fitted policy of its checkpoint (measured: mean squared distances
/// 0.0094 free, 0.0015 anchored, 0.0021 anchored and resumed; PPO's steps at this rate leave a floor).
#[test]
fn an_anchor_holds_the_policy_near_the_fitted_one() {
    let config = |anchor: Value| {
        tiny(json!({
            "joints": 3, "normalize": true, "timesteps": 4096, "eval_freq": 0,
            "ppo": {"learning_rate": 1e-3, "n_epochs": 5},
            "init": {"epochs": 20, "steps": 4096, "log_std": -1.0, "anchor": anchor},
        }))
    };
    let run = |anchor: Value, name: &str| {
        let dir = scratch(name);
        trainer::train(&session(config(anchor), &dir, false), &mut Silent).unwrap();
        dir
    };
    let plain = run(Value::Null, "anchor-none");
    let zero = run(json!(0.0), "anchor-zero");
    assert!(params(&plain) == params(&zero), "anchor 0 changed the run");
    let heavy = run(json!(1000.0), "anchor-heavy");
    let fitted = |dir: &Path| dir.join("checkpoints").join("model_0_steps.safetensors");
    let c = config(Value::Null);
    let (free, kept) = (
        distance(&c, &plain.join("model.safetensors"), &fitted(&plain)),
        distance(&c, &heavy.join("model.safetensors"), &fitted(&heavy)),
    );
    println!(
        "mean squared distance to the fitted policy after PPO: free {free:.6}, anchored {kept:.6}"
    );
    assert!(kept < 0.2 * free, "anchored {kept}, free {free}");
    let tb = heavy
        .join(snake_rl::rundir::TB_DIR)
        .join(snake_rl::rundir::TB_RUN);
    let events: Vec<u8> = std::fs::read_dir(&tb)
        .unwrap()
        .flat_map(|e| std::fs::read(e.unwrap().path()).unwrap())
        .collect();
    for tag in ["train/anchor_loss", "train/anchor_weight"] {
        assert!(
            events.windows(tag.len()).any(|w| w == tag.as_bytes()),
            "{tag} not logged"
        );
    }
    // Stopped after the init and resumed: the same parameters as the run never stopped.
    let stopped = scratch("anchor-stopped");
    let outcome = trainer::train(
        &session(config(json!(1000.0)), &stopped, false),
        &mut StopAt(1500, 0),
    )
    .unwrap();
    assert!(matches!(outcome, Outcome::Interrupted(..)));
    trainer::train(&session(config(json!(1000.0)), &stopped, true), &mut Silent).unwrap();
    // (A resumed run draws new episodes, as SB3 does: held near the same fitted policy, not equal.)
    let resumed = distance(&c, &stopped.join("model.safetensors"), &fitted(&stopped));
    assert!(resumed < 0.3 * free, "resumed {resumed}, free {free}");
    // Without its fitted policy, a resumed anchored run says so.
    std::fs::remove_dir_all(&stopped).ok();
    trainer::train(
        &session(config(json!(1000.0)), &stopped, false),
        &mut StopAt(1500, 0),
    )
    .unwrap();
    std::fs::remove_file(fitted(&stopped)).unwrap();
    let e = trainer::train(&session(config(json!(1000.0)), &stopped, true), &mut Silent)
        .unwrap_err()
        .to_string();
    assert!(e.contains("init.anchor:") && !e.contains('\n'), "{e}");
    for d in [plain, zero, heavy, stopped] {
        std::fs::remove_dir_all(d).ok();
    }
}
