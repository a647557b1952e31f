"""The Rerun viewer as a process: finding it, spawning it on a display, serving a recording to the
web viewer on 127.0.0.1, and the checks (ports, display) made before anything runs."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from snakesim.viewer.recording import RecordingError


# -- the viewer processes -------------------------------------------------------------------------
def rerun_executable() -> str:
    """The Rerun viewer program shipped with rerun-sdk."""
    try:
        import rerun_cli
    except ImportError:  # pragma: no cover
        raise RecordingError("the Rerun viewer (rerun-sdk's rerun_cli) is not installed") from None
    exe = Path(rerun_cli.__file__).with_name("rerun")
    if not exe.is_file():  # pragma: no cover
        raise RecordingError(f"the Rerun viewer is missing: {exe} does not exist")
    return str(exe)


def check_port_free(port: int, flag: str) -> None:
    """RecordingError unless ``port`` can be listened on at 127.0.0.1."""
    if not 1 <= port <= 65535:
        raise RecordingError(f"{flag} must be a port in [1, 65535], got {port}")
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError as error:
            raise RecordingError(
                f"{flag}: port {port} on 127.0.0.1 is in use ({error.strerror or error}); pick another port"
            ) from None


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def check_display() -> None:
    """RecordingError where the native viewer cannot open a window (Linux without a display)."""
    if sys.platform.startswith("linux") and not (
        os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    ):
        raise RecordingError(
            "--spawn opens Rerun's native viewer, which needs a display (DISPLAY and WAYLAND_DISPLAY are "
            "unset); watch in a browser with --serve, or write a file with --rrd"
        )


def _last_line(path: Path) -> str:
    try:
        lines = [line.strip() for line in path.read_text(errors="replace").splitlines() if line.strip()]
    except OSError:
        return ""
    return lines[-1] if lines else ""


def _wait_for_port(process: subprocess.Popen, port: int, log: Path, what: str, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise RecordingError(
                f"{what} exited with status {process.returncode} before it was ready: "
                f"{_last_line(log) or 'no message'}"
            )
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.settimeout(0.5)
            if s.connect_ex(("127.0.0.1", port)) == 0:
                return
        time.sleep(0.1)
    process.terminate()
    raise RecordingError(f"{what} did not start listening on 127.0.0.1:{port} within {timeout:g} s")


#: How long a spawned viewer must stay up after it listens: one without a usable display (an X server
#: that is not there) opens its port first and exits a moment later.
SPAWN_GRACE = 2.0


def _spawn(extra: list[str]) -> int:
    """Starts Rerun's native viewer detached (it stays open after we exit), its gRPC server on
    127.0.0.1; returns that port once it listens and stayed up. RecordingError if it does not."""
    check_display()
    port = _free_port()
    fd, name = tempfile.mkstemp(prefix="snakesim-rerun-viewer-", suffix=".log")
    log = Path(name)
    try:
        with os.fdopen(fd, "wb") as out:
            process = subprocess.Popen(
                [rerun_executable(), "--bind", "127.0.0.1", "--port", str(port), *extra],
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        _wait_for_port(process, port, log, "the Rerun viewer")
        try:
            process.wait(timeout=SPAWN_GRACE)
        except subprocess.TimeoutExpired:
            return port
        raise RecordingError(
            f"the Rerun viewer exited with status {process.returncode}: {_last_line(log) or 'no message'}"
        )
    finally:
        log.unlink(missing_ok=True)  # a running viewer keeps writing to it, unnamed


def spawn_viewer() -> str:
    """Starts Rerun's native viewer; returns the gRPC URL to stream a recording to."""
    port = _spawn(["--expect-data-soon"])
    return f"rerun+http://127.0.0.1:{port}/proxy"


def spawn_file(path: str | os.PathLike) -> None:
    """Opens the recording ``path`` in Rerun's native viewer."""
    _spawn([os.fspath(path)])


def serve(path: str | os.PathLike, *, web_port: int, grpc_port: int, ready=None) -> int:
    """Serves the recording ``path`` with Rerun's web viewer on 127.0.0.1 until Ctrl-C (or the server
    ends); ``ready(url)`` is called once the page can be opened. Returns 0 after Ctrl-C."""
    check_port_free(web_port, "--web-port")
    check_port_free(grpc_port, "--grpc-port")
    if web_port == grpc_port:
        raise RecordingError("--web-port and --grpc-port must differ")
    with tempfile.TemporaryDirectory(prefix="snakesim-serve-") as tmp:
        log = Path(tmp) / "rerun.log"
        with open(log, "wb") as out:
            process = subprocess.Popen(
                [
                    rerun_executable(),
                    "--serve-web",
                    "--bind",
                    "127.0.0.1",
                    "--port",
                    str(grpc_port),
                    "--web-viewer-port",
                    str(web_port),
                    os.fspath(path),
                ],
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=subprocess.STDOUT,
                start_new_session=True,  # Ctrl-C reaches us; we stop it
            )
        try:
            # A `kill` or a closed terminal stops the server as Ctrl-C does, never leaving it behind.
            stops = {sig: signal.getsignal(sig) for sig in (signal.SIGTERM, signal.SIGHUP)}
            for sig in stops:
                signal.signal(sig, _interrupt)
        except ValueError:  # not the main thread: signals stay as they are
            stops = {}
        try:
            _wait_for_port(process, web_port, log, "the Rerun web server")
            _wait_for_port(process, grpc_port, log, "the Rerun web server")
            url = web_viewer_url(web_port, grpc_port)
            if ready is not None:
                ready(url)
            process.wait()
            raise RecordingError(
                f"the Rerun web server stopped (status {process.returncode}): "
                f"{_last_line(log) or 'no message'}"
            )
        except KeyboardInterrupt:
            return 0
        finally:
            for sig, handler in stops.items():
                signal.signal(sig, handler)
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
                try:
                    process.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    process.kill()
                    process.wait()


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def web_viewer_url(web_port: int, grpc_port: int) -> str:
    """The page of the web viewer served on ``web_port`` showing the recording on ``grpc_port``."""
    from urllib.parse import quote

    return f"http://127.0.0.1:{web_port}/?url=" + quote(f"rerun+http://127.0.0.1:{grpc_port}/proxy", safe="")
