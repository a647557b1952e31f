"""Measures a model card's table with the card's own commands and keeps what they printed, so that a test
(snake-py/tests/test_card_numbers.py) checks the card against the last measurement instead of numbers
copied by hand.

    .venv/bin/python scripts/card_numbers.py pegs-10|sand-10 [--reuse DIR]

runs, for the card's rows, `snakesim evaluate ... --episodes 100 --seed 900000 --json DIR/ROW.json`
(about 12 minutes on the 2-core machine for pegs-10: the agent 1.5, `baseline:steer` 5.7,
`baseline:gait` 4.4), then writes models/measured/CARD.json: each row's summary (the JSON without its
per-episode list), the commands, the date and the commit. `--reuse DIR --at DATE,COMMIT` takes the JSON
files already in DIR (an earlier run of the same commands, on that date at that commit) instead.
"""

from __future__ import annotations

import argparse
import datetime
import json
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]

#: Each card's measured rows: the row's name in models/measured/CARD.json and its command's arguments.
CARDS = {
    "pegs-10": {
        "agent": ["models/pegs-10.safetensors"],
        "steer": ["baseline:steer", "--env-from", "models/pegs-10.safetensors"],
        "gait": ["baseline:gait", "--env-from", "models/pegs-10.safetensors"],
    },
    "sand-10": {
        "agent": ["models/sand-10.safetensors"],
        "steer": ["baseline:steer", "--env-from", "models/sand-10.safetensors"],
        "gait": ["baseline:gait", "--env-from", "models/sand-10.safetensors"],
        # The best hand controller found (experiments/sand-patch): steer driving the wave harder.
        "hold": ["baseline:steer", "--hold", "0.5,1", "--env-from", "models/sand-10.safetensors"],
    },
}
EPISODES = ["--episodes", "100", "--seed", "900000"]


def command(arguments: list[str], out: Path) -> list[str]:
    return ["snakesim", "evaluate", *arguments, *EPISODES, "--no-progress", "--json", str(out)]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("card", choices=sorted(CARDS))
    parser.add_argument("--reuse", type=Path, help="a folder of the rows' JSON files from an earlier run")
    parser.add_argument("--at", metavar="DATE,COMMIT", help="with --reuse: when and at which commit it ran")
    args = parser.parse_args()
    if (args.reuse is None) != (args.at is None):
        parser.error("--reuse and --at go together")
    folder = args.reuse or REPO / "out" / f"card-{args.card}"
    folder.mkdir(parents=True, exist_ok=True)
    rows = {}
    for row, arguments in CARDS[args.card].items():
        out = folder / f"{args.card}-{row}.json"
        if args.reuse is None:
            run = command(arguments, out)
            subprocess.run([str(REPO / ".venv" / "bin" / run[0]), *run[1:]], cwd=REPO, check=True)
        summary = json.loads(out.read_text())
        summary.pop("per_episode", None)
        rows[row] = {"command": " ".join(command(arguments, Path(f"{row}.json"))[:-3]), **summary}
    if args.at is not None:
        date, commit = args.at.split(",")
    else:
        head = ["git", "rev-parse", "--short", "HEAD"]
        commit = subprocess.run(head, cwd=REPO, capture_output=True, text=True).stdout.strip()
        date = datetime.date.today().isoformat()
    record = {"card": f"models/{args.card}.md", "measured": date, "commit": commit, "rows": rows}
    target = REPO / "models" / "measured" / f"{args.card}.json"
    target.parent.mkdir(exist_ok=True)
    target.write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {target.relative_to(REPO)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
