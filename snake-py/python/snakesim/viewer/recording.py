"""Rerun recordings of the snake: its cubes in 3D at every physics step, the ground, the goal and the
head's path, time series of the joints and the reward, and the configuration as text.

What a recording holds (entity paths; ``N`` joints, ``N + 1`` cubes, the head first):

- ``world/snake``: the cubes as 3D boxes (``Boxes3D``), their true poses after every 1/240 s physics
  step; ``world/ground`` the plane (a thin plate); ``world/head_path/{k}`` the head's path so far
  (sampled every 0.05 s, in pieces of 100 points); ``world/goal`` the goal as a flat disc of the goal
  radius (env episodes only).
- ``joints/angle``, ``joints/target``, ``joints/velocity``, ``joints/torque``: ``Scalars`` with one
  value per joint (series ``j0`` ... ``j{N-1}``, joint 0 next to the head) at every physics step:
  angle and target (rad), velocity (rad/s), the torque the motor applied (N m).
- Env episodes, at every env step: ``reward/total`` and each term ``reward/goal``,
  ``reward/progress``, ``reward/smoothness``, ``reward/energy``; ``distance_to_goal`` (m, as the
  reward computes it); ``episode`` a text log line at each episode's start.
- ``config``: the run's or env's configuration (``TextDocument``, JSON).

Timelines: ``time`` (simulated time, a duration) and ``step`` (physics steps). An env episode's first
row is the reset's own physics step (step 1, as the env counts it). Several episodes in one recording
follow one another on the timelines: the second starts the physics step after the first ends.

Rerun stores positions and quaternions as float32 and scalars as float64.
"""

from __future__ import annotations

import dataclasses
import io
import itertools
import json
import math
import os
from collections.abc import Iterator, Mapping, Sequence
from contextlib import ExitStack, contextmanager
from typing import Any

import numpy as np

from snakesim.files import FileError, open_regular, output_file
from snakesim.limits import LIMITS

#: Timelines of every recording.
TIME = "time"
STEP = "step"
#: Most simulated seconds in one recording (all its episodes together).
MAX_SECONDS: float = float(LIMITS["recording_seconds"])
#: The head's path is sampled this often (simulated seconds).
PATH_PERIOD = 0.05
#: Points per piece of the head's path (``world/head_path/0``, ``/1``, ...): each piece is logged
#: growing until it is full and then stays, so a recording holds O(T) path points, not O(T^2).
PATH_PIECE = 100
#: Half the side of the ground plate, metres (the plane itself is infinite).
GROUND_HALF = 30.0

HEAD_COLOR = (214, 32, 32, 255)
BODY_COLOR = (201, 204, 214, 255)
GROUND_COLOR = (176, 180, 170, 255)
GOAL_COLOR = (46, 158, 74, 140)
PATH_COLOR = (90, 120, 220, 255)
REWARD_TERMS = ("goal", "progress", "smoothness", "energy")
JOINT_QUANTITIES = ("angle", "target", "velocity", "torque")
TRACE_FORMAT = "snakesim physics trace 1"


class RecordingError(ValueError):
    """A recording that cannot be made (no viewer, a port in use, too long, ...): one line."""


def _rerun():
    try:
        import rerun
    except ImportError as error:  # pragma: no cover - rerun-sdk is in requirements.lock
        raise RecordingError(
            f"Rerun recordings need the rerun-sdk package ({error}); install requirements.lock "
            "(bash scripts/setup)"
        ) from None
    return rerun


@dataclasses.dataclass
class Trace:
    """Consecutive physics steps: K rows of the state after each."""

    steps: np.ndarray  # (K,) physics steps since the world was built
    poses: np.ndarray  # (K, N + 1, 7): x, y, z, qx, qy, qz, qw of every cube, the head first
    positions: np.ndarray  # (K, N) joint angles, rad
    velocities: np.ndarray  # (K, N) rad/s
    torques: np.ndarray  # (K, N) N m
    targets: np.ndarray  # (K, N) rad; NaN where no target was set

    @classmethod
    def from_core(cls, trace: Mapping[str, np.ndarray]) -> Trace:
        """From ``_core.Env.physics_trace()``."""
        return cls(
            steps=np.asarray(trace["steps"], dtype=np.int64),
            poses=np.asarray(trace["poses"], dtype=np.float64),
            positions=np.asarray(trace["positions"], dtype=np.float64),
            velocities=np.asarray(trace["velocities"], dtype=np.float64),
            torques=np.asarray(trace["torques"], dtype=np.float64),
            targets=np.asarray(trace["targets"], dtype=np.float64),
        )

    def __len__(self) -> int:
        return len(self.steps)


