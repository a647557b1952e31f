"""pybullet 3.2.7 reference for the skin-friction slope tests (tests/skin.rs).

A box slides on a plane under gravity tilted by the slope angle (the same as a slope, and what a
`ground: {slope}` world will build), with pybullet's own isotropic lateral friction. The skin tests
compare snakesim's skin friction along the sliding direction with this Coulomb friction.

Usage:
    python skin_slope_reference.py SPEC.json OUT_DIR

SPEC.json: {"slope_deg", "half_extents", "mass", "yaw", "ground_friction", "steps", "frictions": [mu...]}.
Writes OUT_DIR/slope.csv with columns case, mu, distance (metres the box's centre moved in the plane).

Independent of snakesim: only pybullet calls.
"""

import csv
import json
import math
import os
import sys

import pybullet as p
from pybullet_utils import bullet_client


def slide(spec, mu):
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    plane = client.createMultiBody(0, client.createCollisionShape(p.GEOM_PLANE))
    client.changeDynamics(plane, -1, lateralFriction=spec["ground_friction"])
    slope = math.radians(spec["slope_deg"])
    g = 9.81
    # Downhill is -y.
    client.setGravity(0, -g * math.sin(slope), -g * math.cos(slope))
    he = spec["half_extents"]
    box = client.createCollisionShape(p.GEOM_BOX, halfExtents=he)
    orientation = client.getQuaternionFromEuler((0, 0, spec["yaw"]))
    body = client.createMultiBody(spec["mass"], box, basePosition=[0, 0, he[2]], baseOrientation=orientation)
    client.changeDynamics(body, -1, lateralFriction=mu)
    start = client.getBasePositionAndOrientation(body)[0]
    for _ in range(spec["steps"]):
        client.stepSimulation()
    end = client.getBasePositionAndOrientation(body)[0]
    client.disconnect()
    return math.hypot(end[0] - start[0], end[1] - start[1])


def main():
    spec = json.load(open(sys.argv[1]))
    with open(os.path.join(sys.argv[2], "slope.csv"), "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["case", "mu", "distance"])
        for k, mu in enumerate(spec["frictions"]):
            out.writerow([k, repr(mu), repr(slide(spec, mu))])


if __name__ == "__main__":
    main()
