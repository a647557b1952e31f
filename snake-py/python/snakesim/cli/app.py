"""The ``snakesim`` command: one module per subcommand in this package; this one assembles them.

    snakesim train --joints 5 --arch small [--config snake-py/configs/paper-small-5.yaml] [...]
    snakesim evaluate RUN_OR_MODEL [--episodes 100] [--json out.json]
    snakesim plot RUN [RUN ...] --out fig.png
    snakesim replay RUN_OR_MODEL --out motion.png --out motion.gif
    snakesim replay RUN_OR_MODEL --rrd episode.rrd          # a Rerun recording (also --spawn, --serve)
    snakesim view episode.rrd --serve                        # Rerun's web viewer on 127.0.0.1
    snakesim sweep CONFIG.yaml [...] --seeds K [--grid KEY=V1,V2] --out sweeps/NAME [--address HOST:PORT]
    snakesim search CONFIG.yaml --space space.yaml --trials T --out sweeps/NAME
    snakesim calibrate --robot R --targets T.csv --log L.csv --fit motors.kp=0.05:1 --out FITTED.yaml

``snakesim COMMAND --help`` lists every option. Errors print one line on stderr and exit non-zero
(2 for bad usage, 1 for anything else, 130 after Ctrl-C, 143 after SIGTERM).
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import tempfile
import threading

from snakesim.cli import calibrate, evaluate, export, plot, replay, search, sweep, train, validate, view
from snakesim.cli.args import Parser
from snakesim.cli.errors import UserError, report


def build_parser() -> Parser:
    parser = Parser(
        prog="snakesim",
        description="Train, evaluate, plot and replay PPO agents of the 'Simulating Snakes' snake.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=Parser)
    for command in (train, evaluate, plot, sweep, search, replay, export, view, calibrate, validate):
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


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the program is, as Ctrl-C raises KeyboardInterrupt: ``finally`` blocks
    and context managers run (temporary folders are removed, a trainer saves its checkpoint), then
    the command exits 143 (128 + SIGTERM), as a process killed by SIGTERM would."""


@contextlib.contextmanager
def _sigterm_unwinds():
    """Turns SIGTERM into :class:`Terminated` while the command runs (in the main thread only:
    Python delivers signals there); a second SIGTERM kills at once. Yields a list that holds the
    signal once it came."""
    received: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield received
        return

    def terminate(signum, frame):
        received.append(signum)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        raise Terminated

    previous = signal.signal(signal.SIGTERM, terminate)
    try:
        yield received
    finally:
        signal.signal(signal.SIGTERM, previous)


def main(argv: list[str] | None = None) -> int:
    try:
        with _sigterm_unwinds() as received, _scratch_for_torch():
            code = _main(argv)
            # A trainer that caught the SIGTERM (and saved its checkpoint) still ends as SIGTERM ends.
            return 143 if received else code
    except Terminated:  # arrived outside the command (while arguments were parsed, or cleaning up)
        print("snakesim: terminated", file=sys.stderr)
        return 143


def _main(argv: list[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from snakesim.agents.loading import AgentError
    from snakesim.extras import MissingExtra
    from snakesim.files import FileError
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
        FileError,
    ) as error:
        print(report(args.command, error), file=sys.stderr)
        return 1
    except Terminated:
        print(f"snakesim {args.command}: terminated", file=sys.stderr)
        return 143
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
        where = f"{error.filename} " if error.filename else ""
        print(report(args.command, f"{where}{error.strerror or error}"), file=sys.stderr)
        return 1
    except Exception as error:  # noqa: BLE001 - the last line of defence: one line, never a traceback
        if os.environ.get("SNAKESIM_TRACEBACK"):
            raise
        hint = "(set SNAKESIM_TRACEBACK=1 for the traceback)"
        print(report(args.command, f"{type(error).__name__}: {error} {hint}"), file=sys.stderr)
        return 1
    except BaseException as error:
        # A Rust panic reaches Python as pyo3's PanicException, which derives from BaseException, not
        # Exception: one line too. (KeyboardInterrupt and SystemExit went past above or pass on.)
        if type(error).__name__ != "PanicException" or os.environ.get("SNAKESIM_TRACEBACK"):
            raise
        hint = "(a bug; set SNAKESIM_TRACEBACK=1 for the traceback)"
        print(report(args.command, f"internal error: {error} {hint}"), file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
