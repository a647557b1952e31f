"""Run configurations: defaults, YAML, command-line precedence, the shipped paper configs."""

import pathlib

import pytest
from snakesim.agents.loading import env_kwargs_of
from snakesim.cli import app as cli
from snakesim.cli import train as cli_train
from snakesim.runs import config as runconfig

CONFIGS = sorted((pathlib.Path(__file__).resolve().parents[1] / "configs").glob("*.yaml"))
MODELS = pathlib.Path(__file__).resolve().parents[2] / "models"


def test_defaults_are_the_papers_table_1():
    config = runconfig.resolve({})
    assert config["ppo"] == {
        "learning_rate": 3e-4,
        "n_steps": 4096,
        "batch_size": 64,
        "n_epochs": 10,
        "gamma": 0.99,
        "gae_lambda": 0.95,
        "clip_range": 0.2,
        "clip_range_vf": None,
        "normalize_advantage": True,
        "ent_coef": 0.0,
        "vf_coef": 0.5,
        "max_grad_norm": 0.5,
        "target_kl": None,
    }
    assert config["trainer"] == "native"
    assert (config["timesteps"], config["n_envs"], config["seed"]) == (20_000_000, 16, 42)
    assert (config["eval_freq"], config["eval_episodes"], config["checkpoint_freq"]) == (
        250_000,
        10,
        1_000_000,
    )
    assert config["eval_seed"] == 42 + runconfig.EVAL_SEED_OFFSET


def test_shipped_configs_are_the_papers_four_runs_and_the_agents():
    names = [path.stem for path in CONFIGS]
    assert names == [
        "efficient-10",
        "goal-10",
        "goal-20",
        "goal-5",
        "goal-yaw-pitch-16",
        "paper-init-10",
        "paper-init-20",
        "paper-large-10",
        "paper-large-5",
        "paper-small-10",
        "paper-small-5",
        "paper-tuned-10",
        "paper-tuned-5",
        "pegs-10",
        "robust-yaw-pitch-16",
        "rough-10",
        "sand-10",
        "swim-10",
    ]
    by_name = dict(zip(names, CONFIGS, strict=True))
    for name in ("goal-5", "goal-10", "goal-20"):
        config = runconfig.load(by_name[name])
        assert config["env"] == {"task": "goal"} and config["preset"] == "paper", name
        assert config["joints"] == int(name.split("-")[1]), name
    for name in ("paper-large-10", "paper-large-5", "paper-small-10", "paper-small-5"):
        config = runconfig.load(by_name[name])
        arch, joints = name.split("-")[1:]
        assert config["arch"] == arch and config["joints"] == int(joints), name
        assert config["preset"] == "snakebot-gym" and config["timesteps"] == 20_000_000
        assert config["seed"] == 42 and config["ppo"] == runconfig.DEFAULTS["ppo"]
        # The published ppo_10_arch_shared agent records n_envs 32; the others the code's default 16.
        assert config["n_envs"] == (32 if name == "paper-large-10" else 16)


# Each shipped agent's model file, by the config that trained it (the same name, or as listed here).
AGENT_OF_CONFIG = {"paper-tuned-10": "paper-10", "paper-init-20": "paper-20"}


@pytest.mark.parametrize(
    "path",
    [p for p in CONFIGS if (MODELS / f"{AGENT_OF_CONFIG.get(p.stem, p.stem)}.safetensors").is_file()],
    ids=lambda p: p.stem,
)
def test_a_shipped_agents_config_trains_in_the_env_its_model_records(path):
    # The model's metadata is what snake-rl wrote at the end of the training that the config ran.
    config = runconfig.load(path)
    model = MODELS / f"{AGENT_OF_CONFIG.get(path.stem, path.stem)}.safetensors"
    recorded = env_kwargs_of(model)
    for key in ("robot", "world"):
        # A robot or world file edited since training (yaw-pitch-16 got its servo limit) is the
        # model's record, not the file: the config names the same file, and retraining it now
        # trains on the file as it is (goal-yaw-pitch-16.yaml says so).
        if isinstance(recorded.get(key), dict):
            assert recorded[key]["path"] == config["env"][key]
            recorded[key] = recorded[key]["path"]
    assert runconfig.env_kwargs(config) == recorded
    assert config["trainer"] == "native"


def test_every_shipped_agent_has_its_config():
    trained = {AGENT_OF_CONFIG.get(p.stem, p.stem) for p in CONFIGS}
    assert sorted(p.stem for p in MODELS.glob("*.safetensors") if p.stem not in trained) == []


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_config_round_trip(path, tmp_path):
    resolved = runconfig.resolve(runconfig.load_yaml(path))
    runconfig.save(resolved, tmp_path / "config.yaml")
    assert runconfig.load(tmp_path / "config.yaml") == resolved
    assert runconfig.resolve(runconfig.load(tmp_path / "config.yaml")) == resolved


