"""Every limit on sizes, ranges and durations, as the Rust side defines them (snake-core's
``limits`` and snake-rl's run configuration): one table, read here and nowhere restated."""

from __future__ import annotations

from typing import Any

from snakesim import _core

#: Name -> limit (integers and floats), e.g. ``LIMITS["eval_episodes"]``.
LIMITS: dict[str, Any] = dict(_core.LIMITS)
