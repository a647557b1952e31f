"""A sweep on a local Ray (no --address) leaves nothing behind: Ray's session files go to a folder under
TMPDIR that is removed when the sweep ends, not to /tmp/ray. (Its own module: test_sweep.py's Ray head
must not be running beside it.)"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
import yaml

pytest.importorskip("ray")

TINY = {
    "trainer": "native",
    "joints": 3,
    "n_envs": 4,
    "timesteps": 1024,
    "eval_freq": 1024,
    "eval_episodes": 1,
    "checkpoint_freq": 1024,
    "threads": 1,
    "ppo": {"n_steps": 128, "batch_size": 64, "n_epochs": 1},
    "env": {"max_episode_steps": 100},
}


def _ray_folders() -> list[Path]:
    """Ray's default session folder and ours, where a long TMPDIR sends them (/tmp)."""
    ours = sorted(Path("/tmp").glob("snakesim-ray-*"))
    default = Path("/tmp/ray")
    return ours + (sorted(default.iterdir()) if default.is_dir() else [])


@pytest.mark.parametrize("short", [True, False], ids=["short TMPDIR", "TMPDIR too long for Ray's sockets"])
def test_a_local_sweep_leaves_no_ray_files(tmp_path, short):
    if short:
        scratch = Path(tempfile.mkdtemp(prefix="t", dir="/tmp"))
    else:
        scratch = tmp_path / ("long" * 12)
        scratch.mkdir()
    config = tmp_path / "tiny.yaml"
    config.write_text(yaml.safe_dump(TINY))
    before = _ray_folders()
    env = {**os.environ, "TMPDIR": str(scratch)}
    env.pop("RAY_ADDRESS", None)
    try:
        result = subprocess.run(
            [
                sys.executable,
                "-m",
                "snakesim",
                "sweep",
                str(config),
                "--seeds",
                "1",
                "--out",
                str(tmp_path / "sweep"),
            ],
            env=env,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert result.returncode == 0, result.stderr
        assert "1 trials on a local Ray" in result.stdout
        assert sorted(scratch.iterdir()) == []
    finally:
        if short:
            shutil.rmtree(scratch, ignore_errors=True)
    assert _ray_folders() == before