def _durations(seconds: np.ndarray) -> np.ndarray:
    """Seconds as nanosecond durations, rounded to the nearest (Rerun's duration timelines)."""
    return np.rint(np.asarray(seconds, dtype=np.float64) * 1e9).astype(np.int64).astype("timedelta64[ns]")


def blueprint(joints: int, *, rewards: bool):
    """The viewer's layout: the snake in 3D beside plots of the joints (and the reward), the config."""
    import rerun as rr
    import rerun.blueprint as rrb

    # The joints' plots show the 3 s before the time cursor (scroll out for the whole run).
    window = rrb.TimeAxis(
        view_range=rr.TimeRange(
            start=rr.TimeRangeBoundary.cursor_relative(seconds=-3.0),
            end=rr.TimeRangeBoundary.cursor_relative(seconds=0.0),
        )
    )
    plots = [
        rrb.TimeSeriesView(
            name="joint angles and targets (rad)", contents=["joints/angle", "joints/target"], axis_x=window
        ),
        rrb.TimeSeriesView(name="motor torques (N m)", origin="joints/torque", axis_x=window),
        rrb.TimeSeriesView(name="joint velocities (rad/s)", origin="joints/velocity", axis_x=window),
    ]
    if rewards:
        plots.append(
            rrb.TimeSeriesView(
                name="reward terms and distance to goal", contents=["reward/**", "distance_to_goal"]
            )
        )
    side = [rrb.TextDocumentView(origin="config", name="configuration")]
    if rewards:
        side.append(rrb.TextLogView(origin="episode", name="episodes"))
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(
                rrb.Spatial3DView(
                    origin="world",
                    name="snake",
                    line_grid=rrb.LineGrid3D(visible=True, spacing=1.0),
                    # Behind and above the start, following the snake.
                    eye_controls=rrb.EyeControls3D(
                        position=[4.0, 5.0, 3.0], look_target=[0.0, 0.0, 0.0], tracking_entity="world/snake"
                    ),
                ),
                rrb.Tabs(*side),
                row_shares=[3, 1],
            ),
            rrb.Vertical(*plots),
            column_shares=[3, 2],
        ),
        rrb.TimePanel(timeline=TIME),
        rrb.BlueprintPanel(state="collapsed"),
        rrb.SelectionPanel(state="collapsed"),
    )


