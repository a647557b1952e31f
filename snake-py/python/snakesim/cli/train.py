"""``snakesim train``: PPO with the native trainer or Stable-Baselines3."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from snakesim.cli.args import int_at_least
from snakesim.runs import config as runconfig


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
    from snakesim.runs.results import TrainingInterrupted

    overrides = _train_overrides(args)
    native = _trainer_kind(overrides, args) == "native"
    if native:
        from snakesim.runs.native import NativeTrainer

        trainer = NativeTrainer(overrides, run_dir=args.run_dir, resume=args.resume, progress=args.progress)
    else:
        from snakesim.runs.sb3_trainer import Trainer

        trainer = Trainer(
            overrides,
            run_dir=args.run_dir,
            resume=args.resume,
            progress=args.progress,
            verbose=1 if args.verbose else 0,
        )
    config = trainer.config
    print(
        f"run {trainer.run_dir}: PPO-{runconfig.arch_label(config['arch'])} ({config['trainer']} trainer), "
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


def add_parser(sub) -> None:
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
            options["type"] = int_at_least(*flag["range"])  # the configuration checks the rest
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
