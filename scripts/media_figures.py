"""The figures and studies of docs/media.md ("Granular media"):

- docs/figures/media-alpha.png: Li et al.'s alpha_x and alpha_z over (beta, gamma), as their Fig. 2,
  from snakesim.media.rft_alpha (the simulator's own law);
- docs/figures/media-efficiency.png: the robot sandfish's wave efficiency against A/lambda beside
  Maladen et al.'s peak near 0.2 and measured 0.34;
- printed: a plain drop test (a box dropped into the sand: its depth and vertical speed), the element
  size and `elastic` studies (efficiency and the resting depth against each), the cube snake and
  yaw-pitch-16 on the sand's surface.

    .venv/bin/python scripts/media_figures.py
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from snakesim.media import rft_alpha  # noqa: E402
from snakesim.validation import sand  # noqa: E402
from snakesim.validation.simulate import RATE, ROBOTS, robot_gait_targets, run  # noqa: E402

FIGURES = Path(__file__).resolve().parents[1] / "docs" / "figures"


def alpha_maps() -> None:
    b, g = np.meshgrid(np.linspace(-90, 90, 181), np.linspace(-90, 90, 181))
    ax, az = rft_alpha(np.radians(b), np.radians(g))
    fig, axes = plt.subplots(1, 2, figsize=(9, 4), constrained_layout=True)
    for axis, values, name in zip(axes, (az, ax), ("alpha_z", "alpha_x")):
        image = axis.pcolormesh(b, g, values, cmap="RdBu_r", vmin=-1, vmax=1, shading="auto")
        axis.set_xlabel("beta (degrees)")
        axis.set_ylabel("gamma (degrees)")
        axis.set_title(f"{name} (generic; times zeta)")
        fig.colorbar(image, ax=axis)
    fig.savefig(FIGURES / "media-alpha.png", dpi=80)


def efficiency_figure() -> list[tuple[float, float]]:
    sweep = sand.efficiency_sweep()
    fig, axis = plt.subplots(figsize=(5, 3.5), constrained_layout=True)
    label = "snakesim (RFT), robot sandfish, 1 Hz"
    axis.plot([a for a, _ in sweep], [e for _, e in sweep], "o-", label=label)
    axis.axvline(0.2, color="grey", ls="--", label="Maladen et al.: peak near A/lambda 0.2")
    axis.axhline(0.34, color="k", ls=":", label="measured 0.34 +- 0.02 (A/lambda 0.2)")
    axis.set_xlabel("A / lambda")
    axis.set_ylabel("wave efficiency")
    axis.legend(fontsize=7)
    fig.savefig(FIGURES / "media-efficiency.png", dpi=80)
    return sweep


def world(text: str) -> Path:
    folder = Path(tempfile.mkdtemp())
    path = folder / "world.yaml"
    path.write_text(text)
    return path


def drop_test(extra: str = "") -> tuple[float, float, float]:
    """The robot sandfish held straight (zero targets) dropped from 5 cm above the sand: its depth
    after 2 s, its largest vertical speed in the last second, and its largest height swing there."""
    text = sand.SAND.replace("friction: 0.2}", f"friction: 0.2{extra}}}")
    targets = np.zeros((int(2 * RATE), 6))
    base = run(ROBOTS / "sandfish-robot.yaml", targets, world(text), (0.0, 0.0, 0.165, 0.0))
    z = base[:, 2]
    last = z[int(RATE) :]
    speed = np.abs(np.diff(last)).max() * RATE
    return 0.1 - z[-1], speed, last.max() - last.min()


def study() -> None:
    print("drop test (surface 0.1 m; depth of the centre after 2 s, m; last second: max |vz| m/s, swing m)")
    for elastic in (0.0005, 0.001, 0.002, 0.004):
        d, v, s = drop_test(f", elastic: {elastic}")
        print(f"  elastic {elastic}: depth {d:.4f}, max |vz| {v:.2e}, swing {s:.2e}")
    print("wave efficiency at A/lambda 0.2, 1 Hz, against the element size and elastic")
    for element in (0.02, 0.01, 0.005):
        text = sand.SAND.replace("friction: 0.2}", f"friction: 0.2, element: {element}}}")
        forward, wave = sand._sandfish_speed(text, 0.2, 1.0)
        print(f"  element {element}: efficiency {forward / wave:.4f}")
    for elastic in (0.0005, 0.001, 0.002, 0.004):
        text = sand.SAND.replace("friction: 0.2}", f"friction: 0.2, elastic: {elastic}}}")
        forward, wave = sand._sandfish_speed(text, 0.2, 1.0)
        print(f"  elastic {elastic}: efficiency {forward / wave:.4f}")
    for zeta in (1e5, 2e5, 1e6):
        text = sand.SAND.replace("zeta: 2.0e5", f"zeta: {zeta}")
        forward, wave = sand._sandfish_speed(text, 0.2, 1.0)
        print(f"  zeta {zeta:g}: efficiency {forward / wave:.4f}")
    for mu in (0.0, 0.1, 0.2, 0.4):
        text = sand.SAND.replace("friction: 0.2", f"friction: {mu}")
        forward, wave = sand._sandfish_speed(text, 0.2, 1.0)
        print(f"  friction {mu}: efficiency {forward / wave:.4f}")


def on_the_surface() -> None:
    """yaw-pitch-16 with its own gait on the sand (surface at the plane's height) and on the plane."""
    sand_world = Path(__file__).resolve().parents[1] / "worlds" / "sand.yaml"
    robot = ROBOTS / "yaw-pitch-16.yaml"
    targets = robot_gait_targets(robot, 10.0)
    for name, w in (("sand", sand_world), ("rigid plane, friction 0.3", world("ground_friction: 0.3\n"))):
        base = run(robot, targets, w)
        d = base[-1, :2] - base[0, :2]
        moved = f"{np.hypot(*d):.3f} m ({d[0]:+.3f}, {d[1]:+.3f})"
        print(f"yaw-pitch-16, its gait, 10 s on {name}: moved {moved}")


def main() -> None:
    FIGURES.mkdir(parents=True, exist_ok=True)
    alpha_maps()
    sweep = efficiency_figure()
    print("efficiency against A/lambda:", ", ".join(f"{a:g}: {e:.4f}" for a, e in sweep))
    study()
    on_the_surface()


if __name__ == "__main__":
    main()