class SnakeLog:
    """Logs one snake's physics steps (and env steps) to a Rerun recording stream.

    ``config`` is shown as text; ``rewards`` adds the reward and distance plots (env episodes). Episodes
    follow one another: :meth:`start_episode` begins one after everything logged so far. Rows are
    buffered and sent in columns every ``flush_rows`` physics steps and by :meth:`flush`.
    """

    def __init__(
        self,
        recording,
        *,
        joints: int,
        dt: float,
        half_extent: float,
        config: Mapping[str, Any],
        rewards: bool,
        max_seconds: float = MAX_SECONDS,
        flush_rows: int = 2400,
        shapes: Sequence[Sequence[Mapping[str, Any]]] | None = None,
    ) -> None:
        rr = _rerun()
        self.rr = rr
        self.rec = recording
        self.joints = int(joints)
        self.dt = float(dt)
        self.half_extent = float(half_extent)
        self.rewards = rewards
        self.max_steps = int(math.floor(max_seconds / self.dt + 1e-9))
        self.flush_rows = flush_rows
        self.path_every = max(1, round(PATH_PERIOD / self.dt))
        self.offset = 0  # global step of the previous episode's last physics step
        self.last_step = 0  # global step of the latest row
        self.episodes = 0
        self._path: list[np.ndarray] = []  # the current piece's points
        self._pieces = 0  # full pieces of this episode's path
        self._path_rows: list[tuple[int, int, np.ndarray]] = []  # (step, piece, points)
        self._rows: list[Trace] = []
        self._env_rows: list[tuple[int, dict[str, float], float]] = []
        # Only our two timelines (no wall-clock log_time / log_tick).
        rr.set_log_time_enabled(False, recording=recording)
        rr.set_log_tick_enabled(False, recording=recording)
        log = self._log_static
        log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP)
        log(
            "world/ground",
            rr.Boxes3D(
                # Its top 5 mm under the plane (z = 0), so that the view's grid shows on it.
                half_sizes=[[GROUND_HALF, GROUND_HALF, 0.005]],
                centers=[[0.0, 0.0, -0.01]],
                colors=[GROUND_COLOR],
                fill_mode="solid",
            ),
        )
        # The built-in snake: one Boxes3D of N + 1 cubes. A robot: one entity per link, moved by its
        # pose, holding its shapes placed in its centre-of-mass frame.
        self.shapes = None if shapes is None else [list(link) for link in shapes]
        if self.shapes is None:
            self.parts = self.joints + 1
            log(
                "world/snake",
                rr.Boxes3D(
                    half_sizes=np.full((self.parts, 3), self.half_extent),
                    colors=[HEAD_COLOR] + [BODY_COLOR] * (self.parts - 1),
                    fill_mode="solid",
                ),
            )
        else:
            self.parts = len(self.shapes)
            for i, link in enumerate(self.shapes):
                color = HEAD_COLOR if i == 0 else BODY_COLOR
                for k, shape in enumerate(link):
                    log(f"world/snake/link{i}/shape{k}", _shape_archetype(rr, shape, color))
        names = [f"j{j}" for j in range(self.joints)]
        for quantity in JOINT_QUANTITIES:
            widths = [1.0 if quantity == "target" else 1.5] * self.joints
            log(f"joints/{quantity}", rr.SeriesLines(names=[f"{n} {quantity}" for n in names], widths=widths))
        if rewards:
            for term in ("total", *REWARD_TERMS):
                log(f"reward/{term}", rr.SeriesLines(names=[f"reward {term}"]))
            log("distance_to_goal", rr.SeriesLines(names=["distance to goal (m)"]))
        text = "```json\n" + json.dumps(config, indent=2, default=str) + "\n```\n"
        log("config", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN))
        recording.send_blueprint(blueprint(self.joints, rewards=rewards))

    def _log_static(self, path: str, value) -> None:
        self.rec.log(path, value, static=True)

    def _at(self, step: int) -> None:
        self.rec.set_time(STEP, sequence=int(step))
        self.rec.set_time(TIME, duration=np.timedelta64(int(round(step * self.dt * 1e9)), "ns"))

    @property
    def seconds(self) -> float:
        """Simulated seconds logged so far."""
        return self.last_step * self.dt

    def start_episode(
        self,
        *,
        goal: Sequence[float] | None = None,
        goal_radius: float | None = None,
        note: str | None = None,
    ) -> None:
        """Begins an episode after everything logged so far (its world's steps count from 1)."""
        self.flush()
        rr = self.rr
        self.offset = self.last_step
        self.episodes += 1
        self._path = []
        self._pieces = 0
        self._at(self.offset + 1)
        if self.episodes > 1:
            self.rec.log("world/head_path", rr.Clear(recursive=True))  # the last episode's path
        if goal is not None:
            radius = float(goal_radius or 0.0)
            self.rec.log(
                "world/goal",
                rr.Cylinders3D(
                    lengths=[0.02],
                    radii=[max(radius, 0.05)],
                    centers=[[float(goal[0]), float(goal[1]), 0.01]],
                    colors=[GOAL_COLOR],
                    fill_mode="solid",
                    labels=[f"goal ({float(goal[0]):.2f}, {float(goal[1]):.2f}), radius {radius:g} m"],
                ),
            )
        if note is not None:
            self.rec.log("episode", rr.TextLog(note))

    def add_physics(self, trace: Trace) -> None:
        """Appends physics steps of the current episode (its world's step numbers)."""
        if len(trace) == 0:
            return
        last = self.offset + int(trace.steps[-1])
        if last > self.max_steps:
            raise RecordingError(
                f"the recording is full: it holds at most {self.max_steps * self.dt:g} simulated seconds "
                f"(LIMITS['recording_seconds'] is {MAX_SECONDS:g})"
            )
        n = self.joints
        if trace.poses.shape[1:] != (self.parts, 7) or trace.positions.shape[1:] != (n,):
            raise RecordingError(
                f"expected the state of {n} joints, got poses {trace.poses.shape} and angles "
                f"{trace.positions.shape}"
            )
        self._rows.append(trace)
        for k in range(len(trace)):
            local = int(trace.steps[k])
            if local == 1 or local % self.path_every == 0:
                if len(self._path) == PATH_PIECE:
                    # A new piece starts where the full one ends.
                    self._path = [self._path[-1]]
                    self._pieces += 1
                self._path.append(trace.poses[k, 0, :3].copy())
                self._path_rows.append((self.offset + local, self._pieces, np.array(self._path)))
        self.last_step = last
        if sum(len(t) for t in self._rows) >= self.flush_rows:
            self.flush()

    def add_env_step(self, step: int, reward: float, info: Mapping[str, Any]) -> None:
        """One env step's reward terms and distance, at its last physics step (the world's number)."""
        values = {"total": float(reward)}
        for term in REWARD_TERMS:
            values[term] = float(info.get(f"reward_{term}", 0.0))
        self._env_rows.append((self.offset + int(step), values, float(info.get("distance", math.nan))))

    def flush(self) -> None:
        """Sends every buffered row."""
        rr = self.rr
        if self._rows:
            rows = self._rows
            self._rows = []
            steps = self.offset + np.concatenate([t.steps for t in rows])
            index = [
                rr.TimeColumn(STEP, sequence=steps),
                rr.TimeColumn(TIME, duration=_durations(steps * self.dt)),
            ]
            poses = np.concatenate([t.poses for t in rows])
            k, cubes = poses.shape[:2]
            if self.shapes is None:
                self.rec.send_columns(
                    "world/snake",
                    indexes=index,
                    columns=rr.Boxes3D.columns(
                        centers=poses[:, :, :3].reshape(-1, 3),
                        quaternions=poses[:, :, 3:7].reshape(-1, 4),
                    ).partition([cubes] * k),
                )
            else:
                for i in range(cubes):
                    self.rec.send_columns(
                        f"world/snake/link{i}",
                        indexes=index,
                        columns=rr.Transform3D.columns(
                            translation=poses[:, i, :3], quaternion=poses[:, i, 3:7]
                        ),
                    )
            for quantity, name in zip(JOINT_QUANTITIES, ("positions", "targets", "velocities", "torques")):
                values = np.concatenate([getattr(t, name) for t in rows])
                keep = ~np.isnan(values).any(axis=1)  # a reset's step has no target
                if not keep.any():
                    continue
                self.rec.send_columns(
                    f"joints/{quantity}",
                    indexes=[
                        rr.TimeColumn(STEP, sequence=steps[keep]),
                        rr.TimeColumn(TIME, duration=_durations(steps[keep] * self.dt)),
                    ],
                    columns=rr.Scalars.columns(scalars=values[keep]),
                )
        for step, piece, path in self._path_rows:
            self._at(step)
            self.rec.log(
                f"world/head_path/{piece}", rr.LineStrips3D([path], colors=[PATH_COLOR], radii=[0.03])
            )
        self._path_rows.clear()
        if self._env_rows:
            rows = self._env_rows
            self._env_rows = []
            steps = np.array([r[0] for r in rows], dtype=np.int64)
            index = [
                rr.TimeColumn(STEP, sequence=steps),
                rr.TimeColumn(TIME, duration=_durations(steps * self.dt)),
            ]
            for term in ("total", *REWARD_TERMS):
                self.rec.send_columns(
                    f"reward/{term}",
                    indexes=index,
                    columns=rr.Scalars.columns(scalars=np.array([r[1][term] for r in rows])),
                )
            self.rec.send_columns(
                "distance_to_goal",
                indexes=index,
                columns=rr.Scalars.columns(scalars=np.array([r[2] for r in rows])),
            )


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``v`` rotated by the unit quaternion ``q`` (x, y, z, w)."""
    u, w = q[:3], q[3]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def _shape_archetype(rr, shape: Mapping[str, Any], color):
    """A robot's collision shape (``snake-cli run --trace`` metadata) as a Rerun archetype, placed in its
    link's frame: boxes, spheres (ellipsoids), cylinders and capsules along their z axis."""
    kind, size = shape["kind"], [float(v) for v in shape["size"]]
    pose = np.asarray(shape["pose"], dtype=np.float64)
    center, quaternion = pose[:3], pose[3:7]
    common = dict(colors=[color], fill_mode="solid")
    if kind == "box":
        return rr.Boxes3D(
            half_sizes=[np.asarray(size) / 2], centers=[center], quaternions=[quaternion], **common
        )
    if kind == "sphere":
        return rr.Ellipsoids3D(
            half_sizes=[[size[0]] * 3], centers=[center], quaternions=[quaternion], **common
        )
    if kind == "cylinder":
        return rr.Cylinders3D(
            lengths=[size[1]], radii=[size[0]], centers=[center], quaternions=[quaternion], **common
        )
    if kind == "capsule":
        # Rerun's capsule runs from its origin along +z: start it half a length below the centre.
        start = center + _rotate(quaternion, np.array([0.0, 0.0, -size[1] / 2]))
        return rr.Capsules3D(
            lengths=[size[1]], radii=[size[0]], translations=[start], quaternions=[quaternion], **common
        )
    raise RecordingError(f"unknown shape kind {kind!r}")


