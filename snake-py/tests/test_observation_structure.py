"""Every env names its observation (Gymnasium's ``observation_structure``, as Swimmer-v5's): name ->
size, in order, summing to the observation's length; each named part holds what its name says, and
each env's card (its class docstring) names every part."""

import gymnasium
import numpy as np
import pytest
import snakesim
from snakesim.agents.baselines import goal_bearing
from snakesim.envs.config import observation_slice
from snakesim.envs.env import TASK_ENVS

IDS = (snakesim.ENV_ID, snakesim.GOAL_ENV_ID, snakesim.PEGS_ENV_ID, snakesim.ROUGH_ENV_ID)
#: Each observation layout, the terrain one also with a larger height map than the default 5 x 5.
LAYOUTS = (
    {"observation": "paper"},
    {"observation": "extended"},
    {"observation": "terrain"},
    {"observation": "terrain", "height_map": {"side": 7, "spacing": 0.5}},
)


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("layout", LAYOUTS, ids=lambda k: "-".join(map(str, k.values())))
def test_the_structure_sums_to_the_observation_and_its_parts_hold_what_they_say(env_id, layout):
    env = gymnasium.make(env_id, joints=4, **layout).unwrapped
    structure = env.observation_structure
    assert list(structure)[:2] == ["base_position", "joint_states"]
    assert len(set(structure)) == len(structure)
    assert all(isinstance(size, int) and size > 0 for size in structure.values())
    assert sum(structure.values()) == env.observation_space.shape[0]
    extended = layout["observation"] != "paper"
    assert ("goal_vector" in structure) == extended
    assert ("height_map" in structure) == (layout["observation"] == "terrain")
    assert ("wave_phase" in structure) == (extended and env.config["action"]["mode"] != "joints")
    if "height_map" in structure:
        side = layout.get("height_map", {}).get("side", 5)
        assert structure["height_map"] == side * side and structure["world_up"] == 3
    assert structure["joint_states"] == 2 * env.joints
    # The vector envs' single env has the same structure.
    vector = gymnasium.make_vec(env_id, num_envs=2, joints=4, **layout)
    assert vector.unwrapped.observation_structure == structure
    vector.close()

    env.set_physics_trace(True)
    obs, info = env.reset(seed=3)
    for _ in range(5):
        obs, _, terminated, truncated, info = env.step(np.full(env.action_space.shape, 0.3, np.float32))
        assert not (terminated or truncated)
        part = {name: obs[observation_slice(structure, name)] for name in structure}
        assert len(np.concatenate(list(part.values()))) == len(obs)
        head = env.cube_poses()[0]
        np.testing.assert_array_equal(part["base_position"], head[:2].astype(np.float32))
        trace = env.physics_trace()
        angles, velocities = trace["positions"][-1], trace["velocities"][-1]
        np.testing.assert_array_equal(part["joint_states"][0::2], angles.astype(np.float32))
        np.testing.assert_array_equal(part["joint_states"][1::2], velocities.astype(np.float32))
        if extended:
            goal = np.subtract(env.goal, head[:2])
            assert np.hypot(*part["goal_vector"]) == pytest.approx(np.hypot(*goal), rel=1e-5)
            assert np.hypot(*part["heading"]) == pytest.approx(1.0, abs=1e-6)
            gx, gy = part["goal_vector"]
            assert goal_bearing(obs[None, :], structure)[0] == np.arctan2(gx, -gy)
        if "wave_phase" in structure:
            assert np.hypot(*part["wave_phase"]) == pytest.approx(1.0, abs=1e-6)
        if "world_up" in structure:
            assert np.linalg.norm(part["world_up"]) == pytest.approx(1.0, abs=1e-6)
    with pytest.raises(KeyError, match="no 'nothing'"):
        observation_slice(structure, "nothing")


@pytest.mark.parametrize("task", sorted(TASK_ENVS))
def test_each_env_card_names_every_part_and_states_the_versioning_rule(task):
    cls = TASK_ENVS[task]
    doc = cls.__doc__
    for layout in LAYOUTS:
        for name in cls(joints=3, **layout).observation_structure:
            assert f"``{name}``" in doc, (cls.__name__, name)
    for section in ("Observation space", "Action space", "Reward", "Episode end", "Arguments"):
        assert section in doc or section in TASK_ENVS["paper"].__doc__, (cls.__name__, section)
    assert "Version history" in doc and "bumps" in doc and "v0" in doc, cls.__name__


def test_a_gymnasium_make_env_gives_it_as_the_docstring_says():
    """``gymnasium.make``'s wrappers pass on no attribute (Gymnasium 1.x): the documented ways work."""

    env = gymnasium.make("snakesim/SnakeGoal-v0", joints=5)
    expected = snakesim.SnakeGoalEnv(joints=5).observation_structure
    assert env.unwrapped.observation_structure == expected
    assert env.get_wrapper_attr("observation_structure") == expected
    env.close()
