"""Replays of an agent (the paper's Figure 4): the snake from above at successive moments, and animations.

Each cube is drawn as a square at its pose with a red line from its centre to the middle of its front
face (the direction the head crawls at zero yaw, local -y), so the line shows the cube's heading. The
head cube is drawn darker; the goal is the green disc; the episode's obstacles (a world file's, and
the pegs a task lays out at each reset) are dark grey footprints.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from snakesim.envs.render import _hull, _yaw, silhouette
from snakesim.limits import LIMITS

FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
ANIMATION_SUFFIXES = (".gif", ".mp4")

BODY_FACE = "#c9ccd6"
HEAD_FACE = "#6f7487"
EDGE = "#30323a"
HEADING = "#d62020"
GOAL = "#2e9e4a"
TRAIL = "#5a78dc"
OBSTACLE = "#4a4a4a"


class ReplayError(ValueError):
    """An output that cannot be written (unknown format, no mp4 encoder, ...)."""


@dataclasses.dataclass
class Recording:
    """One episode (or its first ``seconds``): cube poses after every env step, the start included."""

    times: np.ndarray  # (T,) simulated seconds since the first observation
    poses: np.ndarray  # (T, N + 1, 7)
    goal: tuple[float, float]
    goal_radius: float
    half_extent: float
    terminated: bool  # reached the goal
    ret: float
    shapes: list | None = None  # a robot's collision shapes per part (None: the built-in cubes)
    # The episode's obstacles as the env laid them out: {"kind", "size", "pose"} (docs/formats.md).
    obstacles: list = dataclasses.field(default_factory=list)

    @property
    def duration(self) -> float:
        return float(self.times[-1])


def record(
    act: Callable[[np.ndarray], np.ndarray],
    env_kwargs: Mapping[str, Any],
    *,
    seconds: float | None = None,
    seed: int = 0,
    env: Any = None,
) -> Recording:
    """Runs one episode of ``act(obs_batch) -> actions`` in a SnakeEnv; stops early after ``seconds``.
    ``env``: an env made from ``env_kwargs`` to run instead of a new one (possibly wrapped, e.g. in
    :class:`snakesim.wrappers.RerunLogger`)."""
    from snakesim.envs.env import make_env

    if env is None:
        env = make_env(**env_kwargs)
    base = env.unwrapped
    config = base.config
    step_seconds = config["snake"]["dt"] * config["physics_steps_per_env_step"]
    obs, _ = env.reset(seed=seed)
    obstacles = json.loads(base._env.world_json()).get("obstacles", [])
    poses = [base.cube_poses()]
    ret, terminated, steps = 0.0, False, 0
    limit = math.inf if seconds is None else seconds
    while steps * step_seconds < limit - 1e-9:
        action = np.asarray(act(obs[None, :]))[0]
        obs, reward, terminated, truncated, _ = env.step(action)
        steps += 1
        ret += float(reward)
        poses.append(base.cube_poses())
        if terminated or truncated:
            break
    return Recording(
        times=np.arange(len(poses)) * step_seconds,
        poses=np.stack(poses),
        goal=base.goal,
        goal_radius=float(config["goal_radius"]),
        half_extent=base.half_extent,
        terminated=bool(terminated),
        ret=ret,
        shapes=None if base._env.robot_shapes() is None else json.loads(base._env.robot_shapes()),
        obstacles=obstacles,
    )


def check_output(path: str | os.PathLike) -> str:
    """The output's kind (``figure``, ``gif`` or ``mp4``); ReplayError for an unknown or unwritable one."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in FIGURE_SUFFIXES:
        kind = "figure"
    elif suffix == ".gif":
        kind = "gif"
    elif suffix == ".mp4":
        kind = "mp4"
        if shutil.which("ffmpeg") is None:
            raise ReplayError(
                f"cannot write {path}: mp4 needs ffmpeg on PATH (e.g. apt-get install ffmpeg); "
                "write a .gif instead"
            )
    else:
        raise ReplayError(
            f"cannot write {path}: unknown format {suffix or '(none)'} "
            f"(expected {', '.join(FIGURE_SUFFIXES + ANIMATION_SUFFIXES)})"
        )
    return kind


