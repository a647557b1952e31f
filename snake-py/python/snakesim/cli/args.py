"""Argument types and option groups that several subcommands share."""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from snakesim.cli.errors import capped, one_line
from snakesim.envs.config import PRESETS
from snakesim.limits import LIMITS


class Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        self.exit(2, capped(f"{self.prog}: error: {one_line(message)} (see {self.prog} --help)") + "\n")


def int_at_least(minimum: int, maximum: int | None = None):
    """An argparse type: an integer (underscores allowed) of at least `minimum` (and at most
    `maximum`)."""

    def parse(text: str) -> int:
        try:
            value = int(text.replace("_", ""))
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"expected an integer >= {minimum}, got {value}")
        if maximum is not None and value > maximum:
            raise argparse.ArgumentTypeError(f"expected an integer <= {maximum}, got {value}")
        return value

    return parse


positive_int = int_at_least(1)
count = int_at_least(0)
seed = int_at_least(0, LIMITS["seed"])
threads = int_at_least(1, LIMITS["threads"])
episodes = int_at_least(1, LIMITS["eval_episodes"])


def seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text}")
    return value


def goal(text: str) -> tuple[float, float]:
    """X,Y in metres; the env checks the range."""
    parts = text.split(",")
    try:
        x, y = (float(v) for v in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y (two numbers), got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"expected finite X,Y, got {text!r}")
    return x, y


def agent_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "source",
        metavar="RUN_OR_MODEL",
        help="a run directory, a native model .safetensors, an SB3 model .zip (SB3 1.x or 2.x), or "
        "baseline:steer / baseline:gait (hand-made controllers of the goal task), baseline:sine / "
        "baseline:steered_sine (of the paper's env: --env paper)",
    )
    p.add_argument(
        "--joints", type=positive_int, help="for a bare .zip: the snake's joints (default: from the model)"
    )
    p.add_argument("--preset", choices=PRESETS, help="for a bare .zip: the robot preset (default paper)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the episodes (default 0)")
    p.add_argument("--torch-threads", type=threads, default=1, help="torch CPU threads (default 1)")


#: Gymnasium ids of the tasks a baseline runs in, by task name.
TASK_IDS = {
    "paper": "snakesim/Snake-v0",
    "goal": "snakesim/SnakeGoal-v0",
    "pegs": "snakesim/SnakePegs-v0",
    "rough": "snakesim/SnakeRough-v0",
    "swim": "snakesim/SnakeSwim-v0",
}


def task_name(text: str) -> str:
    """``--env``: a task name or its Gymnasium id, as the task name."""
    for name, env_id in TASK_IDS.items():
        if text in (name, env_id):
            return name
    raise argparse.ArgumentTypeError(
        f"unknown task {text!r} (expected one of: {', '.join(TASK_IDS)}, or {', '.join(TASK_IDS.values())})"
    )


def baseline_env_options(p: argparse.ArgumentParser) -> None:
    """The env a baseline runs in: a task, a robot, or exactly a model's env (``--robot`` also puts
    a model on another robot file)."""
    p.add_argument(
        "--env",
        type=task_name,
        metavar="TASK",
        help="for a baseline: the task, goal (default), paper, pegs, rough or swim, or its Gymnasium id "
        "(snakesim/SnakePegs-v0)",
    )
    p.add_argument(
        "--robot",
        metavar="FILE",
        help="a robot file: for a baseline instead of the cube snake; for a model in place of the robot "
        "it records (e.g. an edited one; it must fit the model's observation and action sizes)",
    )
    p.add_argument(
        "--env-from",
        metavar="MODEL",
        help="for a baseline: exactly the env recorded in MODEL (a native model or a run directory)",
    )
    p.add_argument(
        "--hold",
        type=held_wave,
        metavar="AMPLITUDE,FREQUENCY",
        help="for baseline:gait or baseline:steer: hold the wave's amplitude and frequency actions at these "
        "values, each in [-1, 1] (default 0,0: the middle of their ranges; 1 is the top)",
    )


