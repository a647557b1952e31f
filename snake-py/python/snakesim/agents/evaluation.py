"""The evaluation protocol of ``snakesim evaluate``, the SB3 trainer's evaluations and the sweeps:
which episodes an agent runs (seeds, envs), and what is measured of each."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from snakesim.agents.protocol import Agent


def run_episodes(
    act: Any,
    env_kwargs: Mapping[str, Any],
    episodes: int,
    seed: int,
    restart: Any = None,
    progress: Callable[[int], object] | None = None,
) -> list[dict[str, Any]]:
    """Runs ``episodes`` episodes of ``act(obs_batch) -> actions`` in a batched env of its own, as
    snake-rl's ``evaluate::run_episodes_with`` (the native trainer's evaluations) does: up to 16
    episodes at once, env i seeded with ``seed + i`` (its later episodes continue its stream), so a
    seed gives the same episodes whatever the policy, listed in the episodes' order (env 0's, then env
    1's, ...), not the order they end in, so two policies' i-th episodes are one episode. Each is a
    dict: ``ret``, ``steps``, ``success``, ``seconds``, ``distance`` (m, start to end), ``path_length``
    (m), ``work`` (J), ``weight`` (N), ``speed`` (m/s), ``path_efficiency`` and ``cost_of_transport``
    (None where undefined), and under ``randomize`` ``physics`` (the episode's draws).
    ``restart(i)``, where given, hears that env i's episode ended (an actor with a clock per env
    restarts it). ``progress(done)``, where given, hears each counted episode's end with the number
    ended so far (1 to ``episodes``); the episodes are the same with or without it.
    """
    from snakesim import _core
    from snakesim.envs.config import action_array, env_config

    return _core.run_episodes(
        env_config(**env_kwargs), episodes, seed, lambda obs: action_array(act(obs)), restart, progress
    )


def summarize(episodes: list[dict[str, Any]]) -> dict[str, Any]:
    """Mean/std return, success rate (with its 95 % Wilson interval), mean steps and seconds to goal
    (successes only), mean speed, path efficiency and cost of transport (over the episodes that have
    them), mean length: snake-rl's ``evaluate::summarize``, as the native trainer's evaluations."""
    from snakesim import _core

    return _core.summarize(episodes)


def evaluate(
    agent: Agent,
    episodes: int,
    seed: int,
    deterministic: bool = True,
    progress: Callable[[int], object] | None = None,
) -> dict[str, Any]:
    """:func:`summarize` of ``episodes`` episodes of the agent, with the per-episode figures;
    ``progress`` as :func:`run_episodes`'s."""
    agent.restart()
    done = run_episodes(
        lambda obs: agent.act(obs, deterministic), agent.env_kwargs, episodes, seed, agent.restart, progress
    )
    out = summarize(done)
    shown = ("steps", "success", "seconds", "speed", "path_efficiency", "cost_of_transport")
    # Under `randomize`, each episode's draws ("physics"), to tell which physics cost its failures.
    shown += ("physics",) if done and "physics" in done[0] else ()
    out["per_episode"] = [{"return": e["ret"], **{key: e[key] for key in shown}} for e in done]
    return out
