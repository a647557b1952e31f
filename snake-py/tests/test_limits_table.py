"""``snakesim.limits.LIMITS`` is built from Rust's tables (``snake_core::limits::ALL`` and the run
configuration's limits): every constant of snake-core/src/limits.rs and of snake-rl's config limits is
there, by the naming rule (``MAX_X`` is ``x``, a ``MIN_X``/``MAX_X`` pair or a ``(low, high)`` range is
``x_min`` and ``x_max``), with the value the Rust source gives it."""

import math
import re
from pathlib import Path

import pytest
from snakesim.limits import LIMITS

REPO = Path(__file__).resolve().parents[2]
SOURCES = (REPO / "snake-core/src/limits.rs", REPO / "snake-rl/src/config/limits.rs")
CONST = re.compile(r"^pub const (\w+): ([^=]+) = (.+);$", re.M)
#: The table itself.
SKIP = {"ALL"}


def rust_value(expr: str, known: dict[str, float]) -> float | tuple[float, ...]:
    """A constant's value from its Rust expression (literals, shifts, arithmetic, std's consts)."""
    text = re.sub(r"(?<=\d)_(?=\d)", "", expr)
    text = text.replace("std::f64::consts::", "").replace("u32::MAX", str(2**32 - 1))
    text = re.sub(r"\bas \w+", "", text)
    text = text.replace("[", "(").replace("]", ")")
    names = {"PI": math.pi, "TAU": math.tau, "FRAC_PI_2": math.pi / 2, **known}
    return eval(text, {"__builtins__": {}}, names)  # noqa: S307 - our own source's constant expressions


def key_of(name: str, names: set[str]) -> str:
    stem = re.sub(r"^(MAX|MIN)_", "", name).lower()
    paired = {f"MAX_{stem.upper()}", f"MIN_{stem.upper()}"} <= names
    return f"{stem}_{name[:3].lower()}" if paired else stem


@pytest.mark.parametrize("source", SOURCES, ids=lambda p: p.parent.name)
def test_every_rust_limit_is_in_limits(source):
    known: dict[str, float] = {}
    consts = CONST.findall(source.read_text(encoding="utf-8"))
    names = {name for name, _, _ in consts}
    checked = 0
    for name, _kind, expr in consts:
        if name in SKIP or "crate::" in expr or "snake_core::" in expr:
            continue  # defined elsewhere (the network's sizes, snake-core's MAX_ENVS)
        value = rust_value(expr, known)
        known[name] = value
        key = key_of(name, names)
        if isinstance(value, tuple):
            assert (LIMITS[f"{key}_min"], LIMITS[f"{key}_max"]) == value, name
        else:
            assert LIMITS[key] == value, (name, key)
            assert isinstance(LIMITS[key], float) == isinstance(value, float), (name, key)
        checked += 1
    assert checked > 10


def test_the_randomization_limits_are_there():
    """Those the hand-kept dict lacked: randomized physics' scales, latency and observation noise."""
    assert LIMITS["physics_scale_min"] == 0.01 and LIMITS["physics_scale_max"] == 100.0
    assert LIMITS["latency_steps"] == 32 and LIMITS["obs_noise"] == 10.0
    assert LIMITS["target_rows"] == 864_000
