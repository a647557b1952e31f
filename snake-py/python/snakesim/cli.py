"""The ``snakesim`` command: train PPO as the paper did, then evaluate, plot and replay the agents.

    snakesim train --joints 5 --arch small [--config snake-py/configs/paper-small-5.yaml] [...]
    snakesim evaluate RUN_OR_MODEL [--episodes 100] [--json out.json]
    snakesim plot RUN [RUN ...] --out fig.png
    snakesim replay RUN_OR_MODEL --out motion.png --out motion.gif
    snakesim replay RUN_OR_MODEL --rrd episode.rrd          # a Rerun recording (also --spawn, --serve)
    snakesim view episode.rrd --serve                        # Rerun's web viewer on 127.0.0.1
    snakesim sweep CONFIG.yaml [...] --seeds K [--grid KEY=V1,V2] --out sweeps/NAME [--address HOST:PORT]
    snakesim search CONFIG.yaml --space space.yaml --trials T --out sweeps/NAME

``snakesim COMMAND --help`` lists every option. Errors print one line on stderr and exit non-zero
(2 for bad usage, 1 for anything else, 130 after Ctrl-C).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any, NoReturn

from snakesim import runconfig, search, sweep
from snakesim.config import LIMITS, PRESETS
from snakesim.files import write_atomically


class UserError(Exception):
    """An error of the user's input: reported as one line, no traceback."""


def _one_line(message: object) -> str:
    return " ".join(str(message).split())


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {_one_line(message)} (see {self.prog} --help)\n")


def _int_at_least(minimum: int, maximum: int | None = None):
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


_positive_int = _int_at_least(1)
_count = _int_at_least(0)
_seed = _int_at_least(0, LIMITS["seed"])
_threads = _int_at_least(1, LIMITS["threads"])
_episodes = _int_at_least(1, LIMITS["eval_episodes"])


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of seconds, got {text}")
    return value


def _goal(text: str) -> tuple[float, float]:
    """X,Y in metres; the env checks the range."""
    parts = text.split(",")
    try:
        x, y = (float(v) for v in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y (two numbers), got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"expected finite X,Y, got {text!r}")
    return x, y


