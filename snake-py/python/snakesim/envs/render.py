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


#: Points on a circle's outline when a round shape's silhouette is drawn.
CIRCLE_POINTS = 24


def _rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` rotated by the unit quaternion ``q`` (x, y, z, w)."""
    u, w = np.asarray(q[:3], dtype=np.float64), float(q[3])
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def _compose(outer: np.ndarray, inner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pose ``outer * inner`` (each x, y, z, qx, qy, qz, qw) as (position, quaternion)."""
    p, q = np.asarray(outer[:3], dtype=np.float64), np.asarray(outer[3:7], dtype=np.float64)
    r = np.asarray(inner[3:7], dtype=np.float64)
    position = p + _rotate(q, np.asarray(inner[:3], dtype=np.float64)[None, :])[0]
    x1, y1, z1, w1 = q
    x2, y2, z2, w2 = r
    quaternion = np.array(
        [
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
        ]
    )
    return position, quaternion


def silhouette(link_pose: np.ndarray, shape: dict) -> np.ndarray:
    """Points (K, 2) whose convex hull is the shape's outline seen from above: a box's 8 corners, the
    outlines of a cylinder's two end discs, a sphere's equator, a capsule's two end spheres. ``shape``
    is one of a robot link's shapes (``SnakeEnv``'s ``robot_shapes``: kind, size, pose in the link's
    centre-of-mass frame), ``link_pose`` the link's pose (x, y, z, qx, qy, qz, qw)."""
    centre, q = _compose(np.asarray(link_pose, dtype=np.float64), np.asarray(shape["pose"], dtype=np.float64))
    kind, size = shape["kind"], [float(v) for v in shape["size"]]
    angles = np.linspace(0.0, 2.0 * np.pi, CIRCLE_POINTS, endpoint=False)
    ring = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=1)
    if kind == "box":
        half = np.asarray(size[:3]) / 2.0
        signs = np.array(
            [[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64
        )
        local = signs * half
    elif kind == "sphere":
        return (centre[None, :2] + size[0] * ring[:, :2]).astype(np.float64)
    elif kind == "cylinder":
        r, half_length = size[0], size[1] / 2.0
        local = np.vstack([r * ring + [0.0, 0.0, z] for z in (-half_length, half_length)])
    elif kind == "capsule":
        r, half_length = size[0], size[1] / 2.0
        ends = _rotate(q, np.array([[0.0, 0.0, -half_length], [0.0, 0.0, half_length]]))
        # A sphere's outline from above is a circle whatever its orientation.
        return np.vstack([centre[:2] + end[:2] + r * ring[:, :2] for end in ends])
    else:
        raise ValueError(f"unknown shape kind {kind!r}")
    return (centre[None, :] + _rotate(q, local))[:, :2]


def _hull(points: np.ndarray) -> np.ndarray:
    """The convex hull of 2D points, counter-clockwise (Andrew's monotone chain)."""
    pts = sorted({(float(x), float(y)) for x, y in points})
    if len(pts) <= 2:
        return np.asarray(pts, dtype=np.float64)

    def half(chain):
        out: list[tuple[float, float]] = []
        for p in chain:
            while len(out) >= 2:
                (ax, ay), (bx, by) = out[-2], out[-1]
                if (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax) > 0:
                    break
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(reversed(pts))
    return np.asarray(lower[:-1] + upper[:-1], dtype=np.float64)


def _inside(polygon: np.ndarray, wx: np.ndarray, wy: np.ndarray) -> np.ndarray:
    """Which pixel centres lie in a counter-clockwise convex polygon (a point or a segment: none)."""
    if len(polygon) < 3:
        return np.zeros(np.broadcast_shapes(wx.shape, wy.shape), dtype=bool)
    mask = np.ones(np.broadcast_shapes(wx.shape, wy.shape), dtype=bool)
    for (ax, ay), (bx, by) in zip(polygon, np.roll(polygon, -1, axis=0)):
        mask &= (bx - ax) * (wy - ay) - (by - ay) * (wx - ax) >= 0
    return mask


def top_down(
    cube_poses: np.ndarray,
    half_extent: float,
    goal: tuple[float, float],
    goal_radius: float,
    size: int = 480,
    view: float | None = None,
    centre: tuple[float, float] | None = None,
    trail: np.ndarray | None = None,
    shapes: list[list[dict]] | None = None,
) -> np.ndarray:
    """Draws the body (rows of x, y, z, qx, qy, qz, qw, one per part; the head first) and the goal disc
    from above: each part as a cube of ``half_extent`` (the built-in snake), or, with ``shapes`` (a
    robot's: per part, its collision shapes as ``SnakeEnv.robot_shapes`` gives them), each shape's
    outline seen from above.

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

    if shapes is not None:
        for i in range(len(poses) - 1, -1, -1):  # the head last, on top
            for shape in shapes[i]:
                image[_inside(_hull(silhouette(poses[i], shape)), wx, wy)] = HEAD if i == 0 else BODY
        return image
    yaws = _yaw(poses[:, 3:7])
    for i in range(len(poses) - 1, -1, -1):  # the head last, on top
        dx, dy = wx - xy[i, 0], wy - xy[i, 1]
        c, s = np.cos(yaws[i]), np.sin(yaws[i])
        u, v = c * dx + s * dy, -s * dx + c * dy  # into the cube's frame
        inside = (np.abs(u) <= half_extent) & (np.abs(v) <= half_extent)
        image[inside] = HEAD if i == 0 else BODY
    return image
