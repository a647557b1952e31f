"""Property tests (hypothesis) over the env's constructor, reset options and actions: whatever a user
passes, the env returns finite observations and rewards or raises a ValueError, TypeError or (physics
that blew up) RuntimeError; nothing else, never a crash or a hang. Over model files: an edited
model loads as an agent that acts finitely, or is refused in one line naming the file. And over
`snakesim calibrate`'s inputs (its --fit items, targets and log CSVs): checked values or one line."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from snakesim import SnakeEnv, _core, agents
from snakesim.envs.config import ENV_KEYWORDS
from snakesim.runs.calibrate import (
    FIT_KEYS,
    CalibrationError,
    parse_fit,
    read_log,
    read_targets,
)

ROBOTS = Path(__file__).resolve().parents[2] / "robots"
WORLDS = ROBOTS.parent / "worlds"

# Examples per property: each builds a world and steps it a few times (~5 ms).
EXAMPLES = 500
USER_ERRORS = (ValueError, TypeError, RuntimeError)

anything = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        st.integers(),
        st.floats(),
        st.text(max_size=4),
    ),
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.tuples(inner, inner),
        st.dictionaries(st.text(max_size=12), inner, max_size=3),
    ),
    max_leaves=6,
)
plausible = {
    "joints": st.integers(1, 6),
    "preset": st.sampled_from(["paper", "snakebot-gym"]),
    "task": st.sampled_from(["paper", "goal"]),
    "goal": st.tuples(st.floats(-30, 30), st.floats(-30, 30)),
    "goal_radius": st.floats(0, 3),
    "max_episode_steps": st.integers(1, 50),
    "physics_steps_per_env_step": st.integers(1, 12),
    "action_scale": st.floats(0.01, 3),
    "observation": st.sampled_from(["paper", "extended", "terrain"]),
    "action": st.fixed_dictionaries(
        {"mode": st.sampled_from(["joints", "gait", "residual"])},
    ),
    "height_map": st.fixed_dictionaries({"side": st.integers(-1, 17), "spacing": st.floats(-0.5, 2.5)}),
    "reward": st.one_of(
        st.dictionaries(
            st.sampled_from(["distance_weight", "progress_weight", "smoothness_weight", "energy_weight"]),
            st.floats(-3, 3),
            max_size=3,
        ),
        st.fixed_dictionaries(
            {"progress_around_craters": st.booleans(), "progress_around_ridges": st.booleans()}
        ),
    ),
    "start": st.fixed_dictionaries({"z": st.floats(0, 1)}),
    "goal_distribution": st.one_of(
        st.none(), st.fixed_dictionaries({"distance": st.tuples(st.floats(0, 5), st.floats(5, 20))})
    ),
    "robot": st.sampled_from([None, str(ROBOTS / "paper-cubes-5.yaml"), str(ROBOTS / "wheeled-8.urdf")]),
    "terrain": st.sampled_from(
        [
            None,
            {
                "pegs": {
                    "spacing": 0.4,
                    "radius": 0.03,
                    "height": 0.3,
                    "jitter": 0.05,
                    "density": 0.5,
                    "width": 2.0,
                }
            },
            {
                "rough": {
                    "amplitude": 0.05,
                    "wavelength": 0.5,
                    "hills_amplitude": 0.3,
                    "hills_wavelength": 3.0,
                }
            },
            {"rough": {"craters": {"count": 2, "radius": 2.0, "depth": 1.0, "wall": 0.5}}},
            {"rough": {"craters": {"count": 1, "terminate": True}}},
            {"rough": {"ridges": {"count": 2, "length": 3.0, "clearance": 0.5}}},
            {"rough": {"craters": {"count": 1}, "ridges": {"count": 1}}},
        ]
    ),
    "world": st.sampled_from(
        [None, str(WORLDS / "slope-10.yaml"), str(WORLDS / "rough.yaml"), str(WORLDS / "pegs.yaml")]
    ),
    "snake": st.dictionaries(
        st.sampled_from(["link_mass", "base_mass", "motor_force", "lateral_friction"]),
        st.floats(0.01, 20),
        max_size=2,
    ),
    "randomize": st.one_of(
        st.none(),
        st.dictionaries(
            st.sampled_from(
                ["ground_friction", "mass_scale", "effort_scale", "kp_scale", "kd_scale", "obs_noise"]
            ),
            st.tuples(st.floats(-0.5, 3), st.floats(-0.5, 3)),
            max_size=3,
        ),
        st.fixed_dictionaries({"latency_steps": st.tuples(st.integers(-1, 40), st.integers(-1, 40))}),
    ),
}


@st.composite
def env_kwargs(draw):
    """Keywords mostly plausible, some holding anything at all, now and then an unknown one."""
    kwargs = {}
    for key in draw(st.lists(st.sampled_from(ENV_KEYWORDS), unique=True, max_size=5)):
        wild = draw(st.integers(0, 9)) == 0
        kwargs[key] = draw(anything if wild else plausible[key])
    if draw(st.integers(0, 19)) == 0:
        kwargs[draw(st.text(min_size=1, max_size=8))] = draw(anything)
    return kwargs


def numbers(n):
    return st.lists(st.floats(width=32), min_size=n, max_size=n)


@st.composite
def reset_options(draw):
    options = {}
    if draw(st.booleans()):
        options["start"] = draw(
            st.one_of(st.tuples(*[st.floats(-3, 3)] * 2, st.floats(0, 1), st.floats(-4, 4)), anything)
        )
    if draw(st.booleans()):
        options["goal"] = draw(st.one_of(st.tuples(st.floats(-30, 30), st.floats(-30, 30)), anything))
    if draw(st.integers(0, 19)) == 0:
        options["bogus"] = 1
    return options


@st.composite
def action_arrays(draw, dim):
    kind = draw(st.integers(0, 9))
    if kind == 0:  # any shape, any dtype
        dtype = draw(st.sampled_from([np.float32, np.float64, np.int64, np.bool_, np.complex64, object]))
        shape = draw(st.lists(st.integers(0, 4), max_size=3))
        return np.zeros(shape, dtype=dtype)
    if kind == 1:  # right shape, any float
        return np.array(draw(numbers(dim)), dtype=np.float32)
    return np.array(draw(st.lists(st.floats(-1.5, 1.5), min_size=dim, max_size=dim)), dtype=np.float32)


def finite(obs, reward=0.0):
    return bool(np.isfinite(obs).all()) and math.isfinite(reward)


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(kwargs=env_kwargs(), options=reset_options(), seed=st.integers(0, 2**64 - 1), data=st.data())
def test_env_is_finite_or_a_typed_error(kwargs, options, seed, data):
    try:
        env = SnakeEnv(**kwargs)
    except USER_ERRORS as error:
        event(f"refused: {type(error).__name__}")
        return
    try:
        obs, _ = env.reset(seed=seed, options=options)
    except USER_ERRORS as error:
        event(f"reset refused: {type(error).__name__}")
        return
    event("env built and reset")
    assert finite(obs)
    dim = env.action_space.shape[0]
    for _ in range(data.draw(st.integers(1, 8))):
        action = data.draw(action_arrays(dim))
        try:
            obs, reward, terminated, truncated, _ = env.step(action)
        except USER_ERRORS as error:
            event(f"step refused: {type(error).__name__}")
            continue
        event("stepped")
        assert finite(obs, reward)
        assert obs.shape == env.observation_space.shape and obs.dtype == np.float32
        if terminated or truncated:
            break


# -- model files: whatever bytes a user points `snakesim evaluate` at ---------------------------------
MODEL = (Path(__file__).resolve().parents[2] / "models" / "goal-5.safetensors").read_bytes()


def _edit(data: bytes, edits: list[tuple[int, int, bytes]]) -> bytes:
    """Each edit (position, bytes to drop, bytes to put there) applied in turn."""
    out = bytearray(data)
    for at, drop, put in edits:
        at %= len(out) + 1
        out[at : at + drop] = put
    return bytes(out)


@settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    edits=st.lists(
        st.tuples(st.integers(0, 1 << 20), st.integers(0, 64), st.binary(max_size=16)), max_size=6
    ),
    name=st.sampled_from(["model.safetensors", "model.zip", "model.pt", "model"]),
)
def test_a_model_file_is_an_agent_or_one_line(tmp_path_factory, edits, name):
    """The shipped model, edited: `load_agent` gives an agent or an AgentError of one line that names
    the file, nothing else (a non-finite weight, a lying header, a truncated tensor...)."""
    path = tmp_path_factory.mktemp("model") / name
    path.write_bytes(_edit(MODEL, edits))
    try:
        agent = agents.load_agent(path)
    except agents.AgentError as error:
        message = str(error)
        event("refused")
        assert "\n" not in message and str(path) in message, message
        return
    event("loaded")
    obs = np.zeros((1, agent.policy.obs_dim), np.float32)
    assert np.isfinite(agent.act(obs)).all()


# -- snakesim calibrate's inputs: its --fit items, its targets and log CSVs ------------------------------
@settings(max_examples=300, deadline=None)
@given(
    items=st.lists(
        st.one_of(
            st.text(max_size=30),
            st.builds("{}={}:{}".format, st.sampled_from(FIT_KEYS), st.floats(0, 10), st.floats(0, 10)),
            st.builds(
                "{}={}:{}".format,
                st.sampled_from([*FIT_KEYS, "motors.stiffness", "", " motors.kp"]),
                st.one_of(st.floats(0, 10), st.floats(), st.text(max_size=5)),
                st.one_of(st.floats(0, 10), st.floats(), st.text(max_size=5)),
            ),
        ),
        max_size=4,
    )
)
def test_fit_items_are_bounds_or_one_line(items):
    """``--fit KEY=LOW:HIGH``: finite bounds 0 <= low < high of known keys, each once, or a one-line
    CalibrationError that names the argument, which the command names by its flag (issue 58: the
    library names no flag)."""
    from snakesim.cli.calibrate import CALIBRATE_FLAGS

    try:
        bounds = parse_fit(items)
    except CalibrationError as error:
        event("refused")
        message = error.naming(CALIBRATE_FLAGS)
        assert "\n" not in message and "--fit" in message, message
        assert "--fit" not in str(error), str(error)
        return
    event("bounds")
    assert bounds and set(bounds) <= set(FIT_KEYS)
    for low, high in bounds.values():
        assert math.isfinite(low) and math.isfinite(high) and 0 <= low < high


CALIBRATION_JOINTS = ["yaw0", "pitch1", "yaw2"]


def _calibration_csvs() -> tuple[bytes, bytes]:
    """A targets table and a log (``snake-cli run --output``'s columns) of three steps of three joints."""
    targets = ["step," + ",".join(CALIBRATION_JOINTS)]
    log = [",".join(_core.log_columns(3, False))]
    for k in range(1, 4):
        targets.append(f"{k},0.{k},-0.{k},0")
        log.append(f"{k},{k / 240!r},0.0{k},0,0.025,0,0,0,1,0.01,-0.0{k},1e-3")
    return ("\n".join(targets) + "\n").encode(), ("\n".join(log) + "\n").encode()


CALIBRATION_TARGETS, CALIBRATION_LOG = _calibration_csvs()
# What an edit puts in: a CSV's own tokens mostly, any bytes now and then.
CSV_BYTES = st.one_of(
    st.sampled_from([b"", b"0", b"7", b",", b"\n", b"\r\n", b" ", b"-", b".", b"e9", b"nan", b"inf", b"q3"]),
    st.binary(max_size=8),
)


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    edits=st.lists(st.tuples(st.integers(0, 1 << 10), st.integers(0, 8), CSV_BYTES), max_size=4),
    which=st.sampled_from(["targets", "log"]),
    steps=st.one_of(st.just(3), st.integers(1, 4)),
)
def test_calibration_csvs_are_tables_or_one_line(tmp_path_factory, edits, which, steps):
    """The targets and log CSVs of ``snakesim calibrate``, edited: a finite table of the robot's joints
    (targets: steps x joints, in the robot's order; log: steps x (7 + joints), as many rows as the
    targets) or a one-line CalibrationError naming the file."""
    path = tmp_path_factory.mktemp("calibration") / f"{which}.csv"
    path.write_bytes(_edit(CALIBRATION_TARGETS if which == "targets" else CALIBRATION_LOG, edits))
    try:
        if which == "targets":
            table = read_targets(path, CALIBRATION_JOINTS)
            assert table.ndim == 2 and table.shape[1] == len(CALIBRATION_JOINTS)
        else:
            table = read_log(path, len(CALIBRATION_JOINTS), steps)
            assert table.shape == (steps, 7 + len(CALIBRATION_JOINTS))
    except CalibrationError as error:
        event(f"{which} refused")
        message = str(error)
        assert "\n" not in message and str(path) in message, message
        return
    event(f"{which} read")
    assert table.dtype == np.float64 and table.shape[0] >= 1 and np.isfinite(table).all()