def _square(x: float, y: float, yaw: float, h: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    corners = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
    return corners @ np.array([[c, s], [-s, c]]) + np.array([x, y])


def _heading_segment(x: float, y: float, yaw: float, h: float) -> tuple[list[float], list[float]]:
    # The front face's middle: local (0, -h) rotated by yaw.
    return [x, x + h * math.sin(yaw)], [y, y - h * math.cos(yaw)]


class _SnakeArtist:
    """The squares and heading lines of one snake on an axes, or a robot's collision shapes seen from
    above (``shapes``: per part, as ``SnakeEnv.robot_shapes`` gives them); ``update`` moves them to new
    poses."""

    def __init__(
        self,
        ax,
        cubes: int,
        half_extent: float,
        alpha: float = 1.0,
        zorder: int = 3,
        shapes: list | None = None,
    ) -> None:
        from matplotlib.patches import Polygon

        self.h = half_extent
        self.squares = []
        self.lines = []
        self.outlines = []  # (part, shape, polygon) of a robot
        if shapes is not None:
            for i, part in enumerate(shapes):
                for shape in part:
                    polygon = Polygon(
                        np.zeros((3, 2)),
                        closed=True,
                        facecolor=HEAD_FACE if i == 0 else BODY_FACE,
                        edgecolor=EDGE,
                        linewidth=0.6,
                        alpha=alpha,
                        zorder=zorder,
                    )
                    ax.add_patch(polygon)
                    self.outlines.append((i, shape, polygon))
            return
        for i in range(cubes):
            square = Polygon(
                np.zeros((4, 2)),
                closed=True,
                facecolor=HEAD_FACE if i == 0 else BODY_FACE,
                edgecolor=EDGE,
                linewidth=0.8,
                alpha=alpha,
                zorder=zorder,
            )
            ax.add_patch(square)
            self.squares.append(square)
            (line,) = ax.plot([], [], color=HEADING, linewidth=1.6, alpha=alpha, zorder=zorder + 1)
            self.lines.append(line)

    def update(self, poses: np.ndarray) -> None:
        for i, shape, polygon in self.outlines:
            polygon.set_xy(_hull(silhouette(poses[i], shape)))
        yaws = _yaw(poses[:, 3:7])
        for square, line, pose, yaw in zip(self.squares, self.lines, poses, yaws):
            square.set_xy(_square(pose[0], pose[1], float(yaw), self.h))
            line.set_data(*_heading_segment(pose[0], pose[1], float(yaw), self.h))


def _draw_goal(ax, rec: Recording) -> None:
    from matplotlib.patches import Circle

    ax.add_patch(Circle(rec.goal, rec.goal_radius, facecolor=GOAL, alpha=0.25, edgecolor=GOAL, zorder=1))
    ax.plot(*rec.goal, marker="x", color=GOAL, zorder=2)


def _draw_obstacles(ax, rec: Recording) -> None:
    """Each obstacle's footprint seen from above: a disc for a cylinder or sphere (its radius), the
    rectangle of a box turned by its yaw."""
    from matplotlib.patches import Circle, Polygon

    for obstacle in rec.obstacles:
        pose, size = obstacle["pose"], obstacle["size"]
        style = {"facecolor": OBSTACLE, "edgecolor": OBSTACLE, "alpha": 0.85, "zorder": 1.5}
        if obstacle["kind"] == "box":
            yaw = float(_yaw(np.asarray(pose[3:7], dtype=float)[None, :])[0])
            corners = np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]) * np.array(size[:2]) / 2
            c, s = math.cos(yaw), math.sin(yaw)
            xy = corners @ np.array([[c, s], [-s, c]]) + np.array(pose[:2])
            ax.add_patch(Polygon(xy, closed=True, **style))
        else:
            ax.add_patch(Circle((pose[0], pose[1]), size[0], **style))


def _indices(rec: Recording, times: np.ndarray) -> np.ndarray:
    step = rec.times[1] - rec.times[0] if len(rec.times) > 1 else 1.0
    return np.clip(np.rint(times / step).astype(int), 0, len(rec.times) - 1)


