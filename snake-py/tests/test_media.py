"""Granular media from Python (docs/media.md): snakesim.media.rft_alpha against Li et al.'s Eq. 1 written
out here independently, the probe against the law, snake-cli probe's bad input, and the quick
validation cases (snakesim validate)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from snakesim.media import probe, rft_alpha

REPO = Path(__file__).resolve().parents[2]
SNAKE_CLI = REPO / "target" / "release" / "snake-cli"

# Li, Zhang and Goldman 2013, Science 339:1408, the generic coefficients as the paper prints them.
A00, A10, B11, B01, BM11 = 0.206, 0.169, 0.212, 0.358, 0.055
C11, C01, CM11, D10 = -0.124, 0.253, 0.007, 0.088


def li_eq1(b, g):
    az = A00 + A10 * np.cos(2 * b) + B11 * np.sin(2 * b + g) + B01 * np.sin(g) + BM11 * np.sin(-2 * b + g)
    ax = C11 * np.cos(2 * b + g) + C01 * np.cos(g) + CM11 * np.cos(-2 * b + g) + D10 * np.sin(2 * b)
    return ax, az


def test_rft_alpha_is_li_eq1_on_its_domain():
    b, g = np.meshgrid(np.linspace(-np.pi / 2, np.pi / 2, 61), np.linspace(-np.pi / 2, np.pi / 2, 61))
    ax, az = rft_alpha(b, g)
    ex, ez = li_eq1(b, g)
    assert ax.shape == b.shape
    assert np.max(np.abs(ax - ex)) <= 1e-12
    assert np.max(np.abs(az - ez)) <= 1e-12


def test_alpha_z_of_a_horizontal_plate_pushed_down_is_one():
    # The generic coefficients sum to 1.000 (A00 + A10 + B11 + B01 + B-11): Li's normalisation, with
    # gamma = +pi/2 straight down, so that zeta is the medium's alpha_z there.
    ax, az = rft_alpha(0.0, math.pi / 2)
    assert abs(float(az) - 1.0) <= 1e-12 and abs(float(ax)) <= 1e-12


def test_other_angles_follow_lis_symmetries():
    b, g = 0.4, 2.5  # gamma beyond pi/2: the mirror image (-beta, pi - gamma), alpha_x flipped
    ax, az = rft_alpha(b, g)
    ex, ez = li_eq1(-b, math.pi - g)
    assert abs(float(ax) + ex) <= 1e-12 and abs(float(az) - ez) <= 1e-12
    ax, az = rft_alpha(b + math.pi, 0.3)
    ex, ez = li_eq1(b, 0.3)
    assert abs(float(ax) - ex) <= 1e-12 and abs(float(az) - ez) <= 1e-12


def test_a_coefficient_table_is_read_whole():
    table = {"A00": 1, "A10": 0, "B11": 0, "B01": 0, "B-11": 0, "C11": 0, "C01": 0, "C-11": 0, "D10": 0}
    _, az = rft_alpha(0.3, 0.2, table)
    assert float(az) == 1.0
    with pytest.raises(ValueError, match="coefficients"):
        rft_alpha(0.3, 0.2, {k: v for k, v in table.items() if k != "D10"})
    with pytest.raises(ValueError, match="unknown coefficient table"):
        rft_alpha(0.3, 0.2, "mud")
    with pytest.raises(ValueError, match="finite"):
        rft_alpha(float("nan"), 0.2)


def sand_world(folder: Path) -> Path:
    world = folder / "sand.yaml"
    world.write_text(
        "media:\n  - {medium: granular, area: [-1, -1, 1, 1], depth: 0.5, zeta: 2.0e5, friction: 0.2, "
        "element: 0.005}\n"
    )
    return world


@pytest.mark.parametrize("beta,gamma", [(0, 90), (30, 45), (-45, 20), (90, 0), (-30, -60), (60, -10)])
def test_the_probe_is_the_law_over_the_plate_within_2_percent(tmp_path, beta, gamma):
    r = probe(sand_world(tmp_path), (0.0381, 0.0254), beta, gamma, 0.076)["result"]
    ex, ez = li_eq1(math.radians(beta), math.radians(gamma))
    law = 2.0e5 * 0.0381 * 0.0254 * 0.076
    assert math.hypot(r["force_x"] + ex * law, r["force_z"] - ez * law) <= 0.02 * law * math.hypot(ex, ez)


@pytest.mark.skipif(not SNAKE_CLI.exists(), reason="needs the release build of snake-cli")
def test_snake_cli_probe_prints_json_and_refuses_bad_angles(tmp_path):
    world = sand_world(tmp_path)
    base = [str(SNAKE_CLI), "probe", "--world", str(world), "--plate", "0.04,0.02", "--depth", "0.05"]
    done = subprocess.run([*base, "--beta", "0", "--gamma", "90", "--json"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)["result"]
    assert abs(result["force_z"] / (2.0e5 * 0.04 * 0.02 * 0.05) - 1.0) < 0.02
    bad = subprocess.run([*base, "--beta", "120", "--gamma", "0"], capture_output=True, text=True)
    assert bad.returncode != 0 and bad.stdout == ""
    assert bad.stderr.count("\n") == 1 and "--beta" in bad.stderr
    (tmp_path / "neg.yaml").write_text(
        "media:\n  - {medium: granular, area: [-1, -1, 1, 1], depth: 0.5, zeta: -3, friction: 0.2}\n"
    )
    bad = subprocess.run(
        [*base[:2], "--world", str(tmp_path / "neg.yaml"), *base[4:], "--beta", "0", "--gamma", "0"],
        capture_output=True,
        text=True,
    )
    assert bad.returncode != 0 and "media[0]: zeta" in bad.stderr and bad.stderr.count("\n") == 1


def test_the_sandfish_wave_is_maladens_sine_on_the_segments():
    # y = A sin(2 pi (x / lambda + f t)) along the body (head at 0, body along -x): each segment takes the
    # slope at its centre, each joint the difference of its segments' angles; written here independently.
    from snakesim import _core

    robot = REPO / "robots" / "sandfish-robot.yaml"
    a, lam, f, seg = 0.091, 0.455, 1.0, 0.065
    got = _core.sandfish_targets(str(robot), a, lam, f, seg, 480)
    t = np.arange(1, 481)[:, None] / 240.0
    x = -(np.arange(7)[None, :] + 0.5) * seg
    k = 2 * np.pi / lam
    heading = np.arctan(a * k * np.cos(k * x + 2 * np.pi * f * t))
    assert got.shape == (480, 6)
    assert np.max(np.abs(got - (heading[:, 1:] - heading[:, :-1]))) <= 1e-12
    with pytest.raises(ValueError, match="amplitude"):
        _core.sandfish_targets(str(robot), -1.0, lam, f, seg, 10)


def test_the_quick_validation_cases_run_and_pass():
    from snakesim.validation import select

    results = [case.run() for case in select([], quick=True)]
    names = {r.name for r in results}
    assert {f"sand.sandfish-rigid-ground-{f}hz" for f in ("0.5", "1", "1.5")} <= names
    for r in results:
        assert math.isfinite(r.simulated) and math.isfinite(r.published), r
        assert r.passed, r


def test_snakesim_validate_names_a_case_or_fails_in_one_line():
    done = subprocess.run(
        [sys.executable, "-m", "snakesim", "validate", "sand.alpha-*", "sand.probe-beta0-*", "--json", "-"],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    assert [r["name"] for r in document["results"]] == ["sand.alpha-z-plate-down", "sand.probe-beta0-gamma90"]
    bad = subprocess.run(
        [sys.executable, "-m", "snakesim", "validate", "nothing"], capture_output=True, text=True
    )
    assert bad.returncode == 1 and bad.stderr.count("\n") == 1 and "no validation case matches" in bad.stderr
