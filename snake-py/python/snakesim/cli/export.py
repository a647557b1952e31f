"""``snakesim export``: a native policy as a Stable-Baselines3 zip."""

from __future__ import annotations

import argparse

from snakesim.cli.args import agent_options, load_agent
from snakesim.cli.errors import UserError, check_writable


def cmd_export(args: argparse.Namespace) -> int:
    from snakesim.runs.export import to_sb3, vecnormalize_path

    out = check_writable(args.sb3, "--sb3")
    if out.suffix.lower() != ".zip":
        raise UserError(f"cannot write --sb3 {out}: expected a .zip file")
    # The observation statistics go beside the zip (when the policy has them).
    outputs = [(out, "--sb3"), (vecnormalize_path(out), "--sb3's statistics")]
    agent = load_agent(args, outputs)
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


def add_parser(sub) -> None:
    p = sub.add_parser(
        "export",
        help="write a native run's policy as a Stable-Baselines3 zip",
        description="Write a native policy as an SB3 PPO zip that PPO.load opens and that acts as the native "
        "policy does (observation statistics, if any, go beside it as NAME_vecnormalize.pkl).",
    )
    agent_options(p)
    p.add_argument("--sb3", required=True, metavar="MODEL.zip", help="the zip to write")
    p.set_defaults(func=cmd_export)
