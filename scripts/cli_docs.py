"""Writes docs/cli.md from the two commands' own --help (the flags are defined once, in clap and in
argparse over snake-rl's flag table; this page only shows them). snake-py/tests/test_cli.py checks
that the page is current.

    .venv/bin/python scripts/cli_docs.py [--check]
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
PAGE = REPO / "docs" / "cli.md"
SNAKE_CLI = ("run", "atlas", "env", "bench", "train", "probe")
SNAKESIM = (
    "train",
    "evaluate",
    "plot",
    "replay",
    "export",
    "sweep",
    "search",
    "convert",
    "view",
    "calibrate",
    "validate",
)

INTRO = """# The command lines

Two commands, one set of names: `snake-cli` (Rust; no Python needed) runs gaits, robots, worlds, the
env and the native trainer; `snakesim` (the Python package) trains with either trainer, evaluates,
plots, replays, exports, sweeps and records. `snake-cli train` and `snakesim train` take the same run
configuration flags (both built from `snake_rl::flags::FLAGS`) and write the same run directory; an
output path is `--out` or `--output` in both. Formats of what they write: [formats.md](formats.md).

Errors are one line on stderr and a non-zero exit (2 for bad usage, 1 for anything else, 130 after
Ctrl-C). This page is generated from the commands' own `--help` by `scripts/cli_docs.py`; a test
checks that it is current.
"""


def help_text(argv: list[str]) -> str:
    # A fixed width, so that argparse wraps the same way on every terminal.
    env = {**os.environ, "COLUMNS": "100"}
    out = subprocess.run(argv, capture_output=True, text=True, env=env, check=True)
    return out.stdout.rstrip()


def snake_cli_path() -> Path:
    """The release build of snake-cli (``bash scripts/setup`` makes it), in cargo's target folder."""
    return Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target")) / "release" / "snake-cli"


def page() -> str:
    snake_cli = str(snake_cli_path())
    snakesim = [sys.executable, "-m", "snakesim"]
    parts = [INTRO, "## snake-cli\n"]
    for command in SNAKE_CLI:
        parts.append(f"### snake-cli {command}\n\n```\n{help_text([snake_cli, command, '--help'])}\n```\n")
    parts.append("## snakesim\n")
    for command in SNAKESIM:
        parts.append(f"### snakesim {command}\n\n```\n{help_text([*snakesim, command, '--help'])}\n```\n")
    return "\n".join(parts)


def main() -> int:
    text = page()
    if "--check" in sys.argv[1:]:
        if PAGE.read_text() != text:
            print(f"{PAGE} is out of date: run {sys.executable} scripts/cli_docs.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(text)
    print(f"wrote {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
