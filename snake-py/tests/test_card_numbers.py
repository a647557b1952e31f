"""A model card's measured table is what its commands printed last: models/measured/CARD.json, written
by scripts/card_numbers.py from `snakesim evaluate --json`, against the card's rows (and the pages that
quote them: docs/tasks.md, the README's envs table)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
MEASURED = sorted((REPO / "models" / "measured").glob("*.json"))


def cells(row: dict) -> str:
    """The card's columns after the name: success (95 % Wilson), time to goal, speed, path efficiency,
    cost of transport, as the cards print them."""
    low, high = row["success_rate_ci95"]
    success = f"{row['success_rate']:.2f} ({low:.3f}-{high:.3f})"
    if row["success_rate"] >= 0.9:
        success = f"**{row['success_rate']:.2f}** ({low:.3f}-{high:.3f})"
    steps = row["mean_steps_to_goal"]
    reached = steps is not None and steps == steps  # nan: no episode reached the goal
    time = f"{steps:.1f} steps, {row['mean_seconds_to_goal']:.2f} s" if reached else "-"
    return (
        f"{success} | {time} | {row['mean_speed']:.3f} m/s | {row['mean_path_efficiency']:.3f} | "
        f"{row['mean_cost_of_transport']:.1f} |"
    )


def test_there_is_a_measurement():
    assert [p.name for p in MEASURED] == ["pegs-10.json", "sand-10.json"]


@pytest.mark.parametrize("path", MEASURED, ids=lambda p: p.stem)
def test_the_card_shows_its_last_measurement(path):
    record = json.loads(path.read_text())
    card = (REPO / record["card"]).read_text()
    for name, row in record["rows"].items():
        assert row["episodes"] == 100 and row["seed"] == 900000, name
        assert cells(row) in card, f"{record['card']}: the {name} row is not {cells(row)!r}"
    # The card says when, at which commit and with which commands ("Evaluated with", lines wrapped).
    words = " ".join(card.split())
    assert f"{record['measured']} at commit {record['commit']}" in words
    for name in ("agent", "steer"):
        assert record["rows"][name]["command"] in words, name


def test_the_pages_quoting_pegs_10_agree():
    record = json.loads((REPO / "models" / "measured" / "pegs-10.json").read_text())
    steer = record["rows"]["steer"]
    low, high = steer["success_rate_ci95"]
    tasks = (REPO / "docs" / "tasks.md").read_text()
    assert (
        f"| {steer['success_rate']:.2f} ({low:.2f}-{high:.2f}) | {steer['mean_seconds_to_goal']:.2f} s | "
        f"{steer['mean_speed']:.3f} m/s | {steer['mean_path_efficiency']:.3f} | "
        f"{steer['mean_cost_of_transport']:.1f} |" in tasks
    )
    readme = (REPO / "README.md").read_text()
    assert f"(`baseline:steer` {steer['success_rate']:.2f})" in readme
