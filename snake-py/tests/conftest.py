import fcntl
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]

# `bash scripts/test` runs pytest on every core (pytest-xdist: `-n <cores> --dist loadfile
# --no-loadscope-reorder`): each test file runs whole on one worker (its module fixtures made once, its
# tests in their order). Files that share something outside their tmp_path take a lock for the module
# (below), so that they never overlap: test_sweep.py's Ray head and test_sweep_local.py's checks of
# /tmp/ray and /tmp/snakesim-ray-*; test_doc_examples_more.py runs docs/sweeps.md's sweeps on a local
# Ray.
SHARED = {"test_sweep.py": "ray", "test_sweep_local.py": "ray", "test_doc_examples_more.py": "ray"}
# The slowest files first (seconds of a serial run on the 2-core machine, loaded: test_wheel 207 with a
# rebuild, test_tasks 180, test_goal 82, test_model_safety 57, test_writers 49, test_sweep 44,
# test_calibrate 44, test_rerun 37; the other 25 files 70 together), so that no long file starts last and
# leaves a core idle at the end; the rest keep their usual order.
SLOWEST_FIRST = [
    "test_wheel.py",
    "test_doc_examples.py",
    "test_doc_examples_more.py",
    "test_tasks.py",
    "test_goal.py",
    "test_model_safety.py",
    "test_writers.py",
    "test_sweep.py",
    "test_calibrate.py",
    "test_rerun.py",
]


@pytest.fixture(scope="session")
def repo() -> pathlib.Path:
    return REPO


@pytest.fixture(scope="module", autouse=True)
def _one_module_at_a_time_on_a_shared_resource(request, tmp_path_factory):
    """For the modules of SHARED: an exclusive lock, shared by the xdist workers of this run (and by
    other runs of this user), held while the module's tests and fixtures run."""
    resource = SHARED.get(request.path.name)
    if resource is None:
        yield
        return
    lock = tmp_path_factory.getbasetemp().parent / f"snakesim-tests-{resource}.lock"
    with open(lock, "a") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        yield


def pytest_collection_modifyitems(config, items):
    """On an xdist worker: the files of SLOWEST_FIRST first. Otherwise the order is left as collected."""
    if not hasattr(config, "workerinput"):
        return
    rank = {name: i for i, name in enumerate(SLOWEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.path.name, len(rank)))  # stable: the rest keep their order
