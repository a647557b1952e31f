"""The docs describe the tree as it is: every path docs/architecture.md names exists, and the
experiments (experiments/, not run by any other test) still load: their configs parse as run
configurations and their scripts import."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest
from snakesim.runs import config as runconfig

REPO = Path(__file__).resolve().parents[2]
ARCHITECTURE = REPO / "docs" / "architecture.md"
EXPERIMENTS = REPO / "experiments"

#: A file path in backticks: a folder and a name with one of these extensions, no spaces.
PATH = re.compile(r"`([A-Za-z0-9_.*-]+(?:/[A-Za-z0-9_.*-]+)+\.(?:rs|py|pyi|h|cpp|toml|lock|md|yaml))`")


def named_paths(text: str) -> list[str]:
    return sorted(set(PATH.findall(text)))


def test_the_pattern_finds_paths_and_leaves_other_code_alone():
    text = "`snake-core/src/env.rs`, `tests/reference/*.py`, `snake_rl::config`, `a.rs`, `x y/z.py`"
    assert named_paths(text) == ["snake-core/src/env.rs", "tests/reference/*.py"]


def test_architecture_names_the_crates_modules():
    # The page names its files in the checked form; if it stopped, the check below would pass vacuously.
    paths = named_paths(ARCHITECTURE.read_text())
    for root in ("snake-core/src/", "snake-rl/src/", "snake-cli/src/", "snake-py/src/", "snake-py/python/"):
        assert any(p.startswith(root) for p in paths), root


@pytest.mark.parametrize("path", named_paths(ARCHITECTURE.read_text()))
def test_every_path_architecture_names_exists(path):
    if "*" in path:
        assert list(REPO.glob(path)), f"docs/architecture.md names {path}, which matches no file"
    else:
        assert (REPO / path).exists(), f"docs/architecture.md names {path}, which does not exist"


def test_each_experiment_has_a_readme_with_its_question_command_and_commit():
    folders = sorted(p for p in EXPERIMENTS.iterdir() if p.is_dir() and not p.name.startswith((".", "_")))
    assert folders
    index = (EXPERIMENTS / "README.md").read_text()
    for folder in folders:
        readme = (folder / "README.md").read_text()
        assert f"{folder.name}/" in index, folder.name
        assert "**Question.**" in readme and "## Reproduce" in readme, folder.name
        assert re.search(r"last run at commit [0-9a-f]{7}|smoke-tested by", readme), folder.name


@pytest.mark.parametrize("path", sorted(EXPERIMENTS.rglob("*.yaml")), ids=lambda p: p.name)
def test_experiment_configs_are_valid_run_configurations(path):
    resolved = runconfig.resolve(runconfig.load_yaml(path))
    assert resolved["env"]["task"]


@pytest.mark.parametrize("path", sorted(EXPERIMENTS.rglob("*.py")), ids=lambda p: p.name)
def test_experiment_scripts_import(path, monkeypatch):
    # As `python experiments/X/script.py` runs them: their own folder first on sys.path.
    monkeypatch.syspath_prepend(str(path.parent))
    spec = importlib.util.spec_from_file_location(f"experiment_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert callable(module.main)
    # A script's default config lies beside it (found from its own path, not the working directory).
    assert not hasattr(module, "CONFIG") or module.CONFIG.is_file(), module.CONFIG
