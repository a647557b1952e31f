#!/usr/bin/env python3
"""Checks that requirements locks hold only `name==version` pins from the package index.

    python3 scripts/check_lock.py [LOCK ...]     (default: requirements.lock requirements-test.lock)

A line is a pin (`name==version`, optionally with extras), a comment or blank. Anything else (a local
path, a URL, `-e`, an option, a range) could only be installed on the machine that wrote it, or would
install something else tomorrow: the check names each such line and exits 1. The locks are installed
together (requirements-test.lock over requirements.lock), so a package pinned twice, in one file or
two, is an error too. Standard library only: it runs before the Python environment exists
(scripts/setup) and as a test (scripts/test).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

# PEP 508 names and PEP 440 public versions, as `pip freeze` writes them.
_PIN = re.compile(
    r"^[A-Za-z0-9](?:[A-Za-z0-9._-]*[A-Za-z0-9])?"  # name
    r"(?:\[[A-Za-z0-9._,-]+\])?"  # extras
    r"==[0-9]+(?:\.[0-9]+)*(?:(?:a|b|rc)[0-9]+)?(?:\.post[0-9]+)?(?:\.dev[0-9]+)?$"
)


def problems(text: str) -> list[tuple[int, str]]:
    """(line number, line) of every line that is neither a `name==version` pin, a comment nor blank."""
    bad = []
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        if not _PIN.match(stripped):
            bad.append((number, line))
    return bad


def pinned_name(line: str) -> str:
    """The normalised package name of a pin line (PEP 503: case and runs of -_. do not matter)."""
    return re.sub(r"[-_.]+", "-", re.split(r"[\[=]", line.strip(), maxsplit=1)[0]).lower()


def main(argv: list[str]) -> int:
    root = Path(__file__).resolve().parent.parent
    paths = [Path(a) for a in argv] or [root / "requirements.lock", root / "requirements-test.lock"]
    failed = False
    seen: dict[str, tuple[Path, int]] = {}
    for path in paths:
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            print(f"error: cannot read {path}: {error}", file=sys.stderr)
            failed = True
            continue
        bad = problems(text)
        for number, line in bad:
            shown = line if len(line) <= 100 else line[:97] + "..."
            print(
                f"error: {path}:{number}: {shown.strip()!r} is not a name==version pin from the package "
                "index (no paths, URLs, -e or ranges)",
                file=sys.stderr,
            )
        failed = failed or bool(bad)
        bad_lines = {number for number, _ in bad}
        for number, line in enumerate(text.splitlines(), start=1):
            stripped = line.strip()
            if not stripped or stripped.startswith("#") or number in bad_lines:
                continue
            name = pinned_name(stripped)
            if name in seen:
                first, first_line = seen[name]
                print(
                    f"error: {path}:{number}: {name} is pinned again (first at {first}:{first_line}); "
                    "the locks are installed together: pin each package once",
                    file=sys.stderr,
                )
                failed = True
            else:
                seen[name] = (path, number)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