def _overview_limits(rec: Recording, margin: float = 1.0) -> tuple[float, float, float, float]:
    xy = rec.poses[:, :, :2].reshape(-1, 2)
    pts = np.vstack(
        [xy, np.array(rec.goal)[None, :] + rec.goal_radius, np.array(rec.goal)[None, :] - rec.goal_radius]
    )
    lo, hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin
    centre, half = (lo + hi) / 2, (hi - lo).max() / 2
    return centre[0] - half, centre[0] + half, centre[1] - half, centre[1] + half


def draw_strip(
    rec: Recording, out: str | os.PathLike, *, panels: int = 7, title: str | None = None, dpi: int = 150
) -> None:
    """Figure 4: ``panels`` close-ups of the snake at evenly spaced moments, then an overview panel
    with the head's path, the goal and the same moments' poses."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = max(1, min(panels, len(rec.times)))
    times = np.linspace(0.0, rec.duration, panels)
    idx = _indices(rec, times)
    cols = min(panels + 1, 4)
    rows = math.ceil((panels + 1) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(3.0 * cols, 3.0 * rows), squeeze=False)
    flat = axes.ravel()
    xy = rec.poses[:, :, :2]
    span = float(np.max(xy.max(axis=1) - xy.min(axis=1)))  # the snake's largest extent in x or y
    half = max(span / 2 + 4 * rec.half_extent, 1.5)
    try:
        for k, (ax, i) in enumerate(zip(flat, idx)):
            centre = xy[i].mean(axis=0)
            ax.set_xlim(centre[0] - half, centre[0] + half)
            ax.set_ylim(centre[1] - half, centre[1] + half)
            _draw_goal(ax, rec)
            _draw_obstacles(ax, rec)
            ax.plot(xy[: i + 1, 0, 0], xy[: i + 1, 0, 1], color=TRAIL, linewidth=1.0, alpha=0.6, zorder=2)
            _SnakeArtist(ax, xy.shape[1], rec.half_extent, shapes=rec.shapes).update(rec.poses[i])
            to_goal = np.array(rec.goal) - xy[i, 0]
            if np.any(np.abs(np.array(rec.goal) - centre) > half):
                # The goal is out of view: a compass arrow in the corner points to it.
                d = to_goal / max(float(np.hypot(*to_goal)), 1e-9)
                hub = np.array([0.86, 0.14])
                ax.annotate(
                    "",
                    xy=tuple(hub + 0.08 * d),
                    xytext=tuple(hub - 0.08 * d),
                    xycoords="axes fraction",
                    arrowprops={"arrowstyle": "-|>", "color": GOAL, "linewidth": 1.4},
                    zorder=5,
                )
                ax.text(
                    hub[0],
                    hub[1] + 0.13,
                    f"goal {float(np.hypot(*to_goal)):.1f} m",
                    transform=ax.transAxes,
                    color=GOAL,
                    fontsize=7,
                    ha="center",
                    zorder=5,
                )
            ax.set_title(f"({chr(ord('a') + k)}) t = {rec.times[i]:.2f} s", fontsize=9)
            ax.set_aspect("equal")
            ax.tick_params(labelsize=6)
        ax = flat[panels]
        x0, x1, y0, y1 = _overview_limits(rec)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        _draw_goal(ax, rec)
        _draw_obstacles(ax, rec)
        ax.plot(xy[:, 0, 0], xy[:, 0, 1], color=TRAIL, linewidth=1.0, zorder=2)
        for n, i in enumerate(idx):
            _SnakeArtist(
                ax, xy.shape[1], rec.half_extent, alpha=0.3 + 0.7 * (n + 1) / panels, shapes=rec.shapes
            ).update(rec.poses[i])
        outcome = "goal reached" if rec.terminated else "goal not reached"
        ax.set_title(f"path, {rec.duration:.2f} s, {outcome}", fontsize=9)
        ax.set_aspect("equal")
        ax.tick_params(labelsize=6)
        for ax in flat[panels + 1 :]:
            ax.axis("off")
        if title:
            fig.suptitle(title)
        fig.tight_layout()
        fig.savefig(out, dpi=dpi)
    finally:
        plt.close(fig)


#: Most frames of an animation (each frame is held in memory until the file is written: ~0.7 MB).
MAX_FRAMES = LIMITS["replay_frames"]
#: Range of an animation's frames per simulated second (a GIF shows at most 50 frames a second).
FPS_RANGE = (LIMITS["replay_fps_min"], LIMITS["replay_fps_max"])


def check_fps(fps: float) -> None:
    """ReplayError unless ``fps`` lies in :data:`FPS_RANGE`."""
    low, high = FPS_RANGE
    if not (math.isfinite(fps) and low <= fps <= high):
        raise ReplayError(f"--fps must be in [{low:g}, {high:g}], got {fps:g}")


def frame_times(rec: Recording, fps: float) -> np.ndarray:
    """Simulated times of the animation's frames: 0, 1/fps, ... up to the recording's end."""
    check_fps(fps)
    count = int(math.floor(rec.duration * fps + 1e-9)) + 1
    if count > MAX_FRAMES:
        raise ReplayError(
            f"the animation would have {count} frames ({rec.duration:.1f} s at {fps:g} fps), more than "
            f"{MAX_FRAMES}: lower --fps or pass --seconds"
        )
    return np.arange(count) / fps


def render_frames(rec: Recording, fps: float, size: int = 480):
    """The animation's frames as RGB uint8 arrays (size x size), drawn like the figure's overview."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dpi = 100
    fig = plt.figure(figsize=(size / dpi, size / dpi), dpi=dpi)
    ax = fig.add_axes((0.1, 0.08, 0.86, 0.86))
    try:
        x0, x1, y0, y1 = _overview_limits(rec)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.grid(True, alpha=0.25)
        ax.tick_params(labelsize=7)
        _draw_goal(ax, rec)
        _draw_obstacles(ax, rec)
        (trail,) = ax.plot([], [], color=TRAIL, linewidth=1.0, zorder=2)
        snake = _SnakeArtist(ax, rec.poses.shape[1], rec.half_extent, shapes=rec.shapes)
        label = ax.text(0.02, 0.97, "", transform=ax.transAxes, va="top", fontsize=9, zorder=6)
        times = frame_times(rec, fps)
        for t, i in zip(times, _indices(rec, times)):
            trail.set_data(rec.poses[: i + 1, 0, 0], rec.poses[: i + 1, 0, 1])
            snake.update(rec.poses[i])
            label.set_text(f"t = {t:.2f} s")
            fig.canvas.draw()
            yield np.asarray(fig.canvas.buffer_rgba())[:, :, :3].copy()
    finally:
        plt.close(fig)


