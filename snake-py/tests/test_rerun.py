"""Rerun recordings: read back with Rerun's own API and checked against the trajectory CSV of the same
run, the episodes of an agent against a replay without the logger, the live wrapper, the web viewer in
a real (headless) browser, and bad input."""

from __future__ import annotations

import csv
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import _chromium
import gymnasium
import numpy as np
import pytest
import rerun as rr
from snakesim import SnakeGoalEnv
from snakesim.agents.loading import load_agent
from snakesim.cli import app as cli
from snakesim.envs.wrappers import RerunLogger
from snakesim.viewer import replay
from snakesim.viewer.recording import MAX_SECONDS, RecordingError, read_trace

REPO = Path(__file__).resolve().parents[2]
DT = 1 / 240


@pytest.fixture(scope="module")
def snake_cli() -> Path:
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    exe = target / "release" / "snake-cli"
    if not exe.is_file():
        pytest.skip(f"{exe} is not built (cargo build --release -p snake-cli)")
    return exe


def _env() -> dict[str, str]:
    """The environment of a child process: this package first on the path (a checkout's own)."""
    env = dict(os.environ)
    package = str(Path(cli.__file__).resolve().parents[2])
    env["PYTHONPATH"] = os.pathsep.join(p for p in (package, env.get("PYTHONPATH")) if p)
    env["SNAKESIM_PYTHON"] = sys.executable
    return env


def read_rrd(path: Path) -> dict[str, dict]:
    """Every entity of the file's recording: its static values and its rows, with Rerun's reader."""
    reader = rr.chunk.RrdReader(path)
    assert len(reader.recordings()) == 1
    entities: dict[str, dict] = {}
    for chunk in reader.stream():
        entity = entities.setdefault(chunk.entity_path, {"static": {}, "rows": []})
        data = chunk.to_record_batch().to_pydict()
        data.pop("rerun.controls.RowId", None)
        if chunk.is_static:
            entity["static"].update({k: v[0] for k, v in data.items()})
        else:
            keys = list(data)
            entity["rows"] += [dict(zip(keys, values)) for values in zip(*data.values())]
    for entity in entities.values():
        entity["rows"].sort(key=lambda row: row["step"])
    return entities


def _csv_rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _column(rows: list[dict], suffix: str) -> list:
    (key,) = [k for k in rows[0] if k.endswith(suffix)]
    return [row[key] for row in rows]


def _nanoseconds(value) -> int:
    return int(value.value) if hasattr(value, "value") else int(value)


