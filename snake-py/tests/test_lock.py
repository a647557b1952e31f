"""requirements.lock installs from the package index alone (scripts/check_lock.py guards it)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CHECK = ROOT / "scripts" / "check_lock.py"


def run_check(path: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(CHECK), str(path)], capture_output=True, text=True)


def test_the_repository_lock_holds_only_index_pins():
    result = run_check(ROOT / "requirements.lock")
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""


def test_a_local_path_is_refused_naming_the_line(tmp_path):
    lines = (ROOT / "requirements.lock").read_text().splitlines()
    index = next(i for i, line in enumerate(lines) if line.startswith("pybullet=="))
    lines[index] = "pybullet @ file:///tmp/pbw/pybullet-3.2.7-cp311-cp311-manylinux_2_17_x86_64.whl"
    bad = tmp_path / "requirements.lock"
    bad.write_text("\n".join(lines) + "\n")
    result = run_check(bad)
    assert result.returncode == 1
    errors = result.stderr.splitlines()
    assert len(errors) == 1
    assert f"{bad}:{index + 1}:" in errors[0]
    assert "pybullet @ file:///tmp/pbw" in errors[0]


def test_urls_editables_ranges_and_options_are_refused(tmp_path):
    bad = tmp_path / "requirements.lock"
    bad.write_text(
        "# a comment\n\nnumpy==2.4.6\nray[tune]==2.60.0\n"
        "-e ./snake-py\ntorch>=2\nhttps://example.invalid/x.whl\n--index-url https://x\ngymnasium\n"
    )
    result = run_check(bad)
    assert result.returncode == 1
    prefix = f"error: {bad}:"
    lines = result.stderr.splitlines()
    assert all(line.startswith(prefix) for line in lines), lines
    named = [line[len(prefix) :].split(":")[0] for line in lines]
    assert named == ["5", "6", "7", "8", "9"]
