"""A missing optional extra (snakesim.extras) is one line naming the pip install that fixes it: an
ImportError from Python, one `error:` line and exit 1 from the `snakesim` command. (Here the extras are
installed, so a missing module is simulated; test_wheel.py runs the real base install without them.)"""

from __future__ import annotations

import pytest
from snakesim import extras
from snakesim.cli import app as cli


@pytest.fixture
def sb3_missing(monkeypatch):
    monkeypatch.setitem(extras.EXTRAS, "sb3", (extras.EXTRAS["sb3"][0], ("snakesim_no_such_module",)))


def test_require_names_the_module_and_the_pip_install(sb3_missing):
    assert extras.missing("sb3") == "snakesim_no_such_module"
    assert not extras.available("sb3")
    with pytest.raises(ImportError) as caught:
        extras.require("sb3", "the SB3 trainer")
    assert isinstance(caught.value, extras.MissingExtra)
    assert caught.value.name == "snakesim_no_such_module"
    assert str(caught.value) == (
        "the SB3 trainer needs the Python module 'snakesim_no_such_module', which is not installed: "
        "pip install 'snakesim[sb3]'"
    )


def test_every_extra_is_installed_in_the_test_environment():
    assert {extra: extras.missing(extra) for extra in extras.EXTRAS} == {"sb3": None, "sweep": None}


def test_the_command_says_it_in_one_line(sb3_missing, capsys, tmp_path):
    code = cli.main(["train", "--trainer", "sb3", "--run-dir", str(tmp_path / "run")])
    out, err = capsys.readouterr()
    assert (code, out) == (1, "")
    assert err.splitlines() == [
        "snakesim train: error: the SB3 trainer (trainer: sb3; the default, native, needs no extra) needs "
        "the Python module 'snakesim_no_such_module', which is not installed: pip install 'snakesim[sb3]'"
    ]
    assert not (tmp_path / "run").exists()


def test_a_native_model_evaluates_without_the_sb3_extra(sb3_missing, capsys, repo):
    # --no-progress: stderr must hold nothing else (no word of the missing extra).
    code = cli.main(
        ["evaluate", str(repo / "models" / "goal-5.safetensors"), "--episodes", "2", "--no-progress"]
    )
    out, err = capsys.readouterr()
    assert (code, err) == (0, "")
    assert "native trainer" in out