# -- physics traces from snake-cli ----------------------------------------------------------------
def trace_columns(joints: int, parts: int | None = None) -> list[str]:
    """The columns of a physics-trace CSV (``snake-cli run --trace``): ``parts`` poses (the snake's
    ``joints + 1`` cubes, or a robot's links) and ``joints`` joints."""
    columns = ["step", "t"]
    for c in range(joints + 1 if parts is None else parts):
        columns += [f"c{c}_{k}" for k in ("x", "y", "z", "qx", "qy", "qz", "qw")]
    for prefix in ("q", "qd", "tau", "target"):
        columns += [f"{prefix}{j}" for j in range(joints)]
    return columns


def _open_trace(path: str | os.PathLike) -> io.TextIOWrapper:
    """A trace CSV opened as text: a regular file of at most LIMITS['csv_bytes']."""
    return io.TextIOWrapper(open_regular(path, "csv_bytes"), encoding="utf-8")


def read_trace_header(path: str | os.PathLike) -> tuple[dict[str, Any], list[str]]:
    """The metadata line and the column names of a physics-trace CSV; RecordingError if it is not one."""
    try:
        with _open_trace(path) as f:
            # Bounded lines: a file without newlines is not read whole to find the first one.
            first = f.readline(1 << 20)
            header = f.readline(1 << 20).strip().split(",")
    except FileError as error:
        raise RecordingError(str(error)) from None
    except OSError as error:
        raise RecordingError(f"cannot read {path}: {error.strerror or error}") from None
    except UnicodeDecodeError:
        raise RecordingError(f"{path} is not a physics trace (not text)") from None
    prefix = f"# {TRACE_FORMAT} "
    if not first.startswith(prefix):
        raise RecordingError(
            f"{path} is not a physics trace (its first line must start with {prefix.strip()!r})"
        )
    try:
        meta = json.loads(first[len(prefix) :])
        joints = int(meta["joints"])
        dt = float(meta["dt"])
        parts = int(meta.get("parts", joints + 1))
        shapes = meta.get("shapes")
        if shapes is not None and len(shapes) != parts:
            raise ValueError(f"{len(shapes)} shape lists for {parts} parts")
    except (ValueError, KeyError, TypeError) as error:
        raise RecordingError(f"{path}: malformed physics-trace metadata ({error})") from None
    if not (
        1 <= joints <= LIMITS["joints"]
        and 1 <= parts <= LIMITS["joints"] + 1
        and math.isfinite(dt)
        and dt > 0
    ):
        raise RecordingError(f"{path}: joints {joints}, parts {parts} or dt {dt} out of range")
    if header != trace_columns(joints, parts):
        raise RecordingError(f"{path}: the column header does not match a {joints}-joint physics trace")
    return meta, header


