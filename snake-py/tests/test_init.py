"""Initialisation by imitation (the run configuration's ``init`` table) through ``snakesim train``:
bad tables are one-line refusals that create nothing, and a tiny run logs the ``init/`` scalars and
evaluates the fitted policy at 0 timesteps."""

import csv

import pytest
import yaml
from snakesim.cli import app as cli

# About a second: 2 envs, 512 controller steps, 2 rollouts of 256, episodes of at most 100 steps.
TINY = {
    "trainer": "native",
    "joints": 3,
    "n_envs": 2,
    "timesteps": 1024,
    "eval_freq": 512,
    "eval_episodes": 2,
    "checkpoint_freq": 512,
    "threads": 2,
    "normalize": True,
    "ppo": {"n_steps": 256, "batch_size": 64, "n_epochs": 2},
    "env": {"max_episode_steps": 100},
    "init": {"imitate": "steered_sine", "steps": 512, "epochs": 3, "batch_size": 64, "critic": True},
}


def train(tmp_path, capsys, config, *extra):
    path = tmp_path / "config.yaml"
    path.write_text(yaml.safe_dump(config))
    run_dir = tmp_path / "run"
    code = cli.main(["train", "--config", str(path), "--run-dir", str(run_dir), "--no-progress", *extra])
    out, err = capsys.readouterr()
    return code, out, err, run_dir


@pytest.mark.parametrize(
    ("init", "extra", "message"),
    [
        ({"imitate": "wiggle"}, [], "init.imitate: unknown variant `wiggle`"),
        ({"imitate": "sine", "steps": 0}, [], "init.steps: must be in [1, 4194304], got 0"),
        ({"imitate": "sine", "steps": 10**9}, [], "init.steps: must be in [1, 4194304]"),
        ({"imitate": "sine"}, ["--set", "env.task=goal"], "init.imitate: sine sets joint targets"),
        ({"imitate": "sine"}, ["--trainer", "sb3"], "init: only the native trainer"),
    ],
)
def test_bad_init_tables_are_one_line_and_create_nothing(init, extra, message, tmp_path, capsys):
    code, _, err, run_dir = train(tmp_path, capsys, {**TINY, "init": init}, *extra)
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and lines[0].startswith("snakesim"), err
    assert message in lines[0], lines[0]
    assert not run_dir.exists(), "nothing is created for a refused run"


def test_a_run_with_init_logs_it_and_evaluates_the_fitted_policy(tmp_path, capsys):
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    code, _, err, run_dir = train(tmp_path, capsys, TINY)
    assert code == 0, err
    assert "init: imitated steered_sine for 512 env steps" in err
    events = EventAccumulator(str(run_dir / "tb" / "PPO_1"))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert {"init/bc_loss", "init/critic_loss", "init/seconds", "init/controller_ep_rew_mean"} <= tags
    bc = [e.value for e in events.Scalars("init/bc_loss")]
    assert [e.step for e in events.Scalars("init/bc_loss")] == [0, 1, 2, 3]
    assert bc[-1] < bc[0], bc
    with open(run_dir / "evaluations.csv") as f:
        steps = [int(row["timesteps"]) for row in csv.DictReader(f)]
    assert steps == [0, 512, 1024]
    saved = yaml.safe_load((run_dir / "config.yaml").read_text())
    assert saved["init"]["imitate"] == "steered_sine"
