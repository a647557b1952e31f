"""``snakesim evaluate``: the figures of an agent (or a baseline) over unseen episodes."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from snakesim.cli.args import (
    agent_options,
    baseline_env_options,
    episodes,
    goal,
    load_agent,
    progress_options,
)
from snakesim.cli.errors import UserError, check_writable
from snakesim.envs.config import file_label
from snakesim.files import write_atomically
from snakesim.runs.progress import Progress


def env_line(agent) -> str:
    """The evaluated env in words: task, body, joints, world."""
    kwargs = agent.env_kwargs
    task = kwargs.get("task")
    terrain = kwargs.get("terrain") or {}
    if task is None:
        task = "pegs" if terrain.get("pegs") else "rough" if terrain.get("rough") else None
    body = f"robot {file_label(kwargs['robot'])}" if kwargs.get("robot") else f"preset {kwargs['preset']}"
    prefix = "" if task is None else f"task {task}, "
    world = f", world {file_label(kwargs['world'])}" if kwargs.get("world") else ""
    return f"{prefix}{agent.joints} joints, {body}{world}"


def env_file(value) -> str | None:
    """The robot or world file the evaluation ran, for the JSON: its path, or the path of the model's
    record of it followed by `` (as recorded in the model)``; None for none."""
    return None if not value else file_label(value)


def cmd_evaluate(args: argparse.Namespace) -> int:
    from snakesim.agents.evaluation import evaluate

    outputs = [] if args.json in (None, "-") else [(args.json, "--json")]
    for path, what in outputs:
        check_writable(path, what)
    agent = load_agent(args, outputs)
    with Progress(args.episodes, "episodes", "evaluate", args.progress) as progress:
        result = evaluate(
            agent, args.episodes, args.seed, deterministic=not args.stochastic, progress=progress.update
        )
    report = {
        "model": agent.path,
        "arch": agent.arch,
        "joints": agent.joints,
        "preset": agent.env_kwargs["preset"],
        "robot": env_file(agent.env_kwargs.get("robot")),
        "world": env_file(agent.env_kwargs.get("world")),
        "sb3_version": agent.sb3_version,
        "trained_timesteps": agent.num_timesteps,
        "seed": args.seed,
        "deterministic": not args.stochastic,
        "randomize": agent.env_kwargs.get("randomize"),
        "randomize_file": args.randomize,
        **result,
    }
    text = json.dumps(report, indent=2) + "\n"
    if args.json == "-":
        sys.stdout.write(text)
        return 0
    if args.json is not None:
        try:
            write_atomically(args.json, lambda tmp: Path(tmp).write_text(text))
        except OSError as error:
            raise UserError(f"cannot write --json {args.json}: {error.strerror or error}") from None
    steps = report["mean_steps_to_goal"]
    seconds = report["mean_seconds_to_goal"]
    mode = "stochastic" if args.stochastic else "deterministic"
    trainer, label = agent.trainer, agent.network
    low, high = report["success_rate_ci95"]

    def optional(value: float | None, unit: str = "") -> str:
        return "-" if value is None else f"{value:.3f}{unit}"

    rows = [
        ("model", f"{agent.path} ({label}, {trainer})"),
        ("env", env_line(agent)),
        *([("randomize", f"{args.randomize} (physics drawn per episode)")] if args.randomize else []),
        (
            "episodes",
            f"{report['episodes']} (seed {args.seed}, {mode})",
        ),
        ("success rate", f"{report['success_rate']:.3f} (95 % interval {low:.3f}-{high:.3f})"),
        ("mean return", f"{report['mean_return']:.1f} ± {report['std_return']:.1f}"),
        ("mean steps to goal", "-" if steps is None else f"{steps:.1f} ({seconds:.2f} s)"),
        ("mean speed", f"{report['mean_speed']:.3f} m/s"),
        ("path efficiency", optional(report["mean_path_efficiency"])),
        ("cost of transport", optional(report["mean_cost_of_transport"])),
    ]
    width = max(len(name) for name, _ in rows)
    for name, value in rows:
        print(f"{name:<{width}}  {value}")
    if args.json is not None:
        print(f"wrote {args.json}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser(
        "evaluate",
        help="success rate, return, steps to goal, speed, path efficiency and cost of transport of an agent",
    )
    agent_options(p)
    p.add_argument(
        "--goal",
        type=goal,
        metavar="X,Y",
        help="a fixed goal instead of the agent's task's (e.g. 0,-10: the paper's task)",
    )
    baseline_env_options(p)
    p.add_argument(
        "--randomize",
        metavar="FILE",
        help="evaluate under randomized physics: a YAML mapping of parameter to [low, high], the env "
        "keyword randomize's (replaces the agent's own; docs/guide.md, 'Randomized physics')",
    )
    p.add_argument("--episodes", type=episodes, default=100, help="episodes (default 100)")
    p.add_argument(
        "--stochastic", action="store_true", help="sample actions instead of the deterministic policy"
    )
    p.add_argument(
        "--json", metavar="FILE", help="also write the results as JSON (- : print only JSON to stdout)"
    )
    progress_options(p, "episode")
    p.set_defaults(func=cmd_evaluate)