def check_writable(path: str | os.PathLike, what: str = "") -> Path:
    """The output path, if its directory exists and is writable; UserError otherwise."""
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    label = f"{what} {path}" if what else str(path)
    if path.is_dir():
        raise UserError(f"cannot write {label}: it is a directory")
    if not parent.is_dir():
        raise UserError(f"cannot write {label}: directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise UserError(f"cannot write {label}: directory {parent} is not writable")
    return path


# -- train ----------------------------------------------------------------------------------------


def _train_overrides(args: argparse.Namespace) -> dict[str, Any]:
    overrides: dict[str, Any] = {}
    if args.config is not None:
        data = runconfig.load_yaml(args.config)
        try:
            runconfig.validate(data)
        except runconfig.ConfigError as error:
            raise runconfig.ConfigError(f"{args.config}: {error}") from None
        overrides = data
    overrides = runconfig.merge(overrides, runconfig.parse_set(args.set))
    for flag in runconfig.FLAGS:
        if hasattr(args, flag["key"]):
            overrides[flag["key"]] = getattr(args, flag["key"])
    return overrides


def _trainer_kind(overrides: dict[str, Any], args: argparse.Namespace) -> str:
    """The trainer a run uses: the flag or config's, else (resuming) the saved run's, else the default."""
    if "trainer" in overrides:
        return overrides["trainer"]
    if args.resume and args.run_dir is not None:
        saved = Path(args.run_dir) / "config.yaml"
        if saved.is_file():
            return runconfig.load(saved)["trainer"]
    return runconfig.DEFAULTS["trainer"]


def cmd_train(args: argparse.Namespace) -> int:
    from snakesim.train import TrainingInterrupted

    overrides = _train_overrides(args)
    native = _trainer_kind(overrides, args) == "native"
    if native:
        from snakesim.native import NativeTrainer

        trainer = NativeTrainer(overrides, run_dir=args.run_dir, resume=args.resume, progress=args.progress)
    else:
        from snakesim.train import Trainer

        trainer = Trainer(
            overrides,
            run_dir=args.run_dir,
            resume=args.resume,
            progress=args.progress,
            verbose=1 if args.verbose else 0,
        )
    config = trainer.config
    print(
        f"run {trainer.run_dir}: PPO-{config['arch']} ({config['trainer']} trainer), "
        f"{config['joints']} joints, preset {config['preset']}, {config['timesteps']:,} timesteps, "
        f"{config['n_envs']} envs, seed {config['seed']}"
        + (f" (resuming from {trainer.resume_from[0]:,})" if trainer.resume_from else ""),
        flush=True,
    )
    model_file = "model.safetensors" if native else "model.zip"
    try:
        result = trainer.run()
    except TrainingInterrupted as stop:
        print(
            f"snakesim train: interrupted at {stop.timesteps:,} timesteps; saved {stop.path} and "
            f"{trainer.run_dir / model_file}; continue with: "
            f"snakesim train --run-dir {trainer.run_dir} --resume",
            file=sys.stderr,
        )
        return 130
    if native:
        d = result.details or {}
        where = (
            f"rollouts {d.get('rollout_seconds', 0):.1f} s, updates {d.get('update_seconds', 0):.1f} s, "
            f"{d.get('threads')} threads; memory {d['rss_mib'][0]:.0f} MiB after the first update, "
            f"{d['rss_mib'][1]:.0f} MiB at the end"
        )
    else:
        import torch

        where = f"device {trainer.model.device}, torch threads {torch.get_num_threads()}"
    print(
        f"trained {result.timesteps - result.start_timesteps:,} timesteps in {result.seconds:.1f} s: "
        f"{result.timesteps_per_second:.0f} timesteps/s ({result.training_timesteps_per_second:.0f} without "
        f"evaluations; {where})"
    )
    last = result.last_evaluation
    if last is not None:
        steps = "-" if last["mean_steps_to_goal"] is None else f"{last['mean_steps_to_goal']:.0f}"
        print(
            f"evaluation at {last['timesteps']:,} timesteps ({config['eval_episodes']} episodes): "
            f"mean return {last['mean_return']:.1f} ± {last['std_return']:.1f}, "
            f"success rate {last['success_rate']:.2f}, mean steps to goal {steps}"
        )
    print(
        f"wrote {result.run_dir}/{model_file}, evaluations.csv, config.yaml, versions.json, tb/, checkpoints/"
    )
    return 0


# -- evaluate -------------------------------------------------------------------------------------
def _load_agent(args: argparse.Namespace):
    from snakesim import extras
    from snakesim.agents import load_agent

    # One thread: a small MLP gains nothing from more, and they would compete with the env's threads.
    # (Only SB3 models use torch; native models and baselines run without the sb3 extra.)
    if extras.available("sb3"):
        import torch

        torch.set_num_threads(args.torch_threads)
    overrides = None
    if getattr(args, "goal", None) is not None:
        # A fixed goal instead of the task's: e.g. the paper's (0, -10) for a goal-task agent.
        overrides = {"goal": args.goal, "goal_distribution": None}
    return load_agent(args.source, joints=args.joints, preset=args.preset, env_overrides=overrides)


def cmd_evaluate(args: argparse.Namespace) -> int:
    from snakesim.agents import evaluate

    if args.json is not None and args.json != "-":
        check_writable(args.json, "--json")
    agent = _load_agent(args)
    result = evaluate(agent, args.episodes, args.seed, deterministic=not args.stochastic)
    report = {
        "model": agent.path,
        "arch": agent.arch,
        "joints": agent.joints,
        "preset": agent.env_kwargs["preset"],
        "sb3_version": agent.sb3_version,
        "trained_timesteps": agent.num_timesteps,
        "seed": args.seed,
        "deterministic": not args.stochastic,
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
    trainer = {"native": "native trainer", "baseline": "hand-made controller"}.get(
        agent.kind, f"SB3 {agent.sb3_version}"
    )
    label = "baseline" if agent.kind == "baseline" else f"PPO-{agent.arch}"
    low, high = report["success_rate_ci95"]

    def optional(value: float | None, unit: str = "") -> str:
        return "-" if value is None else f"{value:.3f}{unit}"

    rows = [
        ("model", f"{agent.path} ({label}, {trainer})"),
        ("env", f"{agent.joints} joints, preset {report['preset']}"),
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


# -- plot -----------------------------------------------------------------------------------------
def cmd_plot(args: argparse.Namespace) -> int:
    from snakesim.plots import plot_runs

    out = check_writable(args.out, "--out")
    if out.suffix.lower() not in (".png", ".pdf", ".svg"):
        raise UserError(f"cannot write --out {out}: expected a .png, .pdf or .svg file")
    drawn = write_atomically(
        out,
        lambda tmp: plot_runs(
            args.runs,
            tmp,
            title=args.title,
            metric=args.metric,
            group=args.group,
            spread=args.spread,
            x=args.x,
        ),
    )
    print(f"wrote {out}: " + "; ".join(label for label, _ in drawn))
    return 0


# -- sweep and search -----------------------------------------------------------------------------
def _cluster_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a config key for every trial (repeatable)",
    )
    p.add_argument(
        "--address",
        metavar="HOST:PORT",
        help="a running Ray cluster (what `ray start --head` prints; default: a local Ray for this command; "
        f"an unreachable one is an error within {sweep.CONNECT_TIMEOUT_S:g} s)",
    )
    p.add_argument(
        "--cpus-per-trial",
        dest="cpus_per_trial",
        metavar="C",
        type=_threads,
        help=f"CPUs Ray reserves per trial, also its threads unless the config sets them "
        f"(default {sweep.DEFAULT_CPUS_PER_TRIAL})",
    )
    p.add_argument(
        "--max-failures",
        dest="max_failures",
        metavar="F",
        type=_int_at_least(0, sweep.MAX_FAILURES),
        help="retries of a trial whose worker dies, from its last checkpoint "
        f"(default {sweep.DEFAULT_MAX_FAILURES})",
    )
    p.add_argument("--progress", dest="progress", action="store_true", default=None, help="show trial counts")
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no trial counts")


# -- replay ---------------------------------------------------------------------------------------
def cmd_replay(args: argparse.Namespace) -> int:
    from snakesim import replay, rerun_cli

    if not args.out and not rerun_cli.wants_rerun(args):
        raise UserError("give --out (a figure or animation), --rrd, --spawn or --serve")
    rrd = rerun_cli.check_replay(args)
    outs = [check_writable(out, "--out") for out in args.out]
    kinds = [replay.check_output(out) for out in outs]
    if len({out.resolve() for out in outs}) < len(outs):
        raise UserError("two --out name the same file; give each its own path")
    if any(kind != "figure" for kind in kinds):
        replay.check_fps(args.fps)
    agent = _load_agent(args)
    # Rerun outputs record their episodes first; figures and animations then show the first of them.
    recorded = rerun_cli.replay(args, agent, rrd) if rerun_cli.wants_rerun(args) else None
    if recorded is not None:
        rec = recorded.episodes[0]
    else:
        rec = replay.record(
            lambda obs: agent.act(obs, args.deterministic),
            agent.env_kwargs,
            seconds=args.seconds,
            seed=args.seed,
        )
        outcome = "reached the goal" if rec.terminated else "did not reach the goal"
        print(f"replayed {rec.duration:.2f} s ({len(rec.times) - 1} steps): {outcome}, return {rec.ret:.1f}")
    title = args.title if args.title is not None else f"PPO-{agent.arch}, {agent.joints} joints"
    for out, kind in zip(outs, kinds):
        if kind == "figure":
            write_atomically(out, lambda tmp: replay.draw_strip(rec, tmp, panels=args.panels, title=title))
            print(f"wrote {out} ({args.panels} moments and the path)")
        else:
            writer = replay.write_gif if kind == "gif" else replay.write_mp4
            frames = write_atomically(out, lambda tmp, writer=writer: writer(rec, tmp, fps=args.fps))
            print(f"wrote {out} ({frames} frames at {args.fps:g} fps)")
    return recorded.serve() if recorded is not None else 0


# -- export ---------------------------------------------------------------------------------------
def cmd_export(args: argparse.Namespace) -> int:
    from snakesim.export import to_sb3

    out = check_writable(args.sb3, "--sb3")
    if out.suffix.lower() != ".zip":
        raise UserError(f"cannot write --sb3 {out}: expected a .zip file")
    agent = _load_agent(args)
    if agent.kind != "native":
        raise UserError(
            f"{agent.path} is already a Stable-Baselines3 model; export takes native runs and models"
        )
    try:
        written = to_sb3(agent, out)
    except OSError as error:
        raise UserError(f"cannot write --sb3 {out}: {error.strerror or error}") from None
    except ValueError as error:
        raise UserError(str(error)) from None
    print(
        f"wrote {', '.join(map(str, written))} (PPO-{agent.arch}, {agent.joints} joints; load with PPO.load)"
    )
    return 0


# -- the parser -----------------------------------------------------------------------------------
def _agent_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "source",
        metavar="RUN_OR_MODEL",
        help="a run directory, a native model .safetensors, an SB3 model .zip (SB3 1.x or 2.x), or "
        "baseline:steer / baseline:gait (hand-made controllers of the goal task)",
    )
    p.add_argument(
        "--joints", type=_positive_int, help="for a bare .zip: the snake's joints (default: from the model)"
    )
    p.add_argument("--preset", choices=PRESETS, help="for a bare .zip: the robot preset (default paper)")
    p.add_argument("--seed", type=_seed, default=0, help="seed of the episodes (default 0)")
    p.add_argument("--torch-threads", type=_threads, default=1, help="torch CPU threads (default 1)")


def build_parser() -> argparse.ArgumentParser:
    from snakesim import rerun_cli

    parser = _Parser(
        prog="snakesim",
        description="Train, evaluate, plot and replay PPO agents of the 'Simulating Snakes' snake.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=_Parser)
    S = argparse.SUPPRESS

    p = sub.add_parser(
        "train",
        help="train PPO (the paper's settings)",
        description="Train PPO on snakesim (the native trainer, or Stable-Baselines3 with --trainer sb3). "
        "Configuration: defaults (the paper's Table 1) "
        "< --config YAML < --set KEY=VALUE and the flags below.",
    )
    p.add_argument("--config", metavar="FILE.yaml", help="a run configuration (see snake-py/configs/)")
    for flag in runconfig.FLAGS:  # every run-configuration flag, defined once in snake-rl
        kind = flag["value"]
        options: dict[str, Any] = {"dest": flag["key"], "default": S, "help": flag["help"]}
        if kind == "integer":
            options["type"] = _int_at_least(*flag["range"])  # the configuration checks the rest
        elif kind == "choice":
            options["choices"] = flag["choices"]
        elif kind == "switch":
            options["action"] = "store_true"
        p.add_argument(flag["flag"], **options)
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="any config key, e.g. ppo.n_steps=256 or env.max_episode_steps=1000 (repeatable)",
    )
    p.add_argument(
        "--run-dir", dest="run_dir", help="where the run goes (default runs/ppo-ARCH-JOINTS-PRESET-seedSEED)"
    )
    p.add_argument(
        "--resume", action="store_true", help="continue the run in --run-dir from its latest checkpoint"
    )
    p.add_argument(
        "--progress",
        dest="progress",
        action="store_true",
        default=None,
        help="show a progress bar (default: when stderr is a terminal)",
    )
    p.add_argument("--no-progress", dest="progress", action="store_false", help="no progress bar")
    p.add_argument("--verbose", action="store_true", help="print SB3's training tables")
    p.set_defaults(func=cmd_train)

    p = sub.add_parser(
        "evaluate",
        help="success rate, return, steps to goal, speed, path efficiency and cost of transport of an agent",
    )
    _agent_options(p)
    p.add_argument(
        "--goal",
        type=_goal,
        metavar="X,Y",
        help="a fixed goal instead of the agent's task's (e.g. 0,-10: the paper's task)",
    )
    p.add_argument("--episodes", type=_episodes, default=100, help="episodes (default 100)")
    p.add_argument(
        "--stochastic", action="store_true", help="sample actions instead of the deterministic policy"
    )
    p.add_argument(
        "--json", metavar="FILE", help="also write the results as JSON (- : print only JSON to stdout)"
    )
    p.set_defaults(func=cmd_evaluate)

    p = sub.add_parser("plot", help="learning curves (Figure 3)")
    p.add_argument(
        "runs", nargs="+", metavar="RUN", help="run directories, evaluations.csv files or sweep folders"
    )
    p.add_argument("--out", required=True, help="the figure (.png, .pdf or .svg)")
    p.add_argument("--title", help="the figure's title")
    p.add_argument(
        "--metric", choices=("mean_return", "success_rate", "mean_steps_to_goal"), default="mean_return"
    )
    p.add_argument(
        "--group",
        choices=("auto", "none", "all"),
        default="auto",
        help="auto: runs differing only in seed are one line (mean, shaded spread)",
    )
    p.add_argument("--spread", choices=("minmax", "std"), default="minmax", help="the shaded band of a group")
    p.add_argument(
        "--x",
        choices=("timesteps", "wall_time"),
        default="timesteps",
        help="the x axis: timesteps, or the wall time of training (default timesteps)",
    )
    p.set_defaults(func=cmd_plot)

    p = sub.add_parser(
        "sweep",
        help="train every config x grid point x seed on a Ray cluster",
        description="Every (config, grid point, seed) is one run directory under --out, trained as a Ray "
        "Tune trial. See docs/sweeps.md.",
    )
    p.add_argument(
        "configs", nargs="*", metavar="CONFIG.yaml", help="run configurations (see snake-py/configs/)"
    )
    p.add_argument("--out", metavar="SWEEPS/NAME", help="the sweep's folder (new, or empty)")
    p.add_argument(
        "--seeds",
        metavar="K",
        type=_int_at_least(1, sweep.MAX_SEEDS),
        help="seeds per config and grid point: the config's seed and the next K-1 (default 1)",
    )
    p.add_argument(
        "--grid",
        action="append",
        default=[],
        metavar="KEY=V1,V2,...",
        help="values of a config key to train each config with (repeatable: every combination)",
    )
    p.add_argument(
        "--resume", metavar="SWEEPS/NAME", help="finish an interrupted sweep: run its unfinished trials"
    )
    _cluster_options(p)
    p.set_defaults(func=sweep.command)

    p = sub.add_parser(
        "search",
        help="search hyperparameters with Optuna and ASHA on a Ray cluster",
        description="Optuna chooses each trial's values from --space, ASHA stops trials that trail; the best "
        "trial's config is written as OUT/best.yaml. See docs/sweeps.md.",
    )
    p.add_argument("config", metavar="CONFIG.yaml", help="the run configuration the space varies")
    p.add_argument("--space", required=True, metavar="SPACE.yaml", help="keys and their distributions")
    p.add_argument(
        "--trials", required=True, metavar="T", type=_int_at_least(1, sweep.MAX_TRIALS), help="trials to run"
    )
    p.add_argument("--metric", choices=("success_rate", "mean_return"), default="success_rate")
    p.add_argument("--out", required=True, metavar="SWEEPS/NAME", help="the search's folder (new, or empty)")
    _cluster_options(p)
    p.set_defaults(func=search.command)

    p = sub.add_parser(
        "replay", help="the snake at successive moments (Figure 4), animations and Rerun recordings"
    )
    _agent_options(p)
    p.add_argument(
        "--out",
        action="append",
        default=[],
        help="a .png/.pdf/.svg figure, .gif or .mp4 animation (repeatable)",
    )
    rerun_cli.add_replay_options(p)
    p.add_argument(
        "--seconds", type=_seconds, help="stop after this many simulated seconds (default: the whole episode)"
    )
    p.add_argument(
        "--deterministic",
        action="store_true",
        help="the deterministic policy (default: sample, as the paper's snake.py test)",
    )
    p.add_argument(
        "--panels",
        type=_int_at_least(1, LIMITS["replay_panels"]),
        default=7,
        help=f"moments in the figure (1-{LIMITS['replay_panels']}, default 7)",
    )
    p.add_argument(
        "--fps", type=_seconds, default=10.0, help="animation frames per simulated second (default 10)"
    )
    p.add_argument("--title", help="the figure's title")
    p.set_defaults(func=cmd_replay)

    p = sub.add_parser(
        "export",
        help="write a native run's policy as a Stable-Baselines3 zip",
        description="Write a native policy as an SB3 PPO zip that PPO.load opens and that acts as the native "
        "policy does (observation statistics, if any, go beside it as NAME_vecnormalize.pkl).",
    )
    _agent_options(p)
    p.add_argument("--sb3", required=True, metavar="MODEL.zip", help="the zip to write")
    p.set_defaults(func=cmd_export)
    rerun_cli.add_commands(sub)
    return parser


@contextlib.contextmanager
def _scratch_for_torch():
    """torch makes a compile cache (``$TMPDIR/torchinductor_<user>``) the first time a command loads an
    SB3 model, and never removes it; snakesim compiles nothing, so each command gives torch a
    temporary one, removed on exit (unless the user chose one with TORCHINDUCTOR_CACHE_DIR)."""
    if "TORCHINDUCTOR_CACHE_DIR" in os.environ:
        yield
        return
    with tempfile.TemporaryDirectory(prefix="snakesim-torch-") as scratch:
        os.environ["TORCHINDUCTOR_CACHE_DIR"] = scratch
        try:
            yield
        finally:
            del os.environ["TORCHINDUCTOR_CACHE_DIR"]


def main(argv: list[str] | None = None) -> int:
    with _scratch_for_torch():
        return _main(argv)


def _main(argv: list[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from snakesim.agents import AgentError
    from snakesim.extras import MissingExtra
    from snakesim.plots import PlotError
    from snakesim.replay import ReplayError
    from snakesim.rerun_log import RecordingError
    from snakesim.sweep import SweepError
    from snakesim.train import RunDirError, TrainingFailed

    try:
        return args.func(args)
    except (
        UserError,
        runconfig.ConfigError,
        AgentError,
        RunDirError,
        PlotError,
        ReplayError,
        RecordingError,
        SweepError,
        TrainingFailed,
        MissingExtra,
    ) as error:
        print(f"snakesim {args.command}: error: {_one_line(error)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"snakesim {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # Whoever read our output has gone (`snakesim evaluate ... | head -1`): stop quietly. Python
        # would complain about the unflushed stdout at exit; point it at nothing.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except OSError as error:
        # A full disk, a vanished directory: the system's message, with the file when it names one.
        where = f" {error.filename}" if error.filename else ""
        print(f"snakesim {args.command}: error:{where} {error.strerror or error}", file=sys.stderr)
        return 1
    except Exception as error:  # noqa: BLE001 - the last line of defence: one line, never a traceback
        if os.environ.get("SNAKESIM_TRACEBACK"):
            raise
        print(
            f"snakesim {args.command}: error: {type(error).__name__}: {_one_line(error)} "
            "(set SNAKESIM_TRACEBACK=1 for the traceback)",
            file=sys.stderr,
        )
        return 1


if __name__ == "__main__":
    sys.exit(main())
