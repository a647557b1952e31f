"""The wheel for users (scripts/wheel): installed into a fresh venv without torch, run with a bare
environment (`env -i`, PATH=/usr/bin:/bin), with Bullet inside it, and bit for bit the dev build.

The wheel is built by `bash scripts/wheel` into a temporary directory (or taken from $SNAKESIM_WHEEL).
Its dependencies come from the package index, held to requirements.lock's versions (pip's cache
makes that quick after scripts/setup). Everything is removed at the end.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BARE_PATH = "/usr/bin:/bin"

# A tiny native run (as test_native.py's TINY): rollouts of 4 envs x 128 steps, a second or two.
TINY_TRAIN = [
    "--joints", "3", "--n-envs", "4", "--timesteps", "2048", "--eval-freq", "1024", "--eval-episodes", "2",
    "--threads", "2", "--set", "ppo.n_steps=128", "--set", "ppo.batch_size=64", "--set", "ppo.n_epochs=2",
    "--set", "env.max_episode_steps=200", "--no-progress",
]  # fmt: skip

# The physics of a short episode of each env as one hash: observations, rewards and flags of fixed
# actions from a fixed seed (a gait-like sine on every joint).
FINGERPRINT = """
import hashlib, json, sys
import gymnasium, numpy as np, snakesim
out = {"module": snakesim.__file__}
for env_id, joints in (("snakesim/Snake-v0", 5), ("snakesim/SnakeGoal-v0", 10)):
    env = gymnasium.make(env_id, joints=joints)
    digest = hashlib.sha256()
    obs, _ = env.reset(seed=7)
    digest.update(obs.tobytes())
    for t in range(300):
        action = np.sin(0.1 * t + np.arange(env.action_space.shape[0])).astype(np.float32)
        obs, reward, terminated, truncated, _ = env.step(action)
        digest.update(obs.tobytes() + np.float64(reward).tobytes() + bytes([terminated, truncated]))
        if terminated or truncated:
            obs, _ = env.reset()
    out[env_id] = digest.hexdigest()
print(json.dumps(out))
"""


def _run(argv, *, env=None, cwd=None, check=True) -> subprocess.CompletedProcess[str]:
    done = subprocess.run([str(a) for a in argv], env=env, cwd=cwd, capture_output=True, text=True)
    if check and done.returncode != 0:
        raise AssertionError(f"{argv} exited {done.returncode}:\n{done.stdout}\n{done.stderr}")
    return done


class Installed:
    """The wheel installed in a fresh venv; commands run there under `env -i`."""

    def __init__(self, root: Path, wheel: Path) -> None:
        self.root = root
        self.wheel = wheel
        self.venv = root / "venv"
        self.work = root / "work"
        self.work.mkdir()

    def bare(self, command: str, *args, check=True) -> subprocess.CompletedProcess[str]:
        """The venv's ``command`` with no inherited variables (only PATH=/usr/bin:/bin), in work/."""
        program = self.venv / "bin" / command
        return _run(["env", "-i", f"PATH={BARE_PATH}", program, *args], cwd=self.work, check=check)

    @property
    def site_packages(self) -> Path:
        (found,) = self.venv.glob("lib/python3*/site-packages")
        return found


@pytest.fixture(scope="module")
def installed():
    with tempfile.TemporaryDirectory(prefix="snakesim-wheel-") as tmp:
        root = Path(tmp)
        given = os.environ.get("SNAKESIM_WHEEL")
        if given:
            wheel = Path(given)
        else:
            _run(["bash", ROOT / "scripts" / "wheel", "--out", root / "dist"])
            (wheel,) = (root / "dist").glob("snakesim-*.whl")
        inst = Installed(root, wheel)
        _run([sys.executable, "-m", "venv", inst.venv])
        _run([inst.venv / "bin" / "pip", "install", "-q", "--disable-pip-version-check", wheel,
              "-c", ROOT / "requirements.lock"])  # fmt: skip
        yield inst


def test_the_wheel_is_manylinux_abi3_with_bullet_inside(installed):
    assert re.fullmatch(r"snakesim-[^-]+-cp311-abi3-manylinux_2_\d+_x86_64\.whl", installed.wheel.name)
    libs = sorted(p.name for p in (installed.site_packages / "snakesim.libs").iterdir())
    assert [re.sub(r"-[0-9a-f]{8}\.so", ".so", name) for name in libs] == [
        "libBulletCollision-float64.so.3.24",
        "libBulletDynamics-float64.so.3.24",
        "libLinearMath-float64.so.3.24",
    ]


def test_ldd_finds_every_bullet_library_inside_the_wheel(installed):
    libs = installed.site_packages / "snakesim.libs"
    (module,) = (installed.site_packages / "snakesim").glob("_core*.so")
    for binary in [module, *libs.iterdir()]:
        out = _run(["env", "-i", f"PATH={BARE_PATH}", "ldd", binary]).stdout
        assert "not found" not in out, out
        bullet = [line for line in out.splitlines() if re.search(r"Bullet|LinearMath", line)]
        assert bullet or binary.name.startswith("libLinearMath"), out
        for line in bullet:
            resolved = Path(line.split("=>")[1].split("(")[0].strip())
            assert resolved.resolve().parent == libs.resolve(), line


