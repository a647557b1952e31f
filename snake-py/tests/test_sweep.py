"""`snakesim sweep` on Ray: a local Ray head started here (127.0.0.1, 2 CPUs) runs the trials of tiny
sweeps submitted with --address; a trial whose worker is killed resumes from its checkpoint; an
interrupted sweep resumes without redoing finished trials; bad input is one line. The cluster is
stopped when the module's tests end, pass or fail."""

import csv
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
import yaml
from PIL import Image
from snakesim.cli import app as cli
from snakesim.runs import config as runconfig
from snakesim.sweeps.plan import CONNECT_TIMEOUT_S
from snakesim.sweeps.summary import SUCCESS_THRESHOLD

# Rollouts of 2 envs x 256 steps; an evaluation (2 episodes of at most 100 steps) and a checkpoint
# every 1024 timesteps.
TINY = {
    "joints": 3,
    "timesteps": 4096,
    "n_envs": 2,
    "eval_freq": 1024,
    "checkpoint_freq": 1024,
    "eval_episodes": 2,
    "ppo": {"n_steps": 256, "batch_size": 128, "n_epochs": 2},
    "env": {"max_episode_steps": 100},
}
# The goal (0, -10) lies 10 m from the start: with a 11 m goal radius every episode succeeds at its
# first step, so this config reaches a success rate of 1 at its first evaluation. (Every step is then
# a reset, which is slow: half the timesteps.)
NEAR = {**TINY, "timesteps": 2048, "env": {**TINY["env"], "goal_radius": 11.0}}
# The Stable-Baselines3 trainer (one torch thread), half the timesteps too: SB3 steps are slower.
FAR_SB3 = {**TINY, "timesteps": 2048, "trainer": "sb3", "device": "cpu"}
FAULT_TRIAL = "fault_seed42"
# The fault, injected into the cluster's Python processes only (a sitecustomize on their PYTHONPATH), so
# that no test hook ships: the trial FAULT_TRIAL kills its own worker (SIGKILL) once, right after it
# reported its first checkpoint to Tune, the moment a real crash costs the least and tests the most.
FAULT_HOOK = f"""
import os, signal
try:
    from snakesim.sweeps import tune_runner
except ImportError:
    tune_runner = None
if tune_runner is not None:
    report = tune_runner._Reporter.__call__

    def __call__(self, row):
        first = self.reported_checkpoint == 0
        report(self, row)
        if first and self.reported_checkpoint and self.started_from == 0 and self.name == {FAULT_TRIAL!r}:
            os.kill(os.getpid(), signal.SIGKILL)

    tune_runner._Reporter.__call__ = __call__
"""
RAY = Path(sys.executable).with_name("ray")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def write_config(folder: Path, name: str, config: dict) -> Path:
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(config))
    return path


def snakesim(*argv, timeout=180, env=None):
    """The snakesim command in a child process (Ray is not imported into the test process)."""
    return subprocess.run(
        [sys.executable, "-m", "snakesim", *map(str, argv)],
        capture_output=True,
        text=True,
        timeout=timeout,
        env=env,
    )


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def cluster():
    """A Ray head on 127.0.0.1 with 2 CPUs (its workers import snakesim as this process does, and kill
    the trial FAULT_TRIAL once); stopped, with all its processes, when the tests end."""
    port = free_port()
    temp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths have a length limit
    hooks = Path(temp) / "hooks"
    hooks.mkdir()
    (hooks / "sitecustomize.py").write_text(FAULT_HOOK)
    path = os.pathsep.join(p for p in (str(hooks), os.environ.get("PYTHONPATH")) if p)
    env = {**os.environ, "PYTHONPATH": path, "RAY_USAGE_STATS_ENABLED": "0"}
    # fmt: off
    head = subprocess.Popen(
        [
            RAY, "start", "--head", "--block", "--num-cpus", "2", "--include-dashboard=false",
            "--node-ip-address", "127.0.0.1", "--port", str(port),
            "--ray-client-server-port", str(free_port()), "--dashboard-agent-listen-port", str(free_port()),
            "--temp-dir", temp,
        ],
        env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
    )
    # fmt: on
    try:
        deadline = time.monotonic() + 60
        while True:
            assert head.poll() is None, "ray start --head exited"
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert time.monotonic() < deadline, "the Ray head did not start within 60 s"
                time.sleep(0.2)
        yield {"address": f"127.0.0.1:{port}", "temp": Path(temp)}
    finally:
        # `ray start --block` stops the cluster's processes when it is terminated.
        head.terminate()
        try:
            head.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(head.pid, signal.SIGKILL)
            head.wait()
        shutil.rmtree(temp, ignore_errors=True)


