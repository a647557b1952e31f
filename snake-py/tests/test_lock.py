"""requirements.lock and requirements-test.lock install from the package index alone, each package pinned
once (scripts/check_lock.py guards it)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CHECK = ROOT / "scripts" / "check_lock.py"


def run_check(*paths: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(CHECK), *map(str, paths)], capture_output=True, text=True)


def test_the_repository_locks_hold_only_index_pins():
    result = run_check()  # both locks, by default
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""


def test_a_package_pinned_in_both_locks_is_refused(tmp_path):
    base, test = tmp_path / "requirements.lock", tmp_path / "requirements-test.lock"
    base.write_text("# base\nnumpy==2.4.6\ntyping_extensions==4.16.0\n")
    test.write_text("torch==2.15.0\n\nTyping-Extensions==4.15.0\n")
    result = run_check(base, test)
    assert result.returncode == 1
    assert result.stderr.splitlines() == [
        f"error: {test}:3: typing-extensions is pinned again (first at {base}:3); the locks are installed "
        "together: pin each package once"
    ]


def test_a_local_path_is_refused_naming_the_line(tmp_path):
    lines = (ROOT / "requirements-test.lock").read_text().splitlines()
    index = next(i for i, line in enumerate(lines) if line.startswith("pybullet=="))
    lines[index] = "pybullet @ file:///tmp/pbw/pybullet-3.2.7-cp311-cp311-manylinux_2_17_x86_64.whl"
    bad = tmp_path / "requirements-test.lock"
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
