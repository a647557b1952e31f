"""Progress for a person waiting on a command (``snakesim evaluate``, ``calibrate``, ``sweep``,
``export`` of an SB3 zip): on
a terminal, a bar on stderr with the total, the rate and an estimate of the time left (tqdm); when
stderr is not a terminal (piped, a log file), one plain line per step of progress; nothing on stdout,
so that ``--json -`` prints JSON alone."""

from __future__ import annotations

import sys
import time
from typing import TextIO


def clock(seconds: float) -> str:
    """``75.2`` -> ``1:15``; ``3725`` -> ``1:02:05``."""
    seconds = max(0, int(round(seconds)))
    hours, rest = divmod(seconds, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


class Progress:
    """Progress towards ``total`` ``unit`` (e.g. 100 episodes), labelled ``label``.

    ``show``: True draws the bar (as ``snakesim train --progress`` does), False shows nothing, None
    (the default) draws the bar when ``stream`` (stderr) is a terminal and otherwise writes one line
    per :meth:`update` that advances, ``label: n/total unit, M:SS elapsed, about M:SS left[, note]``.
    :meth:`update` takes the count done so far (not an increment) and an optional note (the best error
    so far); a count may end below ``total`` (a fit that converges early). Use as a context manager,
    or call :meth:`close`."""

    def __init__(
        self,
        total: int,
        unit: str,
        label: str,
        show: bool | None = None,
        stream: TextIO | None = None,
        estimate: bool = True,
    ) -> None:
        self.total = int(total)
        # False where steps differ too much for a linear estimate of the time left (export's load).
        self.estimate = estimate
        self.unit = unit
        self.label = label
        self.stream = sys.stderr if stream is None else stream
        tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.mode = "none" if show is False else "bar" if show or tty else "lines"
        self.done = 0
        self.start = time.monotonic()
        self.bar = None
        if self.mode == "bar":
            from tqdm import tqdm

            no_estimate = "{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}{postfix}]"
            shape = {} if estimate else {"bar_format": no_estimate}
            self.bar = tqdm(
                total=self.total,
                unit=unit,
                desc=label,
                dynamic_ncols=True,
                file=self.stream,
                mininterval=0.5,
                **shape,
            )

    def update(self, done: int, note: str | None = None) -> None:
        done = int(done)
        if self.bar is not None:
            if note is not None:
                self.bar.set_postfix_str(note, refresh=False)
            self.bar.update(done - self.done)
        elif self.mode == "lines" and done > self.done:
            self.stream.write(self.line(done, time.monotonic() - self.start, note) + "\n")
            self.stream.flush()
        self.done = max(self.done, done)

    def line(self, done: int, elapsed: float, note: str | None = None) -> str:
        """The plain line of ``done`` after ``elapsed`` seconds."""
        text = f"{self.label}: {done}/{self.total} {self.unit}, {clock(elapsed)} elapsed"
        if self.estimate and 0 < done < self.total:
            text += f", about {clock(elapsed * (self.total - done) / done)} left"
        return text if note is None else f"{text}, {note}"

    def write(self, text: str) -> None:
        """A line of its own on the stream, above the bar on a terminal."""
        if self.bar is not None:
            self.bar.write(text, file=self.stream)
        else:
            print(text, file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
