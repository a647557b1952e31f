"""Top-down pictures of the snake and its goal as RGB arrays, with numpy alone."""

from __future__ import annotations

import numpy as np

BACKGROUND = np.array([245, 245, 240], dtype=np.uint8)
GRID = np.array([225, 225, 220], dtype=np.uint8)
HEAD = np.array([200, 40, 40], dtype=np.uint8)
BODY = np.array([70, 70, 80], dtype=np.uint8)
GOAL = np.array([40, 160, 60], dtype=np.uint8)
TRAIL = np.array([90, 120, 220], dtype=np.uint8)


def _yaw(q: np.ndarray) -> np.ndarray:
    """Heading about z of quaternions (x, y, z, w), one per row."""
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def top_down(
    cube_poses: np.ndarray,
    half_extent: float,
    goal: tuple[float, float],
    goal_radius: float,
    size: int = 480,
    view: float | None = None,
    centre: tuple[float, float] | None = None,
    trail: np.ndarray | None = None,
) -> np.ndarray:
    """Draws cubes (rows of x, y, z, qx, qy, qz, qw; the head first) and the goal disc from above.

    The view is a square `view` metres wide centred on `centre` (default: wide enough for the snake and
    the goal, centred between them). Returns a (size, size, 3) uint8 array, +y up.
    """
    poses = np.asarray(cube_poses, dtype=np.float64)
    xy = poses[:, :2]
    points = np.vstack([xy, np.asarray(goal, dtype=np.float64)[None, :]])
    if centre is None:
        lo, hi = points.min(axis=0), points.max(axis=0)
        centre = tuple((lo + hi) / 2.0)
        if view is None:
            view = float((hi - lo).max()) + 4.0 * max(half_extent, goal_radius)
    if view is None:
        view = 12.0
    scale = size / view
    image = np.empty((size, size, 3), dtype=np.uint8)
    image[:] = BACKGROUND

    # Pixel centres in world coordinates (row 0 at the top, so y decreases down the rows).
    coords = (np.arange(size) + 0.5) / scale - view / 2.0
    wx = centre[0] + coords[None, :]
    wy = centre[1] - coords[:, None]

    # A 1 m grid.
    on_x = np.abs(wx - np.round(wx)) < 0.5 / scale
    on_y = np.abs(wy - np.round(wy)) < 0.5 / scale
    image[np.broadcast_to(on_x, (size, size)) | np.broadcast_to(on_y, (size, size))] = GRID

    goal_mask = (wx - goal[0]) ** 2 + (wy - goal[1]) ** 2 <= goal_radius**2
    image[goal_mask] = (0.35 * GOAL + 0.65 * BACKGROUND).astype(np.uint8)
    ring = np.abs(np.sqrt((wx - goal[0]) ** 2 + (wy - goal[1]) ** 2) - goal_radius) < 1.0 / scale
    image[ring] = GOAL

    if trail is not None and len(trail):
        t = np.asarray(trail, dtype=np.float64)
        cols = ((t[:, 0] - centre[0] + view / 2.0) * scale).astype(int)
        rows = ((centre[1] - t[:, 1] + view / 2.0) * scale).astype(int)
        keep = (cols >= 0) & (cols < size) & (rows >= 0) & (rows < size)
        image[rows[keep], cols[keep]] = TRAIL

    yaws = _yaw(poses[:, 3:7])
    for i in range(len(poses) - 1, -1, -1):  # the head last, on top
        dx, dy = wx - xy[i, 0], wy - xy[i, 1]
        c, s = np.cos(yaws[i]), np.sin(yaws[i])
        u, v = c * dx + s * dy, -s * dx + c * dy  # into the cube's frame
        inside = (np.abs(u) <= half_extent) & (np.abs(v) <= half_extent)
        image[inside] = HEAD if i == 0 else BODY
    return image