def test_precedence_defaults_yaml_then_flags(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("joints: 7\nn_envs: 3\nppo: {n_steps: 128}\nenv: {max_episode_steps: 300}\n")
    args = cli.build_parser().parse_args(
        [
            "train",
            "--config",
            str(path),
            "--joints",
            "4",
            "--set",
            "ppo.batch_size=32",
            "--set",
            "env.goal=[1, 2]",
        ]
    )
    config = runconfig.resolve(cli_train._train_overrides(args))
    assert config["joints"] == 4, "a flag beats the YAML"
    assert config["n_envs"] == 3, "the YAML beats the default"
    assert config["seed"] == 42, "the default where nothing is said"
    assert (
        config["ppo"]["n_steps"] == 128
        and config["ppo"]["batch_size"] == 32
        and config["ppo"]["n_epochs"] == 10
    )
    assert config["env"] == {"max_episode_steps": 300, "goal": [1, 2]}


@pytest.mark.parametrize(
    ("config", "match"),
    [
        ({"arch": "huge"}, "^arch: unknown variant `huge`"),
        ({"trainer": "jax"}, "^trainer: unknown variant `jax`"),
        ({"joints": 0}, r"^joints: must be in \[1, 128\], got 0"),
        ({"joints": "five"}, '^joints: invalid type: string "five", expected a non-negative integer'),
        ({"joints": 2.5}, "^joints: invalid type: floating point `2.5`, expected a non-negative integer"),
        ({"bogus": 1}, "^bogus: unknown field `bogus`"),
        ({"ppo": {"lr": 1}}, "^ppo.lr: unknown field `lr`"),
        ({"ppo": {"gamma": 1.5}}, r"^ppo.gamma: must be in \[0, 1\], got 1.5"),
        ({"ppo": {"learning_rate": 0}}, "^ppo.learning_rate: must be positive, got 0"),
        ({"ppo": {"n_epochs": 0}}, r"^ppo.n_epochs: must be in \[1,"),
        ({"ppo": {"batch_size": 100_000}}, r"^ppo.batch_size: must be in \[2, n_steps \* n_envs = 65536\]"),
        ({"seed": 2**32}, r"^seed: must be in \[0, 4294967295\]"),
        ({"env": {"goall": [0, 1]}}, "^env.goall: unknown field `goall`"),
        ({"env": {"snake": {"mass": 1}}}, "^env.snake.mass: unknown field `mass`"),
        ({"env": {"observation": "full"}}, "^env.observation: unknown variant `full`"),
        (
            {"env": {"reward": {"progress_weight": "a"}}},
            '^env.reward.progress_weight: invalid type: string "a"',
        ),
        ({"env": {"max_episode_steps": 1e30}}, "^env.max_episode_steps: invalid type: floating point"),
        ({"device": "tpu"}, "^device: expected auto, cpu, cuda or cuda:N, got 'tpu'"),
        ({"normalize": "yes"}, '^normalize: invalid type: string "yes", expected a boolean'),
    ],
)
def test_bad_configs_name_the_key(config, match):
    with pytest.raises(runconfig.ConfigError, match=match):
        runconfig.validate(config)


def test_bad_yaml_files(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("joints: [5\narch: small\n")
    with pytest.raises(runconfig.ConfigError, match=r"bad.yaml: not valid YAML \(line"):
        runconfig.load_yaml(bad)
    listing = tmp_path / "list.yaml"
    listing.write_text("- 1\n- 2\n")
    with pytest.raises(runconfig.ConfigError, match="must hold a mapping"):
        runconfig.load_yaml(listing)
    with pytest.raises(runconfig.ConfigError, match="does not exist"):
        runconfig.load_yaml(tmp_path / "missing.yaml")
    assert runconfig.load_yaml(_write(tmp_path / "empty.yaml", "")) == {}


def _write(path, text):
    path.write_text(text)
    return path


def test_parse_set():
    # Values are YAML, parsed by the same rules as the config files: 3e-4 is a number.
    assert runconfig.parse_set(
        [
            "ppo.n_steps=64",
            "seed=3",
            "env.start={x: [0, 0]}",
            "ppo.learning_rate=3e-4",
            "env.reward.progress_weight=2",
        ]
    ) == {
        "ppo": {"n_steps": 64, "learning_rate": 3e-4},
        "seed": 3,
        "env": {"start": {"x": [0, 0]}, "reward": {"progress_weight": 2}},
    }
    with pytest.raises(runconfig.ConfigError, match="KEY=VALUE"):
        runconfig.parse_set(["n_steps"])
    with pytest.raises(runconfig.ConfigError, match="is not a key path"):
        runconfig.parse_set(["ppo..n_steps=1"])


def test_set_merges_into_nested_tables():
    config = runconfig.resolve(
        runconfig.merge(
            {"env": {"reward": {"smoothness_weight": 0.5}}},
            runconfig.parse_set(["env.reward.progress_weight=1", "timesteps=2e6"]),
        )
    )
    assert config["env"]["reward"] == {"smoothness_weight": 0.5, "progress_weight": 1}
    assert config["timesteps"] == 2_000_000


def test_linear_schedules():
    config = runconfig.validate({"ppo": {"learning_rate": "lin_1e-3", "clip_range": "lin_0.3"}})
    assert config["ppo"]["learning_rate"] == "lin_0.001"
    lr = runconfig.schedule(config["ppo"]["learning_rate"])
    assert lr(1.0) == 1e-3 and lr(0.5) == 5e-4
    with pytest.raises(runconfig.ConfigError, match="^ppo.learning_rate: expected a number or lin_"):
        runconfig.validate({"ppo": {"learning_rate": "fast"}})