def write_gif(rec: Recording, out: str | os.PathLike, fps: float = 10.0) -> int:
    """An animated GIF (Pillow), played in real time; returns the number of frames."""
    from PIL import Image

    images = [Image.fromarray(frame) for frame in render_frames(rec, fps)]
    images[0].save(
        out,
        format="GIF",
        save_all=True,
        append_images=images[1:],
        duration=max(int(round(1000 / fps)), 20),
        loop=0,
        optimize=False,
    )
    return len(images)


def write_mp4(rec: Recording, out: str | os.PathLike, fps: float = 10.0) -> int:
    """An mp4 through the ffmpeg program (its default mp4 encoder, H.264 where it has one); returns the
    number of frames."""
    ffmpeg = shutil.which("ffmpeg")
    if ffmpeg is None:
        raise ReplayError(f"cannot write {out}: mp4 needs ffmpeg on PATH; write a .gif instead")
    frames = render_frames(rec, fps)
    first = next(frames)
    h, w = first.shape[:2]
    command = [
        ffmpeg, "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{w}x{h}",
        "-r", f"{fps}", "-i", "-", "-an", "-pix_fmt", "yuv420p", os.fspath(out),
    ]  # fmt: skip
    count = 0
    with tempfile.TemporaryFile() as log:  # a file, not a pipe: ffmpeg can never block on its messages
        process = subprocess.Popen(command, stdin=subprocess.PIPE, stderr=log)
        assert process.stdin is not None
        try:
            for frame in itertools.chain([first], frames):
                process.stdin.write(frame.tobytes())
                count += 1
        except BrokenPipeError:
            pass  # ffmpeg stopped early: its message says why
        finally:
            frames.close()
            try:
                process.stdin.close()
            except BrokenPipeError:
                pass
        returncode = process.wait()
        log.seek(0)
        message = log.read().decode(errors="replace").strip().splitlines()
    if returncode != 0:
        raise ReplayError(
            f"ffmpeg failed writing {out}: {message[-1] if message else f'exit status {returncode}'}"
        )
    return count
