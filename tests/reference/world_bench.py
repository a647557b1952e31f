"""pybullet 3.2.7's physics steps per second on a world beside the flat plane, for `snake-cli bench --world`.

Usage: python world_bench.py WORLD.json JOINTS START_Z STEPS REPEATS

WORLD.json is a world file's content with its generators expanded (a heightfield file, a list of
obstacles), as world_reference.py builds it. Each repeat runs the flat plane, then the world (fresh
clients, the paper's cube snake at (0, 0, START_Z) on the flat plane's resting height raised as
snakesim raises it), and times only the control-and-step loop, as pybullet_bench.py does.
Prints one JSON object: {"flat": [steps/s ...], "world": [steps/s ...]}.
"""

import json
import os
import sys

import pybullet as p
from pybullet_utils import bullet_client

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paper_env_reference import HALF_EXTENT, create_snake  # noqa: E402
from pybullet_bench import timed_gait  # noqa: E402
from world_reference import build_world_from  # noqa: E402


def one_run(world, base_dir, joints, z, steps):
    client = bullet_client.BulletClient(connection_mode=p.DIRECT)
    # world_reference.py's order: the world, gravity, then the snake.
    build_world_from(client, world, base_dir)
    client.setGravity(0, 0, -9.81)
    uid = create_snake(client, joints, [0, 0, z], [0, 0, 0, 1], link_mass=0.06)
    return timed_gait(client, uid, joints, steps)


def main(argv):
    if len(argv) != 6:
        sys.exit("usage: world_bench.py WORLD.json JOINTS START_Z STEPS REPEATS")
    with open(argv[1]) as f:
        world = json.load(f)
    base_dir = os.path.dirname(os.path.abspath(argv[1]))
    joints, z, steps, repeats = int(argv[2]), float(argv[3]), int(argv[4]), int(argv[5])
    flat_world = {"ground": {"plane": {}}}
    out = {"flat": [], "world": []}
    for _ in range(repeats):
        out["flat"].append(one_run(flat_world, base_dir, joints, HALF_EXTENT, steps))
        out["world"].append(one_run(world, base_dir, joints, z, steps))
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv)
