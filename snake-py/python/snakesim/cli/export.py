"""``snakesim export``: a policy as a Stable-Baselines3 zip (native models) and as an ONNX graph (any
model), for PPO.load and for the robot."""

from __future__ import annotations

import argparse
from pathlib import Path

from snakesim.cli.args import agent_options, load_agent, progress_options
from snakesim.cli.errors import UserError, check_writable
from snakesim.runs.progress import Progress


def _output(path: str, flag: str, suffix: str) -> Path:
    out = check_writable(path, flag)
    if out.suffix.lower() != suffix:
        raise UserError(f"cannot write {flag} {out}: expected a {suffix} file")
    return out


def _loads_sb3(source: str) -> bool:
    """Whether the source is an SB3 zip (or a run directory holding one): loading it takes SB3 and torch,
    6-9 s on the 2-core machine (measured 2026-11-29: `snakesim export RUN/model.zip --onnx` 8.5 s,
    SB3's own policy and optimizer construction most of it); a native model's whole export takes about
    1 s."""
    path = Path(source)
    return path.suffix.lower() == ".zip" or (path / "model.zip").is_file()


def cmd_export(args: argparse.Namespace) -> int:
    from snakesim.agents.loading import BASELINE_PREFIX
    from snakesim.runs.export import vecnormalize_path

    if args.sb3 is None and args.onnx is None:
        raise UserError("give --onnx POLICY.onnx, --sb3 MODEL.zip or both")
    if args.source.startswith(BASELINE_PREFIX):
        raise UserError(f"{args.source} is a hand-made controller, not a model: export takes runs and models")
    outputs: list[tuple[str | Path, str]] = []
    sb3 = onnx = None
    if args.sb3 is not None:
        sb3 = _output(args.sb3, "--sb3", ".zip")
        # The observation statistics go beside the zip (when the policy has them).
        outputs += [(sb3, "--sb3"), (vecnormalize_path(sb3), "--sb3's statistics")]
    if args.onnx is not None:
        onnx = _output(args.onnx, "--onnx", ".onnx")
        outputs.append((onnx, "--onnx"))
    # Progress where export is slow (an SB3 zip), as evaluate's: a bar on a terminal, a line per step
    # when piped, on stderr; steps: loading, then each output.
    steps = 1 + (onnx is not None) + (sb3 is not None)
    show = args.progress if args.progress is not None or _loads_sb3(args.source) else False
    with Progress(steps, "steps", "export", show, estimate=False) as progress:
        return _export(args, outputs, sb3, onnx, progress)


def _export(
    args: argparse.Namespace, outputs, sb3: Path | None, onnx: Path | None, progress: Progress
) -> int:
    from snakesim.runs.export import to_sb3
    from snakesim.runs.onnx import INPUT, OUTPUT, ExportError, to_onnx_bytes, write_bytes

    agent = load_agent(args, outputs)
    if sb3 is not None and not agent.exports_sb3:
        raise UserError(
            f"{agent.path} is already a Stable-Baselines3 model; --sb3 takes native runs and models "
            "(--onnx takes both)"
        )
    progress.update(1, f"loaded {args.source}")
    # The graph is built (and checked) before anything is written.
    graph = None
    if onnx is not None:
        try:
            graph = to_onnx_bytes(agent)
        except (ExportError, ImportError) as error:
            raise UserError(str(error)) from None
        progress.update(progress.done + 1, "built the ONNX graph")
    if sb3 is not None:
        try:
            written = to_sb3(agent, sb3)
        except OSError as error:
            raise UserError(f"cannot write --sb3 {sb3}: {error.strerror or error}") from None
        except ValueError as error:
            raise UserError(str(error)) from None
        progress.update(progress.done + 1, "wrote the SB3 zip")
        files = ", ".join(map(str, written))
        print(f"wrote {files} (PPO-{agent.arch}, {agent.joints} joints; load with PPO.load)")
    if onnx is not None and graph is not None:
        try:
            write_bytes(onnx, graph)
        except OSError as error:
            raise UserError(f"cannot write --onnx {onnx}: {error.strerror or error}") from None
        print(
            f"wrote {onnx} ({agent.label}, {agent.joints} joints; input {INPUT!r} [batch, obs], output "
            f"{OUTPUT!r} [batch, actions]; run with onnxruntime, see docs/deploy.md)"
        )
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser(
        "export",
        help="write a policy as an ONNX graph (for the robot) or a native one as a Stable-Baselines3 zip",
        description="Write a policy for use outside snakesim. --onnx: any model (native or SB3) as an ONNX "
        "graph from a batch of raw observations to the deterministic actions, observation normalisation "
        "included (docs/deploy.md). --sb3: a native policy as an SB3 PPO zip that PPO.load opens and that "
        "acts as the native policy does (observation statistics, if any, go beside it as "
        "NAME_vecnormalize.pkl). Give either or both.",
    )
    agent_options(p)
    p.add_argument("--sb3", metavar="MODEL.zip", help="the SB3 zip to write (native models only)")
    p.add_argument("--onnx", metavar="POLICY.onnx", help="the ONNX graph to write")
    progress_options(p, "step (by default for an SB3 zip, whose loading takes seconds; a native model: 1 s)")
    p.set_defaults(func=cmd_export)
