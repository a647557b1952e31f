"""Drawing a world file's ground and obstacles in Rerun, from the ``world.drawing`` metadata that
``snake-cli run --trace`` writes (snake-core's ``WorldSpec::drawing``): a heightfield as a triangle
mesh through the points where Bullet placed them, a plane as a flat square, obstacles as their shapes,
water as the translucent box it fills."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

GROUND_COLOR = (150, 140, 120, 255)
OBSTACLE_COLOR = (120, 120, 140, 255)
#: Translucent, so that a robot under the surface shows through it.
WATER_COLOR = (70, 130, 200, 90)


def heightfield_triangles(rows: int, columns: int) -> np.ndarray:
    """Two triangles per grid cell, indexing points stored line by line (``rows`` per line)."""
    x, y = np.meshgrid(np.arange(rows - 1), np.arange(columns - 1))
    a = (y * rows + x).ravel()
    b, c, d = a + 1, a + rows, a + rows + 1
    return np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]).astype(np.uint32)


def log_world(rr, recording, drawing: Mapping[str, Any], shape_archetype, path: str = "world") -> None:
    """Logs the world statically under ``path`` (``ground``, ``obstacles/<k>``, ``water/<k>``);
    ``shape_archetype`` turns one shape description into a Rerun archetype (rerun_log's, shared with
    robots)."""
    ground = drawing["ground"]
    if ground["kind"] == "heightfield":
        rows, columns = int(ground["rows"]), int(ground["columns"])
        points = np.asarray(ground["points"], dtype=np.float32).reshape(-1, 3)
        mesh = rr.Mesh3D(
            vertex_positions=points,
            triangle_indices=heightfield_triangles(rows, columns),
            vertex_colors=np.tile(np.asarray(GROUND_COLOR, dtype=np.uint8), (len(points), 1)),
        )
        recording.log(f"{path}/ground", mesh, static=True)
    else:
        # The plane z = 0 turned by the ground's orientation (a slope), drawn 40 m square.
        recording.log(
            f"{path}/ground",
            rr.Boxes3D(
                half_sizes=[[20.0, 20.0, 0.0005]],
                centers=[[0.0, 0.0, -0.0005]],
                quaternions=[ground["orientation"]],
                colors=[GROUND_COLOR],
                fill_mode="solid",
            ),
            static=True,
        )
    for k, shape in enumerate(drawing.get("obstacles", [])):
        recording.log(f"{path}/obstacles/{k}", shape_archetype(rr, shape, OBSTACLE_COLOR), static=True)
    for k, box in enumerate(drawing.get("water", [])):
        low, high = np.asarray(box[:3], dtype=np.float32), np.asarray(box[3:], dtype=np.float32)
        recording.log(
            f"{path}/water/{k}",
            rr.Boxes3D(
                half_sizes=[(high - low) / 2],
                centers=[(high + low) / 2],
                colors=[WATER_COLOR],
                fill_mode="solid",
            ),
            static=True,
        )
