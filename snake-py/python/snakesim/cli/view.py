"""``snakesim convert`` (a physics trace from ``snake-cli run --trace`` as a Rerun recording) and
``snakesim view`` (open a recording in Rerun's native or web viewer)."""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import Any

from snakesim.cli.errors import UserError
from snakesim.cli.rerun import (
    DEFAULT_GRPC_PORT,
    DEFAULT_WEB_PORT,
    Recorded,
    _port,
    _record,
    add_viewer_options,
    check_outputs,
    wants_rerun,
)
from snakesim.viewer.recording import MAX_SECONDS, RecordingError


# -- convert --------------------------------------------------------------------------------------
def cmd_convert(args: argparse.Namespace) -> int:
    from snakesim.viewer.recording import _rerun, log_trace, read_trace_header

    if args.check:
        _rerun()
        return 0
    if args.trace is None:
        raise UserError("give the physics trace to convert (TRACE.csv, from snake-cli run --trace)")
    if not wants_rerun(args):
        raise UserError("give --rrd FILE.rrd, --spawn or --serve")
    rrd = check_outputs(args)
    meta, _ = read_trace_header(args.trace)
    steps = meta.get("steps")
    if isinstance(steps, (int, float)) and steps * float(meta["dt"]) > MAX_SECONDS + 1e-9:
        raise RecordingError(
            f"{args.trace} holds {steps * float(meta['dt']):g} simulated seconds, more than the "
            f"{MAX_SECONDS:g} a recording holds"
        )
    counted: list[int] = []

    def log_into(recording, recorded: Recorded) -> None:
        counted.append(log_trace(recording, args.trace))

    label = f"{meta.get('source', 'trace')}: {meta['joints']} joints"
    if "preset" in meta:
        label += f", preset {meta['preset']}"
    recorded = _record(args, rrd, log_into, label)
    if not args.quiet:
        print(f"recorded {counted[0]} physics steps of {meta['joints']} joints")
    return recorded.serve()


# -- view -----------------------------------------------------------------------------------------
def cmd_view(args: argparse.Namespace) -> int:
    from snakesim.viewer.processes import check_display, check_port_free, rerun_executable, serve, spawn_file

    path = Path(args.recording)
    if not path.is_file():
        raise UserError(f"cannot open {path}: no such file")
    if not os.access(path, os.R_OK):
        raise UserError(f"cannot open {path}: not readable")
    if args.spawn == args.serve:
        raise UserError("give one of --spawn (native viewer) or --serve (web viewer)")
    _check_rrd(path)
    if args.spawn:
        check_display()
        spawn_file(path)
        print(f"opened {path} in Rerun's native viewer ({rerun_executable()})")
        return 0
    if args.web_port == args.grpc_port:
        raise UserError("--web-port and --grpc-port must differ")
    check_port_free(args.web_port, "--web-port")
    check_port_free(args.grpc_port, "--grpc-port")

    def ready(url: str) -> None:
        print(f"serving Rerun's web viewer at {url} (Ctrl-C to stop)", flush=True)

    return serve(path, web_port=args.web_port, grpc_port=args.grpc_port, ready=ready)


def _check_rrd(path: Path) -> None:
    """RecordingError unless ``path`` is an RRD file with a recording in it."""
    from snakesim.viewer.recording import _rerun

    rr = _rerun()
    try:
        recordings = rr.chunk.RrdReader(path).recordings()
    except (RuntimeError, ValueError, OSError) as error:
        raise RecordingError(
            f"cannot open {path}: not a Rerun recording ({' '.join(str(error).split())})"
        ) from None
    if not recordings:
        raise RecordingError(f"cannot open {path}: it holds no recording")


def add_parser(sub: Any) -> None:
    """The ``convert`` and ``view`` subcommands."""
    p = sub.add_parser(
        "convert",
        help="a physics trace (snake-cli run --trace) as a Rerun recording",
        description="Log a physics trace written by snake-cli run --trace to Rerun: the cubes in 3D at every "
        "physics step and plots of the joints (snake-cli run --rrd does this for you).",
    )
    p.add_argument("trace", metavar="TRACE.csv", nargs="?", help="the physics trace")
    add_viewer_options(p, rrd_help="write the recording here")
    p.add_argument("--quiet", action="store_true", help="print nothing on success")
    p.add_argument("--check", action="store_true", help=argparse.SUPPRESS)  # snake-cli: can we record?
    p.set_defaults(func=cmd_convert)

    p = sub.add_parser(
        "view",
        help="open a Rerun recording (.rrd) in the native or the web viewer",
        description="Open a recording written by snake-cli run --rrd or snakesim replay --rrd.",
    )
    p.add_argument("recording", metavar="FILE.rrd")
    p.add_argument("--spawn", action="store_true", help="Rerun's native viewer (needs a display)")
    p.add_argument("--serve", action="store_true", help="Rerun's web viewer on 127.0.0.1 until Ctrl-C")
    p.add_argument("--web-port", type=_port, default=DEFAULT_WEB_PORT, help=f"default {DEFAULT_WEB_PORT}")
    p.add_argument("--grpc-port", type=_port, default=DEFAULT_GRPC_PORT, help=f"default {DEFAULT_GRPC_PORT}")
    p.set_defaults(func=cmd_view)
