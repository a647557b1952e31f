"""Progress where a person waits (evaluate, calibrate, sweep, export of an SB3 zip): a bar on a
terminal, one plain line per step of progress on stderr when piped, nothing on stdout beside
``--json -``'s JSON; progress changes no result. Also: ``import snakesim`` reaches the documented
subpackages, and ``evaluate`` says which robot ran."""

import io
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from snakesim.agents import evaluate, load_agent
from snakesim.agents.recorded import note
from snakesim.runs.progress import Progress, clock

REPO = Path(__file__).resolve().parents[2]
SNAKESIM = [sys.executable, "-m", "snakesim"]


def run(*args, **kwargs) -> subprocess.CompletedProcess:
    """The command with stdout and stderr piped (not a terminal), from the repository root."""
    return subprocess.run(
        [*SNAKESIM, *map(str, args)], capture_output=True, text=True, cwd=REPO, timeout=300, **kwargs
    )


def test_piped_progress_is_one_line_per_step():
    stream = io.StringIO()
    with Progress(3, "episodes", "evaluate", stream=stream) as progress:
        for done in (1, 1, 2, 3):  # a repeated count is no step
            progress.update(done)
    lines = stream.getvalue().splitlines()
    assert [line.split(",")[0] for line in lines] == [f"evaluate: {k}/3 episodes" for k in (1, 2, 3)]
    assert all("elapsed" in line for line in lines)
    assert "left" in lines[0] and "left" not in lines[-1]
    assert Progress(3, "x", "y", stream=stream).line(1, 10.0, "best error 2") == (
        "y: 1/3 x, 0:10 elapsed, about 0:20 left, best error 2"
    )
    assert clock(3725) == "1:02:05"
    quiet = io.StringIO()
    with Progress(3, "episodes", "evaluate", show=False, stream=quiet) as progress:
        progress.update(3)
    assert quiet.getvalue() == ""


def test_the_bar_has_a_total_and_an_estimate():
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    stream = Terminal()
    with Progress(4, "episodes", "evaluate", stream=stream) as progress:
        assert progress.mode == "bar"
        progress.update(1)
        progress.update(4)
    text = stream.getvalue()
    assert "4/4" in text and "evaluate" in text and "<" in text  # tqdm's elapsed<left


def test_evaluate_piped_prints_a_line_per_episode_and_json_alone_on_stdout():
    done = run("evaluate", "baseline:steer", "--joints", 5, "--episodes", 3, "--json", "-")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)  # stdout is the JSON alone
    assert report["episodes"] == 3 and report["robot"] is None and report["world"] is None
    lines = done.stderr.splitlines()
    assert [line.split(",")[0] for line in lines] == [f"evaluate: {k}/3 episodes" for k in (1, 2, 3)]
    quiet = run("evaluate", "baseline:steer", "--joints", 5, "--episodes", 3, "--json", "-", "--no-progress")
    assert quiet.returncode == 0 and quiet.stderr == ""
    assert json.loads(quiet.stdout)["per_episode"] == report["per_episode"]


def test_export_of_an_sb3_zip_shows_its_steps_and_a_native_model_none(tmp_path):
    # An SB3 zip (snakesim's own export of a native model) loads through SB3 and torch: seconds.
    native_model = REPO / "models" / "goal-5.safetensors"
    assert run("export", native_model, "--sb3", tmp_path / "goal-5.zip").returncode == 0
    done = run("export", tmp_path / "goal-5.zip", "--onnx", tmp_path / "goal-5.onnx")
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(f"wrote {tmp_path / 'goal-5.onnx'} ") and len(done.stdout.splitlines()) == 1
    lines = done.stderr.splitlines()
    assert [line.split(",")[0] for line in lines] == ["export: 1/2 steps", "export: 2/2 steps"], lines
    assert lines[0].endswith(f"loaded {tmp_path / 'goal-5.zip'}")
    assert lines[1].endswith("built the ONNX graph")
    assert "left" not in done.stderr  # no estimate: the load is nearly all of the time
    native = run("export", native_model, "--onnx", tmp_path / "native.onnx")
    assert native.returncode == 0 and native.stderr == ""
    shown = run("export", native_model, "--onnx", tmp_path / "n2.onnx", "--progress")
    assert shown.returncode == 0 and "export: 100%" in shown.stderr


