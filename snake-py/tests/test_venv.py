"""Each checkout's .venv/ imports that checkout's snakesim (scripts/setup, scripts/layer_venv.py).

The locked packages live in one environment shared by every checkout; an editable install there once
sent every checkout's `import snakesim` to whichever clone ran setup last (or to a deleted one).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
import snakesim

ROOT = Path(__file__).resolve().parents[2]
LAYER = ROOT / "scripts" / "layer_venv.py"


def test_snakesim_is_imported_from_this_checkout():
    if os.environ.get("PYTHONPATH"):
        pytest.skip("PYTHONPATH chooses the package here, not the environment")
    assert Path(snakesim.__file__).resolve().is_relative_to(ROOT / "snake-py" / "python")


def make_venv(path: Path) -> Path:
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(path)], check=True)
    return next(path.glob("lib/python3*/site-packages"))


def test_a_layered_venv_sees_the_shared_packages_and_runs_their_commands_itself(tmp_path):
    base, own = tmp_path / "shared", tmp_path / "checkout" / ".venv"
    base_site = make_venv(base)
    (base_site / "locked_pkg.py").write_text("VALUE = 42\n")
    # A .pth of the shared environment must run too (as setuptools' and others' do).
    (base_site / "extra.pth").write_text(str(tmp_path / "extra") + "\n")
    (tmp_path / "extra").mkdir()
    (tmp_path / "extra" / "extra_pkg.py").write_text("VALUE = 7\n")
    script = base / "bin" / "tool"
    script.write_text(f"#!{base}/bin/python3\nimport sys, locked_pkg\nprint(sys.prefix, locked_pkg.VALUE)\n")
    script.chmod(0o755)
    native = base / "bin" / "native-tool"
    native.write_bytes(b"\x7fELF not really a program")
    make_venv(own)

    done = subprocess.run(
        [sys.executable, str(LAYER), str(own), str(base)], capture_output=True, text=True, check=True
    )
    assert "2 commands" in done.stdout

    python = own / "bin" / "python"
    out = subprocess.run(
        [str(python), "-c", "import locked_pkg, extra_pkg; print(locked_pkg.VALUE + extra_pkg.VALUE)"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert out.stdout.strip() == "49"
    # The shared command, run from the checkout's venv, runs the checkout's interpreter.
    tool = own / "bin" / "tool"
    # (The venv's python is a link to the system's; the venv is known by the link's own path.)
    assert tool.read_text().splitlines()[0] == f"#!{own.resolve() / 'bin' / 'python'}"
    prefix, value = subprocess.run([str(tool)], capture_output=True, text=True, check=True).stdout.split()
    assert (Path(prefix).resolve(), value) == (own.resolve(), "42")
    assert (own / "bin" / "native-tool").resolve() == native.resolve()
    # The checkout's own files stay its own: layering never writes into the shared environment.
    assert not (base_site / "_snakesim_base.pth").exists()


def test_layering_refuses_what_is_not_a_venv(tmp_path):
    make_venv(tmp_path / "v")
    done = subprocess.run(
        [sys.executable, str(LAYER), str(tmp_path / "v"), str(tmp_path / "nothing")],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 1
    missing = tmp_path / "nothing"
    assert done.stderr.strip() == f"error: {missing} is not a virtual environment (no pyvenv.cfg)"


def test_layering_over_another_environment_drops_the_previous_ones_commands(tmp_path):
    """scripts/setup layers .venv/ over its environment, scripts/test over the larger test one (and back
    where the locks change): no command of the one before is left behind, the venv's own are kept."""
    small, large, own = tmp_path / "small", tmp_path / "large", tmp_path / "checkout" / ".venv"
    for base, names in ((small, ["maturin"]), (large, ["maturin", "pytest"])):
        make_venv(base)
        for name in names:
            (base / "bin" / name).write_text(f"#!{base}/bin/python3\nprint('{name}')\n")
    make_venv(own)
    (own / "bin" / "snakesim").write_text("#!/bin/sh\n")  # maturin develop's, not the layer's

    def layer(base: Path) -> None:
        subprocess.run([sys.executable, str(LAYER), str(own), str(base)], check=True, capture_output=True)

    layer(large)
    assert (own / "bin" / "pytest").is_file()
    layer(small)
    assert not (own / "bin" / "pytest").exists()
    assert (own / "bin" / "maturin").read_text().startswith(f"#!{own.resolve() / 'bin' / 'python'}")
    assert (own / "bin" / "snakesim").is_file() and (own / "bin" / "python").exists()
