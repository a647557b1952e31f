"""Run configurations: defaults, YAML, command-line precedence, the shipped paper configs."""

import pathlib

import pytest
from snakesim import cli, runconfig

CONFIGS = sorted((pathlib.Path(__file__).resolve().parents[1] / "configs").glob("*.yaml"))


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
        "ent_coef": 0.0,
        "vf_coef": 0.5,
        "max_grad_norm": 0.5,
    }
    assert (config["timesteps"], config["n_envs"], config["seed"]) == (20_000_000, 16, 42)
    assert (config["eval_freq"], config["eval_episodes"], config["checkpoint_freq"]) == (
        250_000,
        10,
        1_000_000,
    )
    assert config["eval_seed"] == 42 + runconfig.EVAL_SEED_OFFSET


def test_shipped_configs_are_the_papers_four_runs():
    names = [path.stem for path in CONFIGS]
    assert names == ["paper-large-10", "paper-large-5", "paper-small-10", "paper-small-5"]
    for path in CONFIGS:
        config = runconfig.load(path)
        arch, joints = path.stem.split("-")[1:]
        assert config["arch"] == arch and config["joints"] == int(joints), path.name
        assert config["preset"] == "snakebot-gym" and config["timesteps"] == 20_000_000
        assert config["seed"] == 42 and config["ppo"] == runconfig.PPO_DEFAULTS
        # The published ppo_10_arch_shared agent records n_envs 32; the others the code's default 16.
        assert config["n_envs"] == (32 if path.stem == "paper-large-10" else 16)


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
    config = runconfig.resolve(cli._train_overrides(args))
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
        ({"arch": "huge"}, "unknown arch 'huge'"),
        ({"joints": 0}, "joints must be at least 1"),
        ({"joints": "five"}, "joints must be an integer"),
        ({"bogus": 1}, "unknown key: bogus"),
        ({"ppo": {"lr": 1}}, "unknown key in ppo: lr"),
        ({"ppo": {"gamma": 1.5}}, r"ppo.gamma must be in \[0.0, 1.0\]"),
        ({"env": {"goall": [0, 1]}}, "unknown key in env: goall"),
        ({"env": {"snake": {"mass": 1}}}, "unknown field `mass`"),
        ({"env": {"observation": "full"}}, "unknown observation"),
        ({"device": "tpu"}, "device must be"),
        ({"normalize": "yes"}, "normalize must be true or false"),
    ],
)
def test_bad_configs_name_the_key(config, match):
    with pytest.raises(runconfig.ConfigError, match=match):
        runconfig.validate(config)


def test_bad_yaml_files(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("joints: [5\narch: small\n")
    with pytest.raises(runconfig.ConfigError, match=r"bad.yaml is not valid YAML \(line"):
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
    assert runconfig.parse_set(["ppo.n_steps=64", "seed=3", "env.start={x: [0, 0]}"]) == {
        "ppo": {"n_steps": 64},
        "seed": 3,
        "env": {"start": {"x": [0, 0]}},
    }
    with pytest.raises(runconfig.ConfigError, match="KEY=VALUE"):
        runconfig.parse_set(["n_steps"])
    with pytest.raises(runconfig.ConfigError, match="only the ppo and env tables"):
        runconfig.parse_set(["joints.x=1"])