def read_trace(path: str | os.PathLike, rows: int = 2400) -> tuple[dict[str, Any], Iterator[Trace]]:
    """A physics-trace CSV's metadata and its rows in blocks of ``rows`` (memory stays bounded)."""
    meta, header = read_trace_header(path)
    n = int(meta["joints"])
    parts = int(meta.get("parts", n + 1))

    def blocks() -> Iterator[Trace]:
        with _open_trace(path) as f:
            f.readline()
            f.readline()
            line = 2
            while True:
                raw = list(itertools.islice(f, rows))
                if not raw:
                    return
                lines = [text for text in raw if text.strip()]  # blank lines carry nothing
                if not lines:
                    continue
                try:
                    data = np.loadtxt(lines, delimiter=",", ndmin=2)
                except ValueError as error:
                    raise RecordingError(
                        f"{path}: malformed rows in lines {line + 1}-{line + len(raw)}: {error}"
                    ) from None
                if data.shape[1] != len(header):
                    raise RecordingError(
                        f"{path}: rows in lines {line + 1}-{line + len(raw)} have {data.shape[1]} values, "
                        f"expected {len(header)}"
                    )
                line += len(raw)
                c = 2 + 7 * parts
                yield Trace(
                    steps=data[:, 0].astype(np.int64),
                    poses=data[:, 2:c].reshape(-1, parts, 7),
                    positions=data[:, c : c + n],
                    velocities=data[:, c + n : c + 2 * n],
                    torques=data[:, c + 2 * n : c + 3 * n],
                    targets=data[:, c + 3 * n : c + 4 * n],
                )
                if len(raw) < rows:
                    return

    return meta, blocks()


