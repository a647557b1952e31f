"""Errors about a library function's own arguments, which the library names by their Python names and
a command by its flags (``max_evals`` here, ``--max-evals`` in ``snakesim calibrate``): as ripgrep's flag
docs ask, the parser, not the library, puts the flag's name in an error."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping


@dataclasses.dataclass(frozen=True)
class Keyword:
    """An argument of a library function, named in an :class:`ArgumentError`."""

    name: str


class ArgumentError(ValueError):
    """A message whose parts may name arguments (:class:`Keyword`): ``str(error)`` names them by their
    Python names, :meth:`naming` with the names a caller uses for them (a command's flags)."""

    def __init__(self, *parts: str | Keyword) -> None:
        self.parts = parts
        super().__init__("".join(p.name if isinstance(p, Keyword) else p for p in parts))

    def naming(self, names: Mapping[str, str]) -> str:
        """The message with each argument named as ``names`` says (others by their Python names)."""
        if not self.parts:
            return str(self)
        return "".join(names.get(p.name, p.name) if isinstance(p, Keyword) else p for p in self.parts)
