"""Layers a checkout's own virtual environment over the shared one that holds the locked packages.

    python scripts/layer_venv.py .venv BASE

The shared environment (BASE, ~7 GB with torch) is built once per lock file and reused by every
checkout and by CI. What is specific to a checkout (the editable snakesim install: a .pth naming the
checkout's own snake-py/python, and the `snakesim` command) goes into the checkout's own small .venv/,
which sees BASE's packages through a .pth that adds BASE's site-packages (and runs BASE's own .pth
files). BASE's commands (pytest, ruff, maturin, tensorboard, rerun, ...) get a counterpart in .venv/bin
that runs .venv's interpreter, so they import this checkout's snakesim. Layering again over another
BASE (scripts/setup's environment, then scripts/test's larger one, or back) first removes the commands
the previous layering made (listed in .venv/.snakesim-layer-commands).
"""

from __future__ import annotations

import sys
from pathlib import Path

# Written by `python -m venv` itself; never replaced by BASE's counterparts.
OWN = ("python", "pip", "activate", "Activate.ps1")
PTH = "_snakesim_base.pth"
MADE = ".snakesim-layer-commands"


def site_packages(venv: Path) -> Path:
    found = sorted(venv.glob("lib/python3*/site-packages"))
    if len(found) != 1:
        raise SystemExit(f"error: {venv} has {len(found)} site-packages directories, expected one")
    return found[0]


def layer(venv: Path, base: Path) -> int:
    base_site = site_packages(base)
    made_list = venv / MADE
    if made_list.is_file():
        for name in made_list.read_text().split():
            old = venv / "bin" / name
            if not name.startswith(OWN) and "/" not in name and (old.is_symlink() or old.is_file()):
                old.unlink()
    (site_packages(venv) / PTH).write_text(f"import site; site.addsitedir({str(base_site)!r})\n")
    python = str(venv.resolve() / "bin" / "python").encode()
    # Longest first, so that .../python3.11 is not read as .../python3 followed by ".11".
    names = (f"python3.{sys.version_info[1]}", "python3", "python")
    interpreters = [f"{base}/bin/{name}".encode() for name in names]
    made = []
    for command in sorted((base / "bin").iterdir()):
        if command.name.startswith(OWN) or not command.is_file():
            continue
        target = venv / "bin" / command.name
        if target.is_symlink() or target.exists():
            target.unlink()
        text = command.read_bytes()
        if not text.startswith(b"\x7fELF") and any(i in text for i in interpreters):
            # A Python entry point (a shebang, or pip's /bin/sh trampoline for long paths): the same
            # script, run by this venv's interpreter.
            for interpreter in interpreters:
                text = text.replace(interpreter, python)
            target.write_bytes(text)
            target.chmod(0o755)
        else:
            # A native program (ruff, maturin): nothing in it names an interpreter.
            target.symlink_to(command)
        made.append(command.name)
    made_list.write_text("".join(f"{name}\n" for name in made))
    return len(made)


def main() -> None:
    if len(sys.argv) != 3:
        raise SystemExit("usage: python scripts/layer_venv.py VENV BASE")
    venv, base = Path(sys.argv[1]), Path(sys.argv[2])
    for path in (venv, base):
        if not (path / "pyvenv.cfg").is_file():
            raise SystemExit(f"error: {path} is not a virtual environment (no pyvenv.cfg)")
    if venv.resolve() == base.resolve():
        raise SystemExit(f"error: {venv} is the shared environment itself")
    made = layer(venv, base)
    print(f"{venv}: layered over {base} ({made} commands)")


if __name__ == "__main__":
    main()
