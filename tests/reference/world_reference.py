"""The pybullet 3.2.7 reference for snakesim's world-file parity tests.

Reads a world file (YAML) and builds it as a pybullet user does: the ground first, its friction, then
every obstacle in file order, each with createCollisionShape + createMultiBody(0, ...) (+ changeDynamics
when it sets a friction); heightfield CSVs are read relative to the world file. Then the robot (the
paper's cube snake, or a URDF) and gravity in the order of the plain references, and a 1/240 s run,
one CSV row per step with the state after it (columns as pybullet_reference.py and urdf_reference.py).

Usage:
    python world_reference.py SCENARIOS.json OUT_DIR

A scenario: name, world (path of the world file), body ("cubes" or "urdf"), start [x, y, z, yaw], and
    cubes: joints, preset, steps (driven by snake.py's wave with force 10, as pybullet_reference's gait)
    urdf:  urdf, inertia, friction, kp, kd, max_velocity, targets (as urdf_reference.py)

The world file's generators (rough ground, pegs) are not read here: the tests hand this script their
expansion (a heightfield CSV, a list of obstacles), which is the input a pybullet user would write.
This file is independent of snakesim.
"""

import csv
import json
import math
import os
import sys

import pybullet as p
import yaml
from pybullet_utils import bullet_client

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paper_env_reference import create_snake  # noqa: E402
from pybullet_reference import MASSES, SnakeWave  # noqa: E402
from urdf_reference import drive  # noqa: E402

DT = 1.0 / 240.0


def read_heightfield(path):
    """One line per grid line along y, one value per point along x; blank lines skipped."""
    with open(path) as f:
        lines = [[float(v) for v in line.split(",")] for line in f if line.strip()]
    return lines


def build_world(client, world_path):
    with open(world_path) as f:
        world = yaml.safe_load(f) or {}
    return build_world_from(client, world, os.path.dirname(world_path))


def build_world_from(client, world, base_dir):
    """The world of a parsed world file (a dict); heightfield files are read relative to base_dir."""
    ((kind, args),) = world.get("ground", {"plane": {}}).items()
    if kind == "plane":
        ground = client.createMultiBody(0, client.createCollisionShape(p.GEOM_PLANE))
    elif kind == "slope":
        orientation = client.getQuaternionFromEuler([math.radians(args["degrees"]), 0, 0])
        shape = client.createCollisionShape(p.GEOM_PLANE)
        ground = client.createMultiBody(0, shape, -1, [0, 0, 0], orientation)
    elif kind == "heightfield":
        lines = read_heightfield(os.path.join(base_dir, args["file"]))
        shape = client.createCollisionShape(
            p.GEOM_HEIGHTFIELD,
            meshScale=args["scale"],
            heightfieldData=[v for line in lines for v in line],
            numHeightfieldRows=len(lines[0]),
            numHeightfieldColumns=len(lines),
        )
        ground = client.createMultiBody(0, shape)
    else:
        raise ValueError(f"ground {kind!r} must be expanded by the test")
    if "ground_friction" in world:
        client.changeDynamics(ground, -1, lateralFriction=world["ground_friction"])
    assert "pegs" not in world, "pegs must be expanded by the test"
    for o in world.get("obstacles", []):
        if o["shape"] == "box":
            shape = client.createCollisionShape(p.GEOM_BOX, halfExtents=o["half_extents"])
        elif o["shape"] == "cylinder":
            shape = client.createCollisionShape(p.GEOM_CYLINDER, radius=o["radius"], height=o["height"])
        elif o["shape"] == "sphere":
            shape = client.createCollisionShape(p.GEOM_SPHERE, radius=o["radius"])
        else:
            raise ValueError(o["shape"])
        orientation = client.getQuaternionFromEuler([0, 0, o.get("yaw", 0.0)])
        body = client.createMultiBody(0, shape, -1, o["position"], orientation)
        if "lateral_friction" in o:
            client.changeDynamics(body, -1, lateralFriction=o["lateral_friction"])


def header(m):
    h = ["step", "t", "base_x", "base_y", "base_z", "base_qx", "base_qy", "base_qz", "base_qw"]
    h += [f"q{j}" for j in range(m)] + ["vx", "vy", "vz", "wx", "wy", "wz"]
    return h + [f"qd{j}" for j in range(m)] + [f"tau{j}" for j in range(m)]


def row(client, uid, joints, step):
    pos, orn = client.getBasePositionAndOrientation(uid)
    lin, ang = client.getBaseVelocity(uid)
    states = client.getJointStates(uid, joints) if joints else []
    out = [step, step * DT, *pos, *orn, *(s[0] for s in states), *lin, *ang]
    out += [s[1] for s in states] + [s[3] for s in states]
    return [repr(v) if isinstance(v, float) else v for v in out]


def run_cubes(client, scenario, writer):
    joints = scenario["joints"]
    _, link_mass = MASSES[scenario["preset"]]
    client.setGravity(0, 0, -9.81)
    x, y, z, yaw = scenario["start"]
    uid = create_snake(
        client, joints, [x, y, z], client.getQuaternionFromEuler((0, 0, yaw)), link_mass=link_mass
    )
    wave = SnakeWave()
    writer.writerow(header(joints))
    for step in range(1, scenario["steps"] + 1):
        for j, target in enumerate(wave.targets(joints)):
            client.setJointMotorControl2(uid, j, p.POSITION_CONTROL, targetPosition=target, force=10.0)
        client.stepSimulation()
        writer.writerow(row(client, uid, list(range(joints)), step))


def run_urdf(client, scenario, writer):
    x, y, z, yaw = scenario["start"]
    flags = p.URDF_USE_INERTIA_FROM_FILE if scenario.get("inertia") == "file" else 0
    uid = client.loadURDF(
        scenario["urdf"], [x, y, z], client.getQuaternionFromEuler([0, 0, yaw]), flags=flags
    )
    client.setGravity(0, 0, -9.81)
    for link, friction in scenario.get("friction", []):
        client.changeDynamics(uid, link, anisotropicFriction=friction)
    movable, forces = [], []
    for j in range(client.getNumJoints(uid)):
        info = client.getJointInfo(uid, j)
        if info[2] in (p.JOINT_REVOLUTE, p.JOINT_PRISMATIC):
            movable.append(j)
            forces.append(info[10])
    m = len(movable)
    kp, kd = scenario.get("kp", 0.1), scenario.get("kd", 1.0)
    with open(scenario["targets"]) as f:
        targets = [[float(v) for v in r] for r in csv.reader(f)]
    writer.writerow(header(m))
    max_velocity = scenario.get("max_velocity")
    for step, targets_row in enumerate(targets, start=1):
        drive(client, uid, movable, targets_row, forces, kp, kd, max_velocity)
        client.stepSimulation()
        writer.writerow(row(client, uid, movable, step))


def run(scenario, out_path):
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    try:
        build_world(client, scenario["world"])
        with open(out_path, "w", newline="") as f:
            writer = csv.writer(f)
            if scenario["body"] == "cubes":
                run_cubes(client, scenario, writer)
            else:
                run_urdf(client, scenario, writer)
    finally:
        client.disconnect()


def main(argv):
    if len(argv) != 3:
        sys.exit("usage: world_reference.py SCENARIOS.json OUT_DIR")
    with open(argv[1]) as f:
        scenarios = json.load(f)
    os.makedirs(argv[2], exist_ok=True)
    for scenario in scenarios:
        run(scenario, os.path.join(argv[2], scenario["name"] + ".csv"))


if __name__ == "__main__":
    main(sys.argv)