def test_sweep_of_two_configs_and_two_seeds_on_a_cluster(cluster, tmp_path, capsys):
    near = write_config(tmp_path, "near", NEAR)
    far = write_config(tmp_path, "far", FAR_SB3)
    out = tmp_path / "sweep"
    done = snakesim(
        "sweep", near, far, "--seeds", 2, "--out", out, "--address", cluster["address"], "--progress"
    )
    assert done.returncode == 0, done.stderr
    assert f"4 trials on the Ray cluster at {cluster['address']} (2 CPUs)" in done.stdout
    assert "trials: 0 running, 4 done, 0 failed, 0 waiting (of 4)" in done.stderr
    assert "Traceback" not in done.stderr

    # Every trial is a run directory of its trainer, trained to the end.
    trials = {p.name: p for p in (out / "trials").iterdir()}
    assert sorted(trials) == ["far_seed42", "far_seed43", "near_seed42", "near_seed43"]
    for name, run in trials.items():
        config = yaml.safe_load((run / "config.yaml").read_text())
        assert config["seed"] == int(name[-2:])
        assert config["trainer"] == ("native" if name.startswith("near") else "sb3")
        model = "model.safetensors" if name.startswith("near") else "model.zip"
        assert (run / model).is_file() and (run / "versions.json").is_file()
        rows = read_csv(run / "evaluations.csv")
        assert [int(r["timesteps"]) for r in rows] == list(range(1024, config["timesteps"] + 1, 1024))
        sessions = [json.loads(line) for line in (run / "sessions.jsonl").read_text().splitlines()]
        assert [s["resumed_from"] for s in sessions] == [0]
    # The trials ran on the test's cluster: its workers' logs are in its temp folder.
    assert list(cluster["temp"].glob("session_*/logs/worker-*"))

    # The summary: one row per config, means and spreads over the two seeds.
    summary = {row["config"]: row for row in read_csv(out / "summary.csv")}
    assert list(summary) == ["near", "far"]
    to = f"{SUCCESS_THRESHOLD:g}"
    near_row, far_row = summary["near"], summary["far"]
    assert (near_row["seeds"], near_row["seeds_evaluated"], near_row[f"seeds_reaching_{to}"]) == (
        "2",
        "2",
        "2",
    )
    assert float(near_row["final_success_rate_mean"]) == 1.0
    assert float(near_row["final_success_rate_std"]) == 0.0
    assert float(near_row[f"timesteps_to_{to}_mean"]) == 1024.0  # the first evaluation
    walls = [float(read_csv(trials[f"near_seed{s}"] / "evaluations.csv")[0]["wall_time"]) for s in (42, 43)]
    assert float(near_row[f"wall_time_to_{to}_mean"]) == pytest.approx(sum(walls) / 2, abs=1e-6)
    finals = [
        float(read_csv(trials[f"far_seed{s}"] / "evaluations.csv")[-1]["mean_return"]) for s in (42, 43)
    ]
    assert float(far_row["final_return_mean"]) == pytest.approx(sum(finals) / 2, abs=1e-6)
    assert float(far_row["final_return_std"]) == pytest.approx(abs(finals[0] - finals[1]) / 2**0.5, abs=1e-6)
    assert float(far_row["final_success_rate_mean"]) == 0.0
    assert far_row[f"seeds_reaching_{to}"] == "0" and far_row[f"timesteps_to_{to}_mean"] == ""
    assert float(far_row["final_timesteps_mean"]) == 2048.0
    table = done.stdout.splitlines()
    assert any(line.startswith("near ") and "1,024 ± 0" in line and "(2/2 seeds)" in line for line in table)
    assert any(line.startswith("far ") and "not reached (0/2 seeds)" in line for line in table)

    # The learning curves: one line per config with its seeds' band.
    figure = tmp_path / "curves.png"
    assert cli.main(["plot", str(out), "--out", str(figure), "--metric", "success_rate"]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {figure}: near, 2 runs; far, 2 runs"
    with Image.open(figure) as image:
        assert image.size == (1050, 675)


def test_a_search_for_success_auc_on_a_cluster(cluster, tmp_path):
    # The goal lies 10 m from the start: a goal radius above 10 succeeds at every step, one below it
    # never does in these few timesteps, so a trial's success_auc is 1 or 0 by its radius alone.
    base = write_config(tmp_path, "base", {**NEAR, "eval_freq": 512})
    space = tmp_path / "space.yaml"
    # A choice of lists (the policy's widths) reaches the trials as lists, and Optuna without a warning.
    space.write_text(
        "env.goal_radius: {uniform: [8.0, 12.0]}\nppo.n_epochs: {randint: [1, 3]}\n"
        "arch.pi: {choice: [[8], [16, 16]]}\n"
    )
    out = tmp_path / "search"
    done = snakesim(
        "search", base, "--space", space, "--trials", 6, "--metric", "success_auc", "--out", out,
        "--address", cluster["address"], "--cpus-per-trial", 1, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "Warning" not in done.stderr, done.stderr

    # success_auc, computed here from each trial's evaluations.csv: the mean of its success rates.
    aucs = {}
    for run in sorted((out / "trials").iterdir()):
        config = yaml.safe_load((run / "config.yaml").read_text())
        assert 8.0 <= config["env"]["goal_radius"] <= 12.0 and 1 <= config["ppo"]["n_epochs"] <= 3
        assert config["arch"] in ({"shared": [], "pi": pi, "vf": [64, 64]} for pi in ([8], [16, 16]))
        rates = [float(r["success_rate"]) for r in read_csv(run / "evaluations.csv")]
        assert set(rates) == ({1.0} if config["env"]["goal_radius"] > 10.0 else {0.0})
        aucs[run.name] = (sum(rates) / len(rates), len(rates), config["env"]["goal_radius"])
    assert len(aucs) == 6
    summary = {json.loads(row["grid"])["env.goal_radius"]: row for row in read_csv(out / "summary.csv")}
    for auc, _, radius in aucs.values():
        assert float(summary[radius]["final_success_auc_mean"]) == pytest.approx(auc, abs=1e-6)

    # best.yaml is the trial with the highest success_auc (more evaluations break ties).
    best = max(aucs, key=lambda name: aucs[name][:2])
    header = (out / "best.yaml").read_text().splitlines()[0]
    assert header == f"# The best trial of the search {out} ({best}): final success_auc {aucs[best][0]:.4g}."
    assert yaml.safe_load((out / "best.yaml").read_text())["env"]["goal_radius"] == aucs[best][2]

    # Optuna's importance of the three keys for the final success_auc, written and printed.
    record = json.loads((out / "importance.json").read_text())
    assert record["metric"] == "success_auc" and record["trials"] == 6
    assert sorted(record["importance"]) == ["arch.pi", "env.goal_radius", "ppo.n_epochs"]
    assert sum(record["importance"].values()) == pytest.approx(1.0)
    assert "importance for the final success_auc over 6 trials: " in done.stdout


def test_a_killed_trial_resumes_from_its_checkpoint(cluster, tmp_path):
    fault = write_config(tmp_path, "fault", TINY)
    out = tmp_path / "sweep"
    done = snakesim(
        "sweep", fault, "--out", out, "--address", cluster["address"], "--max-failures", 1, "--progress"
    )
    assert done.returncode == 0, done.stderr
    assert "trials: 0 running, 1 done, 0 failed, 0 waiting (of 1), 1 retried" in done.stderr
    run = out / "trials" / FAULT_TRIAL
    # The first session's worker died at its second evaluation (2048), after its checkpoint at 1024
    # had been reported; the retry resumed from that checkpoint, in another worker.
    sessions = [json.loads(line) for line in (run / "sessions.jsonl").read_text().splitlines()]
    assert [s["resumed_from"] for s in sessions] == [0, 1024]
    assert sessions[0]["pid"] != sessions[1]["pid"]
    # Each evaluation once (the one the dead worker wrote at 2048 was redone), every checkpoint.
    assert [int(r["timesteps"]) for r in read_csv(run / "evaluations.csv")] == [1024, 2048, 3072, 4096]
    checkpoints = sorted(int(p.name.split("_")[1]) for p in (run / "checkpoints").glob("*.safetensors"))
    assert checkpoints == [1024, 2048, 3072, 4096]
    assert len(list((run / "tb").glob("*/events.out.tfevents.*"))) == 2  # one log per session
    # Tune heard of both sessions: the retry's results say where it resumed from.
    results = (out / "tune" / "session-1" / FAULT_TRIAL / "result.json").read_text().splitlines()
    results = [json.loads(line) for line in results]
    assert [(r["timesteps"], r["resumed_from"]) for r in results] == [
        (1024, 0),
        (2048, 0),
        (2048, 1024),
        (3072, 1024),
        (4096, 1024),
    ]


def test_an_interrupted_sweep_resumes_and_runs_only_the_rest(cluster, tmp_path):
    config = write_config(tmp_path, "resume", {**TINY, "timesteps": 16384})
    out = tmp_path / "sweep"
    # One trial at a time (2 CPUs each): Ctrl-C once the first has finished.
    argv = [
        "sweep",
        config,
        "--seeds",
        3,
        "--out",
        out,
        "--address",
        cluster["address"],
        "--cpus-per-trial",
        2,
    ]
    sweep = subprocess.Popen(
        [sys.executable, "-m", "snakesim", *map(str, argv)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    # A trial trained to the end (a stopped one has a model.safetensors too).
    final = "checkpoints/model_16384_steps.safetensors"
    while not list(out.glob(f"trials/*/{final}")):
        assert sweep.poll() is None and time.monotonic() < deadline, "no trial finished"
        time.sleep(0.1)
    sweep.send_signal(signal.SIGINT)
    stdout, stderr = sweep.communicate(timeout=60)
    assert sweep.returncode == 130, stderr
    assert f"continue with: snakesim sweep --resume {out}" in stderr
    finished = sorted(p.parents[1].name for p in out.glob(f"trials/*/{final}"))
    assert len(finished) == 1, finished
    before = {name: (out / "trials" / name / "evaluations.csv").stat().st_mtime_ns for name in finished}

    resumed = snakesim("sweep", "--resume", out, "--address", cluster["address"])
    assert resumed.returncode == 0, resumed.stderr
    assert "1 of 3 trials finished; running the other 2" in resumed.stdout
    for name in ["resume_seed42", "resume_seed43", "resume_seed44"]:
        run = out / "trials" / name
        assert [int(r["timesteps"]) for r in read_csv(run / "evaluations.csv")][-1] == 16384
        sessions = (run / "sessions.jsonl").read_text().splitlines()
        if name in finished:  # untouched
            assert len(sessions) == 1
            assert (run / "evaluations.csv").stat().st_mtime_ns == before[name]
    summary = read_csv(out / "summary.csv")
    assert [(r["config"], r["seeds"], r["seeds_evaluated"]) for r in summary] == [("resume", "3", "3")]
    assert sorted(p.name for p in (out / "tune").iterdir()) == ["session-1", "session-2"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["{bad}", "--out", "{out}"], "bad.yaml: foo: unknown field `foo`, expected one of `trainer`"),
        (["{good}", "--out", "{out}", "--set", "ppo.nope=1"], "ppo.nope: unknown field `nope`"),
        (["{good}", "--out", "{out}", "--grid", "ppo.n_epochs="], "--grid ppo.n_epochs: the grid is empty"),
        (
            ["{good}", "--out", "{out}", "--grid", "ppo.n_epochs=2,,3"],
            "--grid ppo.n_epochs: the grid is empty",
        ),
        (["{good}", "--out", "{folder}"], "exists, is not empty and is not a sweep; choose another --out"),
        (["--resume", "{folder}"], "is not a sweep folder (no sweep.json)"),
    ],
)
def test_bad_input_is_one_line(tmp_path, capsys, argv, message):
    write_config(tmp_path, "bad", {**TINY, "foo": 1})
    write_config(tmp_path, "good", TINY)
    (tmp_path / "folder").mkdir()
    (tmp_path / "folder" / "notes.txt").write_text("mine\n")
    names = {"bad": tmp_path / "bad.yaml", "good": tmp_path / "good.yaml", "out": tmp_path / "out"}
    names["folder"] = tmp_path / "folder"
    code = cli.main(["sweep", *(a.format(**names) for a in argv)])
    out, err = capsys.readouterr()
    assert code == 1
    assert len(err.splitlines()) == 1 and err.startswith("snakesim sweep: error: ")
    assert message in err
    assert not (tmp_path / "out").exists()
    assert (tmp_path / "folder" / "notes.txt").read_text() == "mine\n"


@pytest.mark.parametrize(
    "space, message",
    [
        ({"ppo": {"learning_rate": {"loguniform": [0.0, 1.0e-3]}}}, "loguniform needs LOW > 0"),
        ({"ppo.n_epochs": {"randint": [5, 2]}}, "randint takes [LOW, HIGH], two numbers with LOW < HIGH"),
        ({"ppo.nope": {"uniform": [0, 1]}}, "ppo.nope = 0: ppo.nope: unknown field `nope`"),
        ({"ppo.batch_size": {"choice": [64, 1]}}, "ppo.batch_size = 1: ppo.batch_size: must be in [2, "),
        ({"ppo.n_epochs": [1, 2]}, "ppo.n_epochs: expected one distribution"),
        ({}, "is empty"),
    ],
)
def test_bad_search_space_is_one_line(tmp_path, capsys, space, message):
    good = write_config(tmp_path, "good", TINY)
    space_file = tmp_path / "space.yaml"
    space_file.write_text(yaml.safe_dump(space))
    argv = ["search", good, "--space", space_file, "--trials", 2, "--out", tmp_path / "out"]
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    assert code == 1
    assert len(err.splitlines()) == 1 and err.startswith("snakesim search: error: ")
    assert message in err
    assert not (tmp_path / "out").exists()


def test_an_unreachable_address_is_one_line_within_the_timeout(tmp_path):
    good = write_config(tmp_path, "good", TINY)
    port = free_port()  # nothing listens there
    started = time.monotonic()
    done = snakesim("sweep", good, "--out", tmp_path / "out", "--address", f"127.0.0.1:{port}", timeout=120)
    assert time.monotonic() - started < CONNECT_TIMEOUT_S
    assert done.returncode == 1
    assert done.stderr == (
        f"snakesim sweep: error: cannot reach a Ray cluster at 127.0.0.1:{port}: Connection refused\n"
    )
    assert not (tmp_path / "out").exists()

    # Something that accepts connections and never answers (Ray would wait for it for minutes): the
    # timeout ends the wait (here 3 s instead of CONNECT_TIMEOUT_S).
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen()
        address = f"127.0.0.1:{silent.getsockname()[1]}"
        code = f"from snakesim.sweeps import tune_runner\ntune_runner.connect({address!r}, timeout=3)"
        started = time.monotonic()
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
        assert time.monotonic() - started < 15
    assert done.returncode == 1
    assert done.stderr.strip().splitlines()[-1] == (
        f"snakesim.sweeps.plan.SweepError: no Ray cluster answered at {address} within 3 s"
    )


@pytest.mark.parametrize(
    "space_file, config, sets, keys",
    [
        ("paper-5.yaml", "paper-tuned-5.yaml", ["seed=100", "timesteps=786432", "eval_freq=65536"], 12),
        ("paper-10.yaml", "paper-tuned-10.yaml", ["seed=100", "timesteps=1572864", "eval_freq=262144"], 13),
    ],
)
def test_the_shipped_search_spaces_fit_the_configs_they_search(space_file, config, sets, keys):
    # snake-py/configs/spaces/*.yaml, with the base config and --set of docs/experiments.md's searches:
    # every end of a range and every choice is a valid value, and every pairing of rollout shape and
    # minibatch size fits (the smallest rollout holds the largest minibatch).
    from snakesim.sweeps import plan, search

    configs = Path(__file__).resolve().parents[1] / "configs"
    ((_, base),) = plan.load_configs([configs / config], sets).items()
    space = search.load_space(configs / "spaces" / space_file, base)
    assert len(space) == keys and not any(key.startswith("env") for key in space)
    rollout = min(space["ppo.n_steps"][1]) * min(space["n_envs"][1])
    assert max(space["ppo.batch_size"][1]) <= rollout


def test_a_searchs_choices_reach_optuna_as_plain_values_and_trials_as_written():
    # Optuna's categorical distributions take None, bools, numbers and strings; a list or mapping goes
    # as its JSON text and comes back to the trial as the space wrote it (true is not taken for 1).
    from snakesim.sweeps import search

    space = {
        "arch.pi": ("choice", [[64, 64], [256, 256, 256]]),
        "arch": ("choice", ["small", {"pi": [32]}]),
        "ppo.target_kl": ("choice", [None, 0.03]),
        "normalize": ("choice", [1, True]),
        "ppo.n_epochs": ("randint", [3, 20]),
    }
    tuned = search._tune_space(space)
    assert tuned["arch.pi"].categories == ["[64, 64]", "[256, 256, 256]"]
    assert tuned["arch"].categories == ["small", '{"pi": [32]}']
    assert tuned["ppo.target_kl"].categories == [None, 0.03]
    params = {"arch.pi": "[256, 256, 256]", "arch": '{"pi": [32]}', "ppo.target_kl": None, "normalize": True}
    values = search._from_tune(space, {**params, "ppo.n_epochs": 7})
    assert values == {
        "arch.pi": [256, 256, 256],
        "arch": {"pi": [32]},
        "ppo.target_kl": None,
        "normalize": True,
        "ppo.n_epochs": 7,
    }
    assert values["normalize"] is True  # == alone would also accept the choice 1


def test_the_importance_study_has_the_distributions_optuna_searched():
    # importance() rebuilds a study; its distributions are what Tune's OptunaSearch made of the space
    # (randint includes both ends, as the space file says, though Tune's own upper end is excluded).
    from optuna.distributions import CategoricalDistribution, FloatDistribution, IntDistribution
    from snakesim.sweeps import search

    space = {
        "ppo.n_epochs": ("randint", [3, 20]),
        "ppo.learning_rate": ("loguniform", [1.0e-5, 1.0e-3]),
        "ppo.ent_coef": ("uniform", [0.0, 0.01]),
        "arch.pi": ("choice", [[64, 64], [256, 256]]),
    }
    assert search._optuna_space(space) == {
        "ppo.n_epochs": IntDistribution(3, 20),
        "ppo.learning_rate": FloatDistribution(1.0e-5, 1.0e-3, log=True),
        "ppo.ent_coef": FloatDistribution(0.0, 0.01),
        "arch.pi": CategoricalDistribution(["[64, 64]", "[256, 256]"]),
    }


def test_a_search_varies_the_networks_widths_and_log_std_init(tmp_path):
    # arch.pi / arch.vf / arch.shared take lists of widths; a part the trial leaves alone keeps the base
    # network's widths (large keeps its trunk).
    from snakesim.sweeps import search

    space_file = tmp_path / "space.yaml"
    space_file.write_text(
        "arch.pi: {choice: [[64, 64], [256, 256], [128, 128, 128]]}\n"
        "arch.vf: {choice: [[64], [256, 256]]}\n"
        "log_std_init: {uniform: [-1.5, 0.0]}\n"
    )
    base = {"arch": "large"}
    space = search.load_space(space_file, base)
    assert space["arch.pi"] == ("choice", [[64, 64], [256, 256], [128, 128, 128]])
    trial = search._overrides(base, {"arch.pi": [256, 256], "log_std_init": -0.5})
    resolved = runconfig.resolve(trial)
    assert resolved["arch"] == {"shared": [128, 128], "pi": [256, 256], "vf": [64, 64]}
    assert resolved["log_std_init"] == -0.5
    space_file.write_text("arch.pi: {choice: [[64], []]}\n")
    with pytest.raises(
        runconfig.ConfigError, match=r"arch.pi = \[\]: arch.pi: must have 1 to 8 layers, got 0"
    ):
        search.load_space(space_file, base)
