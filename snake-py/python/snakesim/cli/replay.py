"""``snakesim replay``: figures, animations and Rerun recordings of an agent's episodes."""

from __future__ import annotations

import argparse

from snakesim.cli import rerun as rerun_cli
from snakesim.cli.args import agent_options, baseline_env_options, int_at_least, load_agent, seconds
from snakesim.cli.errors import UserError, check_distinct, check_writable
from snakesim.files import write_atomically
from snakesim.limits import LIMITS


def cmd_replay(args: argparse.Namespace) -> int:
    from snakesim.viewer import replay

    if not args.out and not rerun_cli.wants_rerun(args):
        raise UserError("give --out (a figure or animation), --rrd, --spawn or --serve")
    rrd = rerun_cli.check_replay(args)
    outs = [check_writable(out, "--out") for out in args.out]
    kinds = [replay.check_output(out) for out in outs]
    outputs = [(out, "--out") for out in outs] + ([(rrd, "--rrd")] if rrd is not None else [])
    check_distinct(outputs)
    if any(kind != "figure" for kind in kinds):
        replay.check_fps(args.fps)
    agent = load_agent(args, outputs)
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
    title = args.title if args.title is not None else f"{agent.label}, {agent.body}"
    for out, kind in zip(outs, kinds):
        if kind == "figure":
            write_atomically(out, lambda tmp: replay.draw_strip(rec, tmp, panels=args.panels, title=title))
            print(f"wrote {out} ({args.panels} moments and the path)")
        else:
            writer = replay.write_gif if kind == "gif" else replay.write_mp4
            frames = write_atomically(out, lambda tmp, writer=writer: writer(rec, tmp, fps=args.fps))
            print(f"wrote {out} ({frames} frames at {args.fps:g} fps)")
    return recorded.serve() if recorded is not None else 0


def add_parser(sub) -> None:
    p = sub.add_parser(
        "replay", help="the snake at successive moments (Figure 4), animations and Rerun recordings"
    )
    agent_options(p)
    baseline_env_options(p)
    p.add_argument(
        "--out",
        "--output",
        dest="out",
        action="append",
        default=[],
        help="a .png/.pdf/.svg figure, .gif or .mp4 animation (repeatable)",
    )
    rerun_cli.add_replay_options(p)
    p.add_argument(
        "--seconds", type=seconds, help="stop after this many simulated seconds (default: the whole episode)"
    )
    p.add_argument(
        "--deterministic",
        action="store_true",
        help="the deterministic policy (default: sample, as the paper's snake.py test)",
    )
    p.add_argument(
        "--panels",
        type=int_at_least(1, LIMITS["replay_panels"]),
        default=7,
        help=f"moments in the figure (1-{LIMITS['replay_panels']}, default 7)",
    )
    p.add_argument(
        "--fps", type=seconds, default=10.0, help="animation frames per simulated second (default 10)"
    )
    p.add_argument("--title", help="the figure's title")
    p.set_defaults(func=cmd_replay)