# -- snake-cli run --rrd: against the trajectory CSV of the same run -----------------------------------
@pytest.fixture(scope="module")
def gait_run(snake_cli, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("gait")
    result = subprocess.run(
        [snake_cli, "run", "--joints", "4", "--seconds", "2", "--output", out / "traj.csv"]
        + ["--trace", out / "trace.csv", "--rrd", out / "gait.rrd"],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert f"wrote {out / 'gait.rrd'}" in result.stdout
    return out


def test_gait_recording_holds_every_physics_step_of_the_csv(gait_run):
    rows = _csv_rows(gait_run / "traj.csv")
    entities = read_rrd(gait_run / "gait.rrd")
    assert {"/world", "/world/ground", "/world/snake", "/world/head_path/0", "/config"} <= set(entities)
    assert {f"/joints/{q}" for q in ("angle", "target", "velocity", "torque")} <= set(entities)
    assert "/world/goal" not in entities  # a gait run has no goal

    snake = entities["/world/snake"]
    assert len(snake["rows"]) == len(rows) == 480
    assert [row["step"] for row in snake["rows"]] == [int(r["step"]) for r in rows]
    # The time timeline is the simulated time of each step, to the nanosecond.
    assert [_nanoseconds(row["time"]) for row in snake["rows"]] == [round(float(r["t"]) * 1e9) for r in rows]
    # The static part: 5 boxes of half extent 0.25, the head first and coloured apart.
    half = np.array(_column([snake["static"]], "half_sizes")[0])
    assert half.shape == (5, 3) and np.all(half == np.float32(0.25))
    # Positions and quaternions are float32 in Rerun: the CSV's doubles rounded once.
    centers = np.array(_column(snake["rows"], "centers"))
    quats = np.array(_column(snake["rows"], "quaternions"))
    assert centers.shape == (480, 5, 3) and quats.shape == (480, 5, 4)
    base = np.array([[float(r[f"base_{k}"]) for k in ("x", "y", "z")] for r in rows])
    base_q = np.array([[float(r[f"base_q{k}"]) for k in "xyzw"] for r in rows])
    assert np.array_equal(centers[:, 0], base.astype(np.float32))
    assert np.array_equal(quats[:, 0], base_q.astype(np.float32))
    # The cubes follow one another 0.51 m apart.
    gaps = np.linalg.norm(np.diff(centers, axis=1), axis=2)
    assert np.allclose(gaps, 0.51, atol=5e-3)
    # Joint angles are float64 scalars: the CSV's exact values.
    angles = np.array(_column(entities["/joints/angle"]["rows"], "scalars"))
    q = np.array([[float(r[f"q{j}"]) for j in range(4)] for r in rows])
    assert angles.shape == (480, 4) and np.array_equal(angles, q)
    # Torques, velocities and targets are the trace's.
    _, blocks = read_trace(gait_run / "trace.csv")
    trace = next(blocks)
    for name, field in (("torque", "torques"), ("velocity", "velocities"), ("target", "targets")):
        values = np.array(_column(entities[f"/joints/{name}"]["rows"], "scalars"))
        assert np.array_equal(values, getattr(trace, field)), name
    torques = np.array(_column(entities["/joints/torque"]["rows"], "scalars"))
    assert np.abs(torques).max() <= 10.0 and np.abs(torques).max() > 0.1  # the motor force limit
    # The head's path: sampled every 0.05 s (41 points: one piece), ending at the head.
    path = entities["/world/head_path/0"]["rows"]
    assert [row["step"] for row in path] == [1] + list(range(12, 481, 12))
    last = np.array(_column(path, "strips")[-1][0])
    assert len(last) == 41 and np.array_equal(last[-1], base[-1].astype(np.float32))
    assert np.array_equal(last, base[[0] + list(range(11, 480, 12))].astype(np.float32))
    # The configuration as text.
    (text,) = _column([entities["/config"]["static"]], "text")[0]
    config = json.loads(text.split("```json\n")[1].split("```")[0])
    assert config["joints"] == 4 and config["steps"] == 480 and config["source"] == "snake-cli run"


def test_the_trace_matches_the_trajectory_csv(gait_run):
    rows = _csv_rows(gait_run / "traj.csv")
    meta, blocks = read_trace(gait_run / "trace.csv", rows=96)
    trace = list(blocks)
    assert [len(t) for t in trace] == [96] * 5  # whole blocks: the end is found without a last, empty one
    steps = np.concatenate([t.steps for t in trace])
    poses = np.concatenate([t.poses for t in trace])
    assert list(steps) == [int(r["step"]) for r in rows]
    base = np.array(
        [
            [float(r[k]) for k in ("base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw")]
            for r in rows
        ]
    )
    assert np.array_equal(poses[:, 0], base)  # the exact bits: both are the simulator's doubles
    assert meta["joints"] == 4 and meta["gait"]["amplitude"] == 0.4


# -- snakesim replay --rrd: an agent's episodes -------------------------------------------------------
@pytest.fixture(scope="module")
def agent():
    return load_agent(str(REPO / "models" / "goal-5.safetensors"))


def test_replay_records_episodes_one_after_another(agent, tmp_path, capsys):
    out = tmp_path / "replay.rrd"
    argv = ["replay", REPO / "models" / "goal-5.safetensors", "--rrd", out, "--episodes", "2"]
    argv += ["--seconds", "1", "--seed", "7", "--deterministic"]
    assert cli.main([str(a) for a in argv]) == 0
    assert "recorded episode 2 (seed 8)" in capsys.readouterr().out
    entities = read_rrd(out)
    assert {"/world/goal", "/reward/total", "/reward/progress", "/distance_to_goal", "/episode"} <= set(
        entities
    )
    # Each episode: the reset's physics step, then 30 env steps of 8 physics steps (1 s at 30 Hz).
    snake = entities["/world/snake"]["rows"]
    assert [row["step"] for row in snake] == list(range(1, 2 * 241 + 1))
    # The same episodes replayed without the logger: the recording shows them as they are.
    act = lambda obs: agent.act(obs, True)  # noqa: E731
    centers = np.array(_column(snake, "centers"))
    rewards = np.array(_column(entities["/reward/total"]["rows"], "scalars"))[:, 0]
    reward_steps = [row["step"] for row in entities["/reward/total"]["rows"]]
    goals = _column(entities["/world/goal"]["rows"], "centers")
    for k, seed in enumerate((7, 8)):
        rec = replay.record(act, agent.env_kwargs, seconds=1, seed=seed)
        offset = 241 * k
        # The poses after each env step: rows 1, 9, 17, ... of the episode (steps 1 + 8 i).
        rows = offset + np.arange(0, 241, 8)
        assert np.array_equal(centers[rows], rec.poses[:, :, :3].astype(np.float32))
        assert reward_steps[30 * k : 30 * (k + 1)] == list(offset + 1 + np.arange(8, 241, 8))
        assert np.isclose(rewards[30 * k : 30 * (k + 1)].sum(), rec.ret, rtol=0, atol=1e-9)
        assert np.allclose(goals[k][0][:2], rec.goal, atol=1e-5)


def test_the_wrapper_changes_nothing_and_stops_at_its_limit(tmp_path):
    plain = SnakeGoalEnv(joints=3)
    recording = rr.RecordingStream("snakesim-test")
    recording.save(tmp_path / "live.rrd")
    logged = RerunLogger(SnakeGoalEnv(joints=3), recording, max_seconds=325 * DT)
    rng = np.random.default_rng(0)
    for seed in (0, 1):
        a, _ = plain.reset(seed=seed)
        b, _ = logged.reset(seed=seed)
        assert np.array_equal(a, b)
        for _ in range(20):
            action = rng.uniform(-1, 1, 3).astype(np.float32)
            sa, sb = plain.step(action), logged.step(action)
            assert np.array_equal(sa[0], sb[0]) and sa[1:4] == sb[1:4]
    # 2 x (1 + 20 x 8) = 322 physics steps fit in 325; the third episode's reset too, its first step
    # not: logging stops, the env goes on.
    with pytest.warns(UserWarning, match="stopped logging: the recording is full"):
        logged.reset(seed=2)
        logged.step(np.zeros(3, np.float32))
    logged.close()
    recording.disconnect()
    steps = [row["step"] for row in read_rrd(tmp_path / "live.rrd")["/world/snake"]["rows"]]
    assert steps == list(range(1, 2 * 161 + 2))
    with pytest.raises(TypeError, match="wraps a snakesim env"):
        RerunLogger(gymnasium.make("CartPole-v1"), recording)
    if rr.get_data_recording() is None:  # nothing from rerun.init in this process
        with pytest.raises(ValueError, match="no Rerun recording"):
            RerunLogger(gymnasium.make("snakesim/Snake-v0"))


def test_long_head_paths_are_logged_in_pieces(tmp_path):
    from snakesim.viewer.recording import PATH_PIECE, SnakeLog, Trace

    recording = rr.RecordingStream("snakesim-test")
    recording.save(tmp_path / "path.rrd")
    log = SnakeLog(recording, joints=1, dt=DT, half_extent=0.25, config={}, rewards=False, flush_rows=1000)
    k = 2 * 240 * 5 + 24  # 10.1 s: 203 samples
    steps = np.arange(1, k + 1)
    head = np.stack([np.cos(steps / 100), np.sin(steps / 100), np.full(k, 0.25)], axis=1)
    poses = np.zeros((k, 2, 7))
    poses[:, 0, :3] = head
    poses[:, :, 6] = 1
    joint = np.zeros((k, 1))
    for _ in range(2):
        log.start_episode()
        log.add_physics(Trace(steps, poses, joint, joint, joint, joint))
    log.flush()
    recording.disconnect()
    entities = read_rrd(tmp_path / "path.rrd")
    sampled = np.array([0] + list(range(11, k, 12)))
    assert len(sampled) == 203 > 2 * PATH_PIECE
    pieces = [np.array(_column(entities[f"/world/head_path/{i}"]["rows"], "strips")[-1][0]) for i in range(3)]
    assert [len(p) for p in pieces] == [100, 100, 5]  # each piece starts where the last one ended
    joined = np.concatenate([pieces[0], pieces[1][1:], pieces[2][1:]])
    assert np.array_equal(joined, head[sampled].astype(np.float32))
    # The second episode starts by clearing the first one's path, at its first step.
    assert [row["step"] for row in entities["/world/head_path"]["rows"]] == [k + 1]
    assert [row["step"] for row in entities["/world/snake"]["rows"]] == list(range(1, 2 * k + 1))


# -- the web viewer in a headless browser ---------------------------------------------------------------
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_web_viewer_shows_the_recording_in_chromium(gait_run, tmp_path):
    exe = _chromium.find()
    if exe is None:
        pytest.skip("chromium is not installed (bash scripts/setup installs Debian's chromium package)")
    web, grpc = _free_port(), _free_port()
    server = subprocess.Popen(
        [sys.executable, "-m", "snakesim", "view", gait_run / "gait.rrd", "--serve"]
        + ["--web-port", str(web), "--grpc-port", str(grpc)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=_env(),
    )
    browser = None
    try:
        line = server.stdout.readline()
        assert "serving Rerun's web viewer at http://127.0.0.1:" in line, line + server.stderr.read()
        url = line.split(" at ", 1)[1].split()[0]
        profile = tmp_path / "profile"
        profile.mkdir()
        browser = _chromium.Chromium(exe, profile)
        browser.page("Page.navigate", {"url": url})
        # The viewer's own copy of what it loaded (its JavaScript handle encodes the active recording).
        saved = None
        deadline = time.monotonic() + 90
        while time.monotonic() < deadline:
            size = browser.evaluate(
                "(() => { try { return window._handle ? window._handle.save_recording().length : -1 }"
                " catch (e) { return -2 } })()"
            )
            if size and size > 0:
                saved = browser.evaluate(
                    "(() => { const b = window._handle.save_recording(); let s = '';"
                    " for (let i = 0; i < b.length; i += 32768)"
                    "   s += String.fromCharCode(...b.subarray(i, i + 32768));"
                    " return btoa(s) })()"
                )
                viewer_file = _write_b64(tmp_path / "viewer.rrd", saved)
                if rr.chunk.RrdReader(viewer_file).recordings():  # none until the data has come in
                    entities = read_rrd(viewer_file)
                    if len(entities.get("/world/snake", {}).get("rows", [])) == 480:
                        break
            time.sleep(1)
        else:
            pytest.fail(f"the viewer did not load the recording: console {browser.console[-5:]}")
        assert {"/world/snake", "/world/ground", "/joints/angle", "/joints/torque", "/config"} <= set(
            entities
        )
        time.sleep(2)  # a few frames drawn
        shot = REPO / "out" / "rerun-web-viewer.png"
        shot.parent.mkdir(exist_ok=True)
        browser.screenshot(shot)
        pixels = _png_pixels(shot)
        assert pixels.shape[0] >= 600 and pixels.shape[1] >= 1000
        assert pixels.std() > 10, "the page is blank"
        # The head cube is drawn red (214, 32, 32) in the 3D view.
        red = (pixels[:, :, 0] > 150) & (pixels[:, :, 1] < 90) & (pixels[:, :, 2] < 90)
        assert red.sum() > 20, "no red head cube on the screenshot"
        assert not [m for m in browser.console if "panic" in m.lower()]
    finally:
        if browser is not None:
            browser.close()
        server.send_signal(signal.SIGTERM)  # as `kill` stops it
        try:
            _, err = server.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()
            server.communicate()
            raise
    assert server.returncode == 0, err
    # The server is gone with its ports.
    with socket.socket() as s:
        s.bind(("127.0.0.1", web))


def test_serve_stops_on_ctrl_c_and_leaves_nothing_behind(gait_run, tmp_path):
    # Served without --rrd: the recording lives in a temporary file until the server stops.
    web, grpc = _free_port(), _free_port()
    env = _env() | {"TMPDIR": str(tmp_path)}
    # SIGINT as a terminal sends it; the server must not inherit an ignored SIGINT (as a suite run as
    # a background job without job control would give it: it then never stopped).
    server = subprocess.Popen(
        [sys.executable, "-m", "snakesim", "convert", gait_run / "trace.csv"]
        + ["--serve", "--web-port", str(web), "--grpc-port", str(grpc)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        assert "recorded 480 physics steps of 4 joints" in server.stdout.readline()
        assert f"http://127.0.0.1:{web}/?url=" in server.stdout.readline()
        assert [p.name[:13] for p in tmp_path.iterdir() if p.name.startswith("snakesim-rrd")] == [
            "snakesim-rrd-"
        ]
        with socket.create_connection(("127.0.0.1", web), timeout=5):
            pass
    finally:
        server.send_signal(signal.SIGINT)
        try:
            _, err = server.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            server.terminate()  # its handler stops the Rerun server too: a failure leaves nothing running
            server.communicate(timeout=30)
            raise
    assert server.returncode == 0 and err == "", err
    for port in (web, grpc):
        with socket.socket() as s:
            s.bind(("127.0.0.1", port))
    assert not list(tmp_path.iterdir())  # the served temporary recording is gone


def _write_b64(path: Path, data: str) -> Path:
    import base64

    path.write_bytes(base64.b64decode(data))
    return path


def _png_pixels(path: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB")).astype(np.int32)


# -- bad input: one line, non-zero exit, nothing written ----------------------------------------------
def _one_line(capsys, argv, code=1) -> str:
    try:
        got = cli.main([str(a) for a in argv])
    except SystemExit as stop:
        got = stop.code
    _, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert got == code, err
    assert len(lines) == 1 and "error:" in lines[0] and "Traceback" not in err, err
    return lines[0]


MODEL = str(REPO / "models" / "goal-5.safetensors")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["replay", MODEL, "--rrd", "{tmp}/missing/x.rrd"], "directory {tmp}/missing does not exist"),
        (["replay", MODEL, "--rrd", "{tmp}/x.txt"], "expected a .rrd file"),
        (["replay", MODEL, "--rrd", "{tmp}/x.rrd", "--episodes", "1000"], "--episodes must be in [1, 100]"),
        (["replay", MODEL, "--out", "{tmp}/x.png", "--episodes", "2"], "--episodes applies to --rrd"),
        (["replay", MODEL], "give --out"),
        (["replay", MODEL, "--rrd", "{tmp}/x.rrd", "--episodes", "40"], "could exceed the 600 simulated"),
        (["replay", "baseline:steer", "--joints", "600", "--rrd", "{tmp}/x.rrd"], "joints"),
        (["convert", "{tmp}", "--rrd", "{tmp}/x.rrd"], "cannot read"),
        (["convert", REPO / "README.md", "--rrd", "{tmp}/x.rrd"], "is not a physics trace"),
        (["view", "{tmp}/nothing.rrd", "--serve"], "no such file"),
        (["view", REPO / "README.md", "--serve"], "not a Rerun recording"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(argv, message, tmp_path, capsys):
    argv = [str(a).format(tmp=tmp_path) for a in argv]
    assert message.format(tmp=tmp_path) in _one_line(capsys, argv)
    assert not any(tmp_path.iterdir())


def test_a_damaged_trace_is_one_line_and_writes_nothing(gait_run, tmp_path, capsys):
    lines = (gait_run / "trace.csv").read_text().splitlines(keepends=True)
    cut = tmp_path / "cut.csv"
    cut.write_text("".join(lines[:10]) + ",".join(lines[10].split(",")[:20]) + "\n")
    line = _one_line(capsys, ["convert", cut, "--rrd", tmp_path / "x.rrd"])
    assert "malformed rows in lines 3-11" in line and "changed from 53 to 20" in line
    garbled = tmp_path / "garbled.csv"
    garbled.write_text("".join(lines[:10]) + lines[10].replace(",", ",x", 1))
    assert "malformed rows in lines 3-11" in _one_line(
        capsys, ["convert", garbled, "--rrd", tmp_path / "x.rrd"]
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cut.csv", "garbled.csv"]


def test_an_unwritable_directory_is_one_line(tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    if os.access(locked, os.W_OK):
        pytest.skip("running as a user who can write anywhere")
    assert "is not writable" in _one_line(capsys, ["replay", MODEL, "--rrd", locked / "x.rrd"])


def test_spawn_without_a_display_is_one_line(gait_run, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    line = _one_line(capsys, ["replay", MODEL, "--spawn"])
    assert "needs a display" in line and "--serve" in line
    assert "needs a display" in _one_line(capsys, ["view", gait_run / "gait.rrd", "--spawn"])


def test_spawn_with_a_display_that_is_not_there_is_one_line(gait_run, capsys, monkeypatch):
    # The viewer opens its port, then fails to reach the X server: the command must say so, not
    # report success.
    free = next(n for n in range(99, 200) if not Path(f"/tmp/.X11-unix/X{n}").exists())
    monkeypatch.setenv("DISPLAY", f":{free}")
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    line = _one_line(capsys, ["view", gait_run / "gait.rrd", "--spawn"])
    assert "the Rerun viewer exited" in line


def test_serve_on_a_port_in_use_is_one_line(gait_run, capsys):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        line = _one_line(capsys, ["view", gait_run / "gait.rrd", "--serve", "--web-port", port])
        assert f"--web-port: port {port} on 127.0.0.1 is in use" in line
        line = _one_line(capsys, ["replay", MODEL, "--serve", "--grpc-port", port])
        assert f"--grpc-port: port {port} on 127.0.0.1 is in use" in line


def test_snake_cli_without_snakesim_is_one_line(snake_cli, tmp_path):
    env = _env() | {"SNAKESIM_PYTHON": str(tmp_path / "no-python")}
    result = subprocess.run(
        [snake_cli, "run", "--seconds", "0.1", "--rrd", tmp_path / "x.rrd"],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
    )
    assert result.returncode == 1
    assert result.stderr.count("\n") == 1 and "bash scripts/setup" in result.stderr, result.stderr
    assert not any(tmp_path.iterdir())


def test_snake_cli_refuses_a_recording_longer_than_the_limit(snake_cli, tmp_path):
    result = subprocess.run(
        [snake_cli, "run", "--seconds", str(MAX_SECONDS + 1), "--rrd", tmp_path / "x.rrd"],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=60,
    )
    assert result.returncode == 1 and "--rrd records at most 600" in result.stderr, result.stderr
    assert not any(tmp_path.iterdir())


def test_recording_errors_are_value_errors():
    assert issubclass(RecordingError, ValueError)


# -- snake-cli run --robot --rrd: links moved by their poses, shapes drawn as such --------------------
ROBOT_URDF = """<robot name="four-shapes">
  <link name="head"><collision><geometry><box size="0.2 0.1 0.1"/></geometry></collision></link>
  <link name="ball"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="can"><collision><origin xyz="0 0.1 0" rpy="1.5707963267948966 0 0"/>
    <geometry><cylinder radius="0.04" length="0.2"/></geometry></collision></link>
  <link name="pill"><inertial><origin xyz="0 0.02 0"/><mass value="0.5"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01"/></inertial>
    <collision><geometry><capsule radius="0.03" length="0.1"/></geometry></collision>
    <collision><origin xyz="0 0.1 0"/><geometry><box size="0.05 0.05 0.05"/></geometry></collision></link>
  <joint name="a" type="continuous"><parent link="head"/><child link="ball"/><origin xyz="0 0.15 0"/>
    <axis xyz="0 0 1"/><limit effort="5"/></joint>
  <joint name="b" type="revolute"><parent link="ball"/><child link="can"/><origin xyz="0 0.06 0"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="5"/></joint>
  <joint name="c" type="fixed"><parent link="can"/><child link="pill"/><origin xyz="0 0.25 0"/></joint>
</robot>
"""


def test_robot_recording_draws_each_link(snake_cli, tmp_path):
    urdf = tmp_path / "four.urdf"
    urdf.write_text(ROBOT_URDF)
    result = subprocess.run(
        [snake_cli, "run", "--robot", urdf, "--start=0,0,0.3,0", "--seconds", "1"]
        + ["--trace", tmp_path / "trace.csv", "--rrd", tmp_path / "robot.rrd"],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    meta, blocks = read_trace(tmp_path / "trace.csv")
    (trace,) = list(blocks)
    assert meta["parts"] == 4 and meta["joints"] == 2 and trace.poses.shape == (240, 4, 7)
    entities = read_rrd(tmp_path / "robot.rrd")
    kinds = {
        "/world/snake/link0/shape0": "half_sizes",
        "/world/snake/link1/shape0": "half_sizes",  # an ellipsoid
        "/world/snake/link2/shape0": "lengths",  # a cylinder
        "/world/snake/link3/shape0": "lengths",  # a capsule
        "/world/snake/link3/shape1": "half_sizes",
    }
    for path, component in kinds.items():
        assert any(k.endswith(component) for k in entities[path]["static"]), (path, entities[path]["static"])
    for i in range(4):
        rows = entities[f"/world/snake/link{i}"]["rows"]
        assert [row["step"] for row in rows] == list(range(1, 241))
        translations = np.array(_column(rows, "translation")).reshape(-1, 3)
        assert np.array_equal(translations, trace.poses[:, i, :3].astype(np.float32))
    # The cylinder stands along the link's y axis (its origin's rpy), 0.1 m ahead of the link frame.
    pose = meta["shapes"][2][0]["pose"]
    assert np.allclose(pose[:3], [0, 0.1, 0]) and np.allclose(np.abs(pose[3]), np.sqrt(0.5))


def test_an_amphibious_recording_draws_the_shore_and_the_water(snake_cli, tmp_path):
    """worlds/amphibious.yaml (docs/media.md, "Ground, then water"): the recording holds the shore (an
    obstacle) and the pool as the translucent box its region fills, from the world file's numbers."""
    result = subprocess.run(
        [snake_cli, "run", "--robot", REPO / "robots/mamba-10-amphibious.yaml", "--gait", "swim"]
        + ["--world", REPO / "worlds/amphibious.yaml", "--seconds", "1", "--rrd", tmp_path / "amph.rrd"],
        capture_output=True,
        text=True,
        env=_env(),
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    entities = read_rrd(tmp_path / "amph.rrd")
    assert "/world/obstacles/0" in entities and "/world/water/1" not in entities
    water = entities["/world/water/0"]["static"]
    (centers,) = [v for k, v in water.items() if k.endswith("centers")]
    (half,) = [v for k, v in water.items() if k.endswith("half_sizes")]
    # area [-10, -20, 10, -0.5], surface 0.25, depth 0.25
    assert np.allclose(centers, [[0.0, -10.25, 0.125]]) and np.allclose(half, [[10.0, 9.75, 0.125]])
    assert len(entities["/world/snake/link0"]["rows"]) == 240
