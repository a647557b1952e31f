"""The ``snakesim`` command: :mod:`snakesim.cli.app` assembles one module per subcommand."""

from __future__ import annotations


def main(argv: list[str] | None = None) -> int:
    """The console script's entry point (``snakesim = snakesim.cli:main``)."""
    # Imported here so that importing the package (e.g. for snakesim.cli.errors) loads no subcommand.
    from snakesim.cli.app import main as run

    return run(argv)
