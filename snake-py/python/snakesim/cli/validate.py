"""``snakesim validate``: every validation case (snakesim.validation) as one table of published value,
source, simulated value, tolerance and pass or FAIL; exit 1 when any case fails."""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys

from snakesim.cli.errors import UserError, check_writable


def _number(value: float) -> str:
    if not math.isfinite(value):
        return str(value)
    return f"{value:.4g}"


def _table(results) -> str:
    rows = [("case", "quantity", "published", "source", "simulated", "tolerance", "result")]
    for r in results:
        unit = f" {r.unit}" if r.unit else ""
        rows.append(
            (
                r.name,
                r.quantity,
                _number(r.published) + unit,
                r.source,
                _number(r.simulated) + unit,
                r.tolerance,
                "pass" if r.passed else "FAIL",
            )
        )
    widths = [max(len(row[k]) for row in rows) for k in range(len(rows[0]))]
    return "\n".join("  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in rows)


def cmd_validate(args: argparse.Namespace) -> int:
    from snakesim.files import write_atomically
    from snakesim.validation import ValidationError, select

    out = None
    if args.json not in (None, "-"):
        out = check_writable(args.json, "--json")
    try:
        chosen = select(args.cases, quick=args.quick)
    except ValidationError as error:
        raise UserError(str(error)) from None
    if not chosen:
        raise UserError("no case to run (--quick leaves only the quick cases)")
    results = []
    for case in chosen:
        if args.json != "-":
            print(f"running {case.name}", file=sys.stderr)
        results.append(case.run())
    failed = [r.name for r in results if not r.passed]
    document = {"results": [dataclasses.asdict(r) for r in results], "failed": failed}
    text = json.dumps(document, indent=2) + "\n"
    if args.json == "-":
        sys.stdout.write(text)
    else:
        print(_table(results))
        print(f"{len(results) - len(failed)} of {len(results)} cases pass")
        if out is not None:

            def write(path: str) -> None:
                with open(path, "w") as f:
                    f.write(text)

            write_atomically(out, write)
    return 1 if failed else 0


def add_parser(sub) -> None:
    p = sub.add_parser(
        "validate",
        help="run the validation cases: simulated against published values (docs/media.md)",
        description="Run snakesim's validation cases (snakesim.validation: skin friction, granular "
        "media, water) and print each case's published value and source, the simulated value, the "
        "tolerance and pass or FAIL; exit 1 when any fails. Cases read the repository's robots/ "
        "(SNAKESIM_ROBOTS names another folder).",
    )
    p.add_argument("cases", nargs="*", metavar="CASE", help="case names or shell globs (default: all)")
    p.add_argument("--quick", action="store_true", help="only the quick cases (seconds each)")
    p.add_argument("--json", metavar="PATH", help="also write the results as JSON (- : print only JSON)")
    p.set_defaults(func=cmd_validate)