def test_progress_changes_no_episode():
    agent = load_agent("baseline:steer", joints=5)
    heard: list[int] = []
    plain = evaluate(agent, 18, 900000)
    shown = evaluate(agent, 18, 900000, progress=heard.append)
    assert heard == list(range(1, 19))  # 18 episodes on 16 envs: two envs run two
    assert shown == plain


def test_evaluate_names_the_robot_and_the_randomize_file(tmp_path):
    randomize = tmp_path / "randomize.yaml"
    randomize.write_text("ground_friction: [0.8, 1.2]\n")
    robot = "robots/yaw-pitch-16.yaml"
    done = run("evaluate", "baseline:steer", "--robot", robot, "--episodes", 1, "--randomize", randomize)
    assert done.returncode == 0, done.stderr
    rows = dict(re.split(r"\s{2,}", line, maxsplit=1) for line in done.stdout.splitlines() if "  " in line)
    assert f"robot {robot}" in rows["env"]
    assert rows["randomize"].startswith(str(randomize))
    out = tmp_path / "r.json"
    args = ("--robot", robot, "--episodes", 1, "--json", out, "--no-progress")
    done = run("evaluate", "baseline:steer", *args)
    assert done.returncode == 0, done.stderr
    assert json.loads(out.read_text())["robot"] == robot


def test_the_robot_note_names_the_robot_that_runs(capsys):
    line = "m.safetensors: robot robots/r.yaml changed since training (r.yaml differs); "
    note([line + "the robot recorded in the model is used"], {"robot": "robots/r.yaml"})
    note([line + "the robot recorded in the model is used"], {"goal": [0, -10]})
    err = capsys.readouterr().err.splitlines()
    assert err[0] == f"note: {line}the robot file given, robots/r.yaml, is used, not the recorded one"
    assert err[1] == f"note: {line}the robot recorded in the model is used"


def test_sweep_display_piped_has_counts_and_time(capsys):
    pytest.importorskip("ray")
    from snakesim.sweeps.tune_runner import _Display

    display = _Display(2, True, False)
    display.set("a", "running")
    display.set("a", "done")
    display.result("a", {"timesteps": 10, "success_rate": 1.0})  # no new line when piped
    display.close()
    lines = capsys.readouterr().err.splitlines()
    assert lines[0].startswith("trials: 1 running, 0 done, 0 failed, 1 waiting (of 2), 0:00 elapsed")
    assert lines[1].startswith("trials: 0 running, 1 done, 0 failed, 1 waiting (of 2), 0:00 elapsed, about")
    assert len(lines) == 2


def test_import_snakesim_reaches_the_subpackages_lazily():
    code = (
        "import sys, snakesim\n"
        "heavy = [m for m in ('torch', 'ray', 'onnx', 'rerun', 'snakesim.runs') if m in sys.modules]\n"
        "assert not heavy, heavy\n"
        "assert callable(snakesim.runs.onnx.to_onnx) and callable(snakesim.agents.load_agent)\n"
        "assert snakesim.viewer.replay and snakesim.limits.LIMITS and 'runs' in dir(snakesim)\n"
        "try:\n    snakesim.nothing\nexcept AttributeError as e:\n    print(e)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "module 'snakesim' has no attribute 'nothing'"


def test_the_deploy_md_export_from_python_lands_where_git_ignores(tmp_path):
    import snakesim

    out = tmp_path / "out" / "policy.onnx"
    out.parent.mkdir()
    snakesim.runs.onnx.to_onnx(snakesim.agents.load_agent(str(REPO / "models/paper-10.safetensors")), out)
    assert out.stat().st_size > 1000
    # docs/deploy.md's exports write to out/, which git ignores.
    ignored = subprocess.run(["git", "check-ignore", "-q", "out/paper-10.onnx"], cwd=REPO)
    assert ignored.returncode == 0 or not (REPO / ".git").exists()
    assert "--onnx out/paper-10.onnx" in (REPO / "docs" / "deploy.md").read_text()