def held_wave(text: str) -> tuple[float, float]:
    """``--hold``'s ``AMPLITUDE,FREQUENCY``: two numbers (their range is the core's to check)."""
    parts = text.split(",")
    try:
        if len(parts) != 2:
            raise ValueError
        amplitude, frequency = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected AMPLITUDE,FREQUENCY (two numbers), got {text!r}"
        ) from None
    return amplitude, frequency


def read_randomize(path: str | os.PathLike) -> dict:
    """The ``randomize`` mapping of a YAML file (parameter -> [low, high], the env keyword's), read
    with the bounded reader; UserError naming the file otherwise."""
    from snakesim.cli.errors import UserError
    from snakesim.runs.config import ConfigError, load_yaml

    try:
        return load_yaml(path, "--randomize")
    except ConfigError as error:
        raise UserError(str(error)) from None


#: The flag of each keyword argument of :func:`snakesim.agents.load_agent`: the loader's errors name
#: its arguments, and the command names them as its user typed them.
AGENT_FLAGS = {
    "joints": "--joints",
    "preset": "--preset",
    "task": "--env",
    "env_from": "--env-from",
    "hold": "--hold",
}


def load_agent(args: argparse.Namespace, outputs: Sequence[tuple[str | os.PathLike, str]] = ()):
    """The agent the command's arguments name; UserError when one of the command's ``outputs``
    ((path, flag), checked writable before) is a file the agent is read from, or two are one file,
    or when the loader refuses the arguments (naming their flags)."""
    from snakesim.agents.loading import AgentError, load_agent
    from snakesim.cli.errors import UserError, check_distinct, check_writable, env_files

    overrides = None
    if getattr(args, "goal", None) is not None:
        # A fixed goal instead of the task's: e.g. the paper's (0, -10) for a goal-task agent.
        overrides = {"goal": args.goal, "goal_distribution": None}
    if getattr(args, "robot", None) is not None:
        overrides = {**(overrides or {}), "robot": args.robot}
    if getattr(args, "randomize", None) is not None:
        # A physics distribution instead of the agent's own (checked when the env is made).
        overrides = {**(overrides or {}), "randomize": read_randomize(args.randomize)}
    try:
        agent = load_agent(
            args.source,
            joints=args.joints,
            preset=args.preset,
            env_overrides=overrides,
            task=getattr(args, "env", None) or "goal",
            env_from=getattr(args, "env_from", None),
            hold=getattr(args, "hold", None),
        )
    except AgentError as error:
        raise UserError(error.naming(AGENT_FLAGS)) from None
    # One thread: a small MLP gains nothing from more, and they would compete with the env's threads.
    # Only loading an SB3 model imports torch; importing it for a native model or a baseline cost every
    # command 2 s before it started (measured: `snakesim export` 3.3 s, 1.1 s without).
    if "torch" in sys.modules:
        sys.modules["torch"].set_num_threads(args.torch_threads)
    inputs = [*agent.files, *env_files(agent.env_kwargs)]
    for folder in (args.source, getattr(args, "env_from", None)):
        if folder is not None and os.path.isdir(folder):
            # A run directory's own files (evaluations.csv, checkpoints, ...) are no place for outputs.
            inputs += [p for p in Path(folder).rglob("*") if p.is_file()]
    for path, what in outputs:
        check_writable(path, what, inputs)
    check_distinct(outputs)
    return agent


def progress_options(p: argparse.ArgumentParser, step: str) -> None:
    """``--progress`` and ``--no-progress``, as ``snakesim train``'s: by default a bar on a terminal
    and one line per step of progress (one of ``step``) when stderr is not one; stdout never."""
    p.add_argument(
        "--progress",
        dest="progress",
        action="store_true",
        default=None,
        help=f"show a progress bar on stderr (default: when stderr is a terminal; otherwise one line per "
        f"{step} there)",
    )
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress")