def test_the_base_install_has_no_torch_and_says_which_extra_is_missing(installed):
    probe = (
        "import importlib.util as u, snakesim\n"
        "print([m for m in ('torch', 'stable_baselines3', 'ray', 'optuna') if u.find_spec(m)])\n"
        "print('SnakeVecEnv' in snakesim.__all__)\n"
        "try:\n    snakesim.SnakeVecEnv\nexcept ImportError as e:\n    print(type(e).__name__, e)\n"
    )
    lines = installed.bare("python", "-c", probe).stdout.splitlines()
    assert lines == [
        "[]",
        "False",
        "MissingExtra snakesim.SnakeVecEnv (Stable-Baselines3's VecEnv) needs the Python module "
        "'stable_baselines3', which is not installed: pip install 'snakesim[sb3]'",
    ]
    config = ROOT / "snake-py" / "configs" / "goal-5.yaml"
    (installed.work / "space.yaml").write_text("ppo:\n  learning_rate: {loguniform: [0.0001, 0.001]}\n")
    for argv, extra in (
        (["train", "--trainer", "sb3", "--run-dir", "sb3-run"], "sb3"),
        (["sweep", config, "--out", "sweep"], "sweep"),
        (["search", config, "--space", "space.yaml", "--trials", "1", "--out", "search"], "sweep"),
    ):
        done = installed.bare("snakesim", *argv, check=False)
        assert done.returncode == 1, done
        assert done.stdout == ""
        (line,) = done.stderr.splitlines()
        assert line.startswith(f"snakesim {argv[0]}: error: "), line
        assert line.endswith(f"pip install 'snakesim[{extra}]'"), line
    assert not (installed.work / "sb3-run").exists()


def test_the_installed_package_is_the_dev_build_bit_for_bit(installed):
    """The same physics from the wheel (bundled libraries, bare environment) as from the checkout."""
    wheel = json.loads(installed.bare("python", "-c", FINGERPRINT).stdout)
    dev = json.loads(_run([sys.executable, "-c", FINGERPRINT]).stdout)
    assert Path(wheel.pop("module")).is_relative_to(installed.site_packages)
    assert Path(dev.pop("module")).is_relative_to(ROOT)
    assert wheel == dev


def _model(path: Path) -> tuple[dict[str, str], dict[str, str]]:
    """A native model file's metadata and a hash of each tensor."""
    from safetensors import safe_open

    with safe_open(str(path), "np") as f:
        tensors = {key: hashlib.sha256(f.get_tensor(key).tobytes()).hexdigest() for key in f.keys()}
        return f.metadata(), tensors


def test_native_training_evaluation_plot_and_replay_run_from_the_wheel(installed, tmp_path):
    model = ROOT / "models" / "goal-5.safetensors"
    installed.bare("snakesim", "train", *TINY_TRAIN, "--run-dir", "run")
    run = installed.work / "run"
    assert (run / "model.safetensors").is_file()
    # The same run from the checkout's build: the same weights and metadata. (Not the same bytes: the
    # order of the header's metadata keys varies from run to run.)
    _run([sys.executable, "-m", "snakesim", "train", *TINY_TRAIN, "--run-dir", tmp_path / "run"])
    assert _model(run / "model.safetensors") == _model(tmp_path / "run" / "model.safetensors")
    evaluations = [
        [line.rsplit(",", 1)[0] for line in (d / "evaluations.csv").read_text().splitlines()]  # no wall_time
        for d in (run, tmp_path / "run")
    ]
    assert evaluations[0] == evaluations[1] and len(evaluations[0]) == 3

    evaluate = ["evaluate", model, "--episodes", "4", "--json", "-"]
    report = json.loads(installed.bare("snakesim", *evaluate).stdout)
    assert report["episodes"] == 4 and report["sb3_version"] == "native"
    assert report == json.loads(_run([sys.executable, "-m", "snakesim", *evaluate]).stdout)

    installed.bare("snakesim", "plot", "run", "--out", "curves.png")
    done = installed.bare(
        "snakesim",
        "replay",
        model,
        "--seconds",
        "2",
        "--deterministic",
        "--out",
        "motion.png",
        "--rrd",
        "ep.rrd",
    )
    assert "wrote motion.png" in done.stdout
    for name in ("curves.png", "motion.png", "ep.rrd"):
        assert (installed.work / name).stat().st_size > 1000, name


def test_the_lock_pins_every_dependency_of_the_package():
    """What the base install pulls is what scripts/setup installs; the extras are in the test lock."""
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    project = tomllib.loads((ROOT / "snake-py" / "pyproject.toml").read_text())["project"]

    def names(path: Path) -> set[str]:
        lines = [line.split("==")[0] for line in path.read_text().splitlines() if "==" in line]
        return {re.sub(r"[-_.]+", "-", line.split("[")[0]).lower() for line in lines}

    def requirement(text: str) -> str:
        return re.sub(r"[-_.]+", "-", re.match(r"[A-Za-z0-9._-]+", text).group(0)).lower()

    base = names(ROOT / "requirements.lock")
    test = names(ROOT / "requirements-test.lock")
    assert {requirement(r) for r in project["dependencies"]} <= base
    for extra, requirements in project["optional-dependencies"].items():
        assert {requirement(r) for r in requirements} <= base | test, extra
    assert "torch" not in base and "stable-baselines3" not in base
    assert shutil.which("env") and shutil.which("ldd")