def log_trace(recording, path: str | os.PathLike) -> int:
    """Logs a physics-trace CSV as one episode; returns the number of physics steps."""
    meta, blocks = read_trace(path)
    log = SnakeLog(
        recording,
        joints=int(meta["joints"]),
        dt=float(meta["dt"]),
        half_extent=float(meta.get("half_extent", 0.25)),
        config=meta,
        rewards=False,
        shapes=meta.get("shapes"),
    )
    world = meta.get("world")
    if world is not None:
        from snakesim.viewer.world_draw import log_world

        log_world(_rerun(), recording, world["drawing"], _shape_archetype)
    log.start_episode()
    count = 0
    for block in blocks:
        log.add_physics(block)
        count += len(block)
    log.flush()
    if count == 0:
        raise RecordingError(f"{path} holds no physics steps")
    return count


@contextmanager
def recording_to(
    *,
    rrd: str | os.PathLike | None = None,
    spawn_url: str | None = None,
    application_id: str = "snakesim",
    name: str | None = None,
):
    """A new recording stream whose data goes to the file ``rrd`` (written whole, through
    :func:`snakesim.files.output_file`, when the block ends without error) and/or a viewer at
    ``spawn_url``."""
    rr = _rerun()
    rec = rr.RecordingStream(application_id)
    with ExitStack() as stack:
        sinks = []
        if rrd is not None:
            sinks.append(rr.FileSink(stack.enter_context(output_file(rrd))))
        if spawn_url is not None:
            sinks.append(rr.GrpcSink(spawn_url))
        try:
            if sinks:
                rec.set_sinks(*sinks)
            if name:
                rec.send_recording_name(name)
            yield rec
            rec.flush()
        finally:
            # Done with the file before it is put in place (or removed).
            rec.disconnect()
