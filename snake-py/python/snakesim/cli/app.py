"""The ``snakesim`` command: one module per subcommand in this package; this one assembles them.

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

import contextlib
import os
import sys
import tempfile

from snakesim.cli import evaluate, export, plot, replay, search, sweep, train, view
from snakesim.cli.args import Parser
from snakesim.cli.errors import UserError, one_line


def build_parser() -> Parser:
    parser = Parser(
        prog="snakesim",
        description="Train, evaluate, plot and replay PPO agents of the 'Simulating Snakes' snake.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=Parser)
    for command in (train, evaluate, plot, sweep, search, replay, export, view):
        command.add_parser(sub)
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
    from snakesim.agents.loading import AgentError
    from snakesim.extras import MissingExtra
    from snakesim.runs.config import ConfigError
    from snakesim.runs.results import TrainingFailed
    from snakesim.runs.rundir import RunDirError
    from snakesim.sweeps.plan import SweepError
    from snakesim.viewer.plots import PlotError
    from snakesim.viewer.recording import RecordingError
    from snakesim.viewer.replay import ReplayError

    try:
        return args.func(args)
    except (
        UserError,
        ConfigError,
        AgentError,
        RunDirError,
        PlotError,
        ReplayError,
        RecordingError,
        SweepError,
        TrainingFailed,
        MissingExtra,
    ) as error:
        print(f"snakesim {args.command}: error: {one_line(error)}", file=sys.stderr)
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
            f"snakesim {args.command}: error: {type(error).__name__}: {one_line(error)} "
            "(set SNAKESIM_TRACEBACK=1 for the traceback)",
            file=sys.stderr,
        )
        return 1


if __name__ == "__main__":
    sys.exit(main())
