"""The ``snakesim`` command's Rerun side: ``replay --rrd/--spawn/--serve``, ``convert`` (a physics
trace from ``snake-cli run --trace`` into a recording) and ``view`` (open a recording)."""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
from pathlib import Path
from typing import Any

from snakesim.limits import LIMITS
from snakesim.viewer.recording import MAX_SECONDS, RecordingError

DEFAULT_WEB_PORT = 9090
DEFAULT_GRPC_PORT = 9876
#: Most episodes of one replay recording.
MAX_EPISODES = LIMITS["recording_episodes"]


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got {text!r}") from None
    if not 1 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"expected a port in [1, 65535], got {value}")
    return value


def add_viewer_options(p: argparse.ArgumentParser, *, rrd_help: str) -> None:
    """--rrd, --spawn, --serve and the ports."""
    p.add_argument("--rrd", metavar="FILE.rrd", help=rrd_help)
    p.add_argument(
        "--spawn", action="store_true", help="open Rerun's native viewer with the recording (needs a display)"
    )
    p.add_argument(
        "--serve",
        action="store_true",
        help="serve the recording with Rerun's web viewer on 127.0.0.1 until Ctrl-C (open the printed URL)",
    )
    p.add_argument(
        "--web-port",
        type=_port,
        default=DEFAULT_WEB_PORT,
        help=f"--serve: the page's port (default {DEFAULT_WEB_PORT})",
    )
    p.add_argument(
        "--grpc-port",
        type=_port,
        default=DEFAULT_GRPC_PORT,
        help=f"--serve: the port the page reads the recording from (default {DEFAULT_GRPC_PORT})",
    )


def add_replay_options(p: argparse.ArgumentParser) -> None:
    """The Rerun options of ``snakesim replay``."""
    add_viewer_options(
        p,
        rrd_help="write a Rerun recording: the cubes in 3D at every physics step, the goal, the head's path, "
        "plots of the joints and the reward (open it with .venv/bin/rerun FILE or snakesim view FILE)",
    )
    p.add_argument(
        "--episodes",
        type=int,
        default=1,
        help="Rerun outputs: episodes to record one after another, seeds SEED, SEED+1, ... "
        f"(1-{MAX_EPISODES}, "
        "default 1; figures and animations show the first)",
    )


def wants_rerun(args: argparse.Namespace) -> bool:
    return bool(args.rrd or args.spawn or args.serve)


def check_outputs(args: argparse.Namespace) -> Path | None:
    """Checks --rrd, --spawn and --serve before anything runs; returns the --rrd path."""
    from snakesim.cli.errors import UserError, check_writable
    from snakesim.viewer.processes import check_display, check_port_free

    rrd = None
    if args.rrd is not None:
        trace = getattr(args, "trace", None)  # convert's input
        rrd = check_writable(args.rrd, "--rrd", [trace] if trace else [])
        if rrd.suffix.lower() != ".rrd":
            raise UserError(f"cannot write --rrd {rrd}: expected a .rrd file")
    if args.spawn:
        check_display()
    if args.serve:
        if args.web_port == args.grpc_port:
            raise UserError("--web-port and --grpc-port must differ")
        check_port_free(args.web_port, "--web-port")
        check_port_free(args.grpc_port, "--grpc-port")
    return rrd


@dataclasses.dataclass
class Recorded:
    """A finished recording: the episodes it holds and, for --serve, the file to serve."""

    args: argparse.Namespace
    episodes: list = dataclasses.field(default_factory=list)
    served: Path | None = None
    _tmp: Any = None  # the temporary directory of a served recording without --rrd

    def serve(self) -> int:
        """Serves the recording with --serve (until Ctrl-C); 0."""
        from snakesim.viewer.processes import serve

        if self.served is None:
            return 0

        def ready(url: str) -> None:
            print(f"serving Rerun's web viewer at {url} (Ctrl-C to stop)", flush=True)

        try:
            return serve(self.served, web_port=self.args.web_port, grpc_port=self.args.grpc_port, ready=ready)
        finally:
            if self._tmp is not None:
                self._tmp.cleanup()


def _record(args: argparse.Namespace, rrd: Path | None, log_into, label: str) -> Recorded:
    """Makes the recording (``log_into(recording, recorded)``) for --rrd and --spawn, and for --serve
    in a temporary file unless --rrd names one."""
    from snakesim.viewer.processes import spawn_viewer
    from snakesim.viewer.recording import recording_to

    spawn_url = spawn_viewer() if args.spawn else None
    recorded = Recorded(args)
    target = rrd
    if args.serve and rrd is None:
        recorded._tmp = tempfile.TemporaryDirectory(prefix="snakesim-rrd-")
        target = Path(recorded._tmp.name) / "recording.rrd"
    try:
        with recording_to(rrd=target, spawn_url=spawn_url, name=label) as recording:
            log_into(recording, recorded)
    except BaseException:
        if recorded._tmp is not None:
            recorded._tmp.cleanup()
        raise
    if rrd is not None and not getattr(args, "quiet", False):
        print(f"wrote {rrd} (open it with: .venv/bin/rerun {rrd}, or snakesim view {rrd} --serve)")
    if spawn_url is not None:
        print("sent the recording to Rerun's native viewer")
    if args.serve:
        recorded.served = target
    return recorded


# -- replay ---------------------------------------------------------------------------------------
def check_replay(args: argparse.Namespace) -> Path | None:
    from snakesim.cli.errors import UserError

    if not 1 <= args.episodes <= MAX_EPISODES:
        raise UserError(f"--episodes must be in [1, {MAX_EPISODES}], got {args.episodes}")
    if args.episodes > 1 and not wants_rerun(args):
        raise UserError(
            "--episodes applies to --rrd, --spawn and --serve; figures and animations show one episode"
        )
    return check_outputs(args)


def replay(args: argparse.Namespace, agent: Any, rrd: Path | None) -> Recorded:
    """Records ``args.episodes`` episodes of ``agent`` for --rrd/--spawn/--serve (``serve()`` the
    result to serve it)."""
    from snakesim.envs.env import make_env
    from snakesim.envs.wrappers import RerunLogger
    from snakesim.viewer import replay as replay_module

    config = make_env(**agent.env_kwargs).config
    dt = config["snake"]["dt"]
    longest = config["max_episode_steps"] * config["physics_steps_per_env_step"] * dt
    if args.seconds is not None:
        longest = min(longest, args.seconds + config["physics_steps_per_env_step"] * dt)
    if args.episodes * longest > MAX_SECONDS:
        raise RecordingError(
            f"{args.episodes} episodes of up to {longest:.1f} s could exceed the {MAX_SECONDS:g} simulated "
            "seconds a recording holds (LIMITS['recording_seconds']); record fewer --episodes or pass "
            "--seconds"
        )

    def log_into(recording, recorded: Recorded) -> None:
        env = RerunLogger(make_env(**agent.env_kwargs), recording)
        for k in range(args.episodes):
            agent.restart()
            rec = replay_module.record(
                lambda obs: agent.act(obs, args.deterministic),
                agent.env_kwargs,
                seconds=args.seconds,
                seed=args.seed + k,
                env=env,
            )
            recorded.episodes.append(rec)
            outcome = "reached the goal" if rec.terminated else "did not reach the goal"
            print(
                f"recorded episode {k + 1} (seed {args.seed + k}): {rec.duration:.2f} s "
                f"({len(rec.times) - 1} steps), {outcome}, return {rec.ret:.1f}"
            )
        env.close()

    return _record(args, rrd, log_into, f"{Path(agent.path).name}, seed {args.seed}")
