"""The paper's snake environment as a Gymnasium env."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from snakesim import _core
from snakesim.envs.config import ENV_DEFAULTS as _D
from snakesim.envs.config import GOAL_ENV_DEFAULTS as _G
from snakesim.envs.config import PEGS_ENV_DEFAULTS as _P
from snakesim.envs.config import ROUGH_ENV_DEFAULTS as _R
from snakesim.envs.config import SWIM_ENV_DEFAULTS as _S
from snakesim.envs.config import action_array, env_config, file_keyword, observation_slice
from snakesim.envs.render import top_down


class ClosedCore:
    """Stands for an env's Rust core once the env is closed: every use raises
    ``gymnasium.error.ClosedEnvironmentError`` (Gymnasium's error for an env used after ``close()``)."""

    __slots__ = ("_owner",)

    def __init__(self, owner: str) -> None:
        self._owner = owner

    def __getattr__(self, name: str) -> Any:
        raise gymnasium.error.ClosedEnvironmentError(
            f"{self._owner} was closed (close() released its worlds): make a new one"
        )


class SnakeEnv(gymnasium.Env):
    """A snake of N position-controlled joints that must crawl to a goal on a plane.

    The environment of "Simulating Snakes" (snakebot-gym's ``Snake-v0``) on snakesim's Bullet core;
    with ``preset="snakebot-gym"`` and the default arguments it gives bit-identical observations and
    rewards to the paper's pybullet env for the same start and actions.

    **Action space**: ``Box(-1, 1, (N,), float32)``. Joint target angles, radians, times
    ``action_scale``; actions are clipped to [-1, 1] first. Integer arrays are taken as numbers; NaN or
    a wrong shape raise ``ValueError``, a non-numeric dtype ``TypeError``. Other action modes
    (``action={"mode": ...}``): ``"gait"``, ``Box(-1, 1, (3,))``
    setting the steering, amplitude and frequency of a lateral-undulation wave within the ranges
    ``action["steering"]`` ([-0.5, 0.5] rad), ``action["amplitude"]`` ([0.2, 0.6] rad) and
    ``action["frequency"]`` ([0.4, 1.0] Hz), the wave's phase carried across steps; ``"residual"``,
    ``Box(-1, 1, (N,))``, pybullet snake.py's wave (0.4 rad, 1.5 s) plus ``action * residual_scale``
    (0.3 rad) per joint. ``baseline:steer`` sharing gait actions (a correction to its steering, or
    a hand-over near the goal) is a wrapper, not an env keyword: :class:`snakesim.wrappers.SteerAssist`
    (a run configuration's ``steer_assist``).

    **Observation space**: ``Box(-inf, inf, (D,), float32)``, every value the simulator's double cast
    to float32. ``env.observation_structure`` names its parts in order, name -> size, summing to D
    (Gymnasium's convention, as Swimmer-v5's; built from the one description in snake-core,
    ``ObservationLayout::structure``); ``snakesim.envs.config.observation_slice(structure, name)``
    gives a part's indices. On a ``gymnasium.make`` env, whose wrappers pass on no attribute in
    Gymnasium 1.x, it is ``env.unwrapped.observation_structure`` (or
    ``env.get_wrapper_attr("observation_structure")``). The parts, in order, of a snake of N joints
    (a robot: its movable joints):

    =================  ======  =====================================================================
    name               size    meaning
    =================  ======  =====================================================================
    ``base_position``  2       base (head) x and y in the world, m
    ``joint_states``   2N      per joint from the head, its angle (rad) and velocity (rad/s),
                               interleaved: angle 0, velocity 0, angle 1, ...
    ``goal_vector``    2       goal minus base position in the head frame (x: left, -y: ahead), m
    ``heading``        2       sin and cos of the head frame's heading
    ``base_velocity``  2       the head's planar velocity in the head frame, m/s
    ``wave_phase``     2       sin and cos of the wave's phase at the head
    ``world_up``       3       the world's up in the head's own frame; (0, 0, 1) upright
    ``height_map``     side^2  ground height minus the head's z on the height map's grid, m
    =================  ======  =====================================================================

    ``observation="paper"`` (the default): ``base_position`` and ``joint_states``, D = 2 + 2N.
    ``observation="extended"`` adds ``goal_vector``, ``heading`` and ``base_velocity`` and, in the gait
    and residual action modes, ``wave_phase``. ``observation="terrain"`` adds to that ``world_up`` and
    ``height_map`` (25 values, last): the ground's height minus the head's z at a 5 x 5 grid of
    points 0.75 m apart, centred on the head and turned with its heading: five rows from 1.5 m ahead
    to 1.5 m behind, each from 1.5 m to the right to 1.5 m to the left (docs/tasks.md, "The terrain
    observation"); ``height_map={"side": 9, "spacing": 0.75}`` makes it a 9 x 9 grid (81 values;
    ``side`` odd, at most 15, ``spacing`` in (0, 2] m) that sees 3 m around. Its goal vector,
    heading, velocity and map are in the rolled head frame: the heading of the body's long axis, with
    left mirrored while the head is upside down, so that rolling over on hills does not scramble
    them (upright and level, the extended frame).

    **Reward**: minus the planar head-goal distance (times ``reward["distance_weight"]``, 1); 100
    instead once the head is within ``goal_radius`` of the goal. Optional terms (``reward={...}``, off
    by default): progress toward the goal (with ``progress_around_craters`` or
    ``progress_around_ridges``, along the shortest way around the rough ground's craters or ridges),
    a smoothness penalty on the change of the action between
    steps, an energy penalty on the motors' work. Every term is reported in ``info``, with the
    episode's mechanical ``work`` (J), ``path_length`` and ``displacement`` (m) so far.

    **Episode end**: ``terminated`` when the goal is reached; ``truncated`` after
    ``max_episode_steps`` env steps (5000, as ``Snake-v0``). ``max_episode_steps=None``: no limit of
    the env's own, for a ``TimeLimit`` wrapper to truncate; ``gymnasium.make`` makes the env so and
    truncates at the spec's 5000, or at T with ``gymnasium.make(..., max_episode_steps=T)``.

    **Start state**: each reset builds a fresh world, drops the snake from z = 0.5 at
    x, y ~ U(-0.5, 0.5) with heading ~ U(-0.2, 0.2) rad, and takes one physics step before the first
    observation, as the paper's env does. ``reset(options={"start": (x, y, z, yaw)})`` places it
    exactly; ``options={"goal": (x, y)}`` moves the goal for that episode. With
    ``goal_distribution={"distance": [lo, hi], "bearing": [lo, hi]}`` each reset draws the goal at a
    uniform distance (m) and bearing (rad, 0 ahead of the head, positive to its left) from the start.

    **Arguments**: ``joints`` (5), ``preset`` ("paper": every cube 0.06 kg; "snakebot-gym": links
    1.0 kg as the paper's code), ``goal`` ((0, -10)), ``goal_distribution`` (None: the fixed goal),
    ``goal_radius`` (1.0), ``max_episode_steps`` (5000), ``physics_steps_per_env_step`` (1),
    ``start`` (ranges of x, y, yaw and z), ``action_scale`` (1.0), ``action`` (mode and ranges;
    "joints"), ``observation`` ("paper"), ``reward`` (terms and weights), ``snake`` (physical
    parameters over the preset's), ``robot`` (None; or a URDF or robot file, see ``robots/``: then the
    action holds one value per movable joint in pybullet's joint order, the observation one (angle,
    velocity) pair per movable joint, and the start places the root link's frame; ``joints`` and
    ``preset`` are ignored), ``world`` (None: the flat plane; or a world file, see ``worlds/`` and
    docs/worlds.md: its ground, friction and obstacles, built at each reset before the robot; raise
    ``start``'s z on raised ground); ``robot`` and ``world`` also take a record of a file's texts
    (``{"path": ..., "files": {name: text}}``, what a model records: docs/formats.md), ``randomize``
    (None; a mapping of ``ground_friction``, ``mass_scale``, ``effort_scale``, ``kp_scale``,
    ``kd_scale``, ``latency_steps``, ``obs_noise``, ``skin_friction_scale``, ``current_speed`` and
    ``current_heading`` (a water current, in a world with water) to ``[low, high]``,
    drawn at each reset from that reset's seed on a stream of its own; reset's ``info["physics"]``
    holds the draw; zero-width ranges at the nominal values are the plain env, bit for bit;
    docs/guide.md, "Randomized physics"), ``render_mode`` (None or "rgb_array").

    **Limits**: positions (start x, y; goals) within 10 km, start heights 0-100 m, reward weights within
    1e6, ``physics_steps_per_env_step`` at most 240, episodes at most 10^7 steps (``snakesim.limits.LIMITS``
    holds them all); a value outside raises ``ValueError`` naming the field. Observations and rewards are
    finite, or ``step()`` raises. One env may be used from several threads: calls take turns.

    **Pickling** carries the configuration only, not the episode (a Bullet world cannot be saved bit
    for bit): the unpickled env needs ``reset()``, and its ``step()`` raises
    ``gymnasium.error.ResetNeeded`` until then, also under wrappers that saw a reset.

    **Closing** (``close()``) releases the Bullet world; afterwards ``reset``, ``step`` and whatever
    reads the world raise ``gymnasium.error.ClosedEnvironmentError`` (``close()`` again does nothing).

    **Version history** (Gymnasium's rule: a change that can change learning, in the observation, the
    action, the reward, the episode's end, the dynamics or a default, bumps the id's ``-vN``; one that
    cannot, such as speed or documentation, keeps it): v0, initial: the paper's env.
    :class:`SnakeGoalEnv` (``snakesim/SnakeGoal-v0``) is the same env with the goal-reaching task's
    defaults.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 30}
    #: Whose defaults the keywords override (snake-rl's ``EnvConfig::for_task``).
    task = "paper"

    def __init__(
        self,
        joints: int = _D["joints"],
        preset: str = _D["preset"],
        goal: Sequence[float] = tuple(_D["goal"]),
        goal_distribution: Mapping[str, Any] | None = _D["goal_distribution"],
        goal_radius: float = _D["goal_radius"],
        max_episode_steps: int | None = _D["max_episode_steps"],
        physics_steps_per_env_step: int = _D["physics_steps_per_env_step"],
        start: Mapping[str, Any] | None = None,
        action_scale: float = _D["action_scale"],
        action: Mapping[str, Any] | None = None,
        observation: str = _D["observation"],
        reward: Mapping[str, Any] | None = None,
        snake: Mapping[str, Any] | None = None,
        robot: str | os.PathLike[str] | Mapping[str, Any] | None = _D["robot"],
        world: str | os.PathLike[str] | Mapping[str, Any] | None = _D["world"],
        terrain: Mapping[str, Any] | None = _D["terrain"],
        height_map: Mapping[str, Any] | None = _D["height_map"],
        randomize: Mapping[str, Any] | None = _D["randomize"],
        render_mode: str | None = None,
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"unknown render_mode {render_mode!r} (expected None or 'rgb_array')")
        # Kept as given (the Rust side checks them), for pickling and for SB3's get_attr.
        self._kwargs = dict(
            joints=joints,
            preset=preset,
            goal=goal,
            goal_distribution=goal_distribution,
            goal_radius=goal_radius,
            max_episode_steps=max_episode_steps,
            physics_steps_per_env_step=physics_steps_per_env_step,
            start=start,
            action_scale=action_scale,
            action=action,
            observation=observation,
            reward=reward,
            snake=snake,
            robot=file_keyword(robot),
            world=file_keyword(world),
            terrain=terrain,
            height_map=height_map,
            randomize=randomize,
        )
        self._config_json = env_config(task=self.task, **self._kwargs)
        self._env = _core.Env(self._config_json)
        self.render_mode = render_mode
        self.joints = self._env.joints
        self.action_space = spaces.Box(-1.0, 1.0, (self._env.action_dim,), dtype=np.float32)
        self.observation_space = spaces.Box(-np.inf, np.inf, (self._env.observation_dim,), dtype=np.float32)
        #: The observation's parts, name -> size, in order (Gymnasium's ``observation_structure``).
        self.observation_structure: dict[str, int] = self._env.observation_structure
        self._base_position = observation_slice(self.observation_structure, "base_position")
        self._trail: list[tuple[float, float]] = []
        self._unpickled = False

    @property
    def config(self) -> dict[str, Any]:
        """The resolved configuration (every field, defaults included)."""
        return json.loads(self._env.config_json())

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        options = dict(options or {})
        start = options.pop("start", None)
        goal = options.pop("goal", None)
        if options:
            raise ValueError(f"unknown reset options {sorted(options)} (expected 'start' and/or 'goal')")
        if seed is None and not hasattr(self, "_seeded"):
            # Without a seed the first reset draws one from Gymnasium's RNG, so episodes stay random.
            seed = int(self.np_random.integers(2**63 - 1))
        self._seeded = True
        self._unpickled = False
        obs, info = self._env.reset(
            seed, None if start is None else tuple(start), None if goal is None else tuple(goal)
        )
        self._trail = []
        return obs, info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._unpickled:
            raise gymnasium.error.ResetNeeded(
                "this env was unpickled: a pickle carries the configuration, not the episode; call reset()"
            )
        obs, reward, terminated, truncated, info = self._env.step(action_array(action))
        if self.render_mode is not None:
            x, y = obs[self._base_position].tolist()
            self._trail.append((x, y))
        return obs, reward, terminated, truncated, info

    def cube_poses(self) -> np.ndarray:
        """The pose of every cube now, shape (N + 1, 7): x, y, z, qx, qy, qz, qw (metres; quaternion
        x, y, z, w), the head (base) first, as a fresh array. Raises RuntimeError before the first reset."""
        return np.asarray(self._env.cube_poses(), dtype=np.float64)

    def set_physics_trace(self, on: bool) -> None:
        """Turns the physics trace on or off (off by default): while on, every reset and step records
        the full state after each of its physics steps, read with :meth:`physics_trace`. Observations
        and rewards are the same bits either way."""
        self._env.set_physics_trace(bool(on))

    def physics_trace(self) -> dict[str, np.ndarray] | None:
        """The state after each physics step of the latest reset or step, K rows (K = 1 after a reset,
        ``physics_steps_per_env_step`` after a step): ``steps`` (K,) the world's physics-step numbers
        (the reset's own step is 1), ``times`` (K,) seconds, ``poses`` (K, N + 1, 7) every cube's pose
        as :meth:`cube_poses`, ``positions``, ``velocities``, ``torques`` (the motors' applied torques,
        N m) and ``targets`` (K, N; NaN on the reset's step, which has none). None while the trace is
        off. Used by :class:`snakesim.wrappers.RerunLogger`."""
        return self._env.physics_trace()

    @property
    def goal(self) -> tuple[float, float]:
        """The current episode's goal (x, y): ``goal``, or the one passed in ``reset(options=...)``."""
        x, y = self._env.goal
        return float(x), float(y)

    @property
    def half_extent(self) -> float:
        """Half the side of each cube, metres."""
        return float(self._env.half_extent)

    def render(self) -> np.ndarray | None:
        """A top-down RGB image (``render_mode="rgb_array"``) of the snake, its path and the goal."""
        if self.render_mode is None:
            gymnasium.logger.warn("render() called without a render_mode; pass render_mode='rgb_array'")
            return None
        goal = self._env.goal
        shapes = self._env.robot_shapes()  # a robot's link shapes; None for the built-in cubes
        return top_down(
            self._env.cube_poses(),
            self._env.half_extent,
            goal,
            self._env.goal_radius,
            trail=np.asarray(self._trail) if self._trail else None,
            shapes=None if shapes is None else json.loads(shapes),
        )

    def close(self) -> None:
        # The Bullet world goes with the core; every later use of it says the env was closed.
        self._env = ClosedCore(f"this {type(self).__name__}")

    # A pickle carries the configuration only (what SubprocVecEnv and copies need), not an episode: the
    # Bullet world's state cannot be saved bit for bit. The unpickled env starts fresh, as after
    # __init__, and its step() says so until reset() is called, even under wrappers that saw a reset.
    def __getstate__(self) -> dict[str, Any]:
        return {"kwargs": self._kwargs, "render_mode": self.render_mode}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(**state["kwargs"], render_mode=state["render_mode"])
        self._unpickled = True


class SnakeGoalEnv(SnakeEnv):
    """A snake that steers to goals anywhere around it: ``snakesim/SnakeGoal-v0``.

    The same simulation as :class:`SnakeEnv` (see it for every keyword) with the goal-reaching task's
    defaults (snake-rl's ``EnvConfig::goal_task``, found best in docs/experiments.md, "Beyond the
    paper"):

    - **Goal**: drawn at each reset 5-15 m from the start at any bearing (``goal_distribution``);
      reached within ``goal_radius`` 1 m.
    - **Action space**: ``Box(-1, 1, (3,), float32)``, the ``gait`` mode: each action sets the
      lateral-undulation wave's steering ([-0.5, 0.5] rad), amplitude ([0.2, 0.6] rad) and frequency
      ([0.4, 1.0] Hz); the wave's phase runs on across steps and the joints follow it at 240 Hz.
      ``action={"mode": "residual"}`` instead adds a per-joint correction to a fixed wave, and
      ``action={"mode": "joints"}`` sets the joint targets as the paper does.
    - **Control rate**: 30 Hz (``physics_steps_per_env_step`` 8).
    - **Observation space**: ``Box(-inf, inf, (2 + 2N + 8,), float32)``, the ``extended`` layout;
      ``observation_structure`` (see :class:`SnakeEnv` for every part):

      =================  ====  ===================================================================
      name               size  meaning
      =================  ====  ===================================================================
      ``base_position``  2     base (head) x and y in the world, m
      ``joint_states``   2N    per joint, its angle (rad) and velocity (rad/s), interleaved
      ``goal_vector``    2     goal minus base position in the head frame, m
      ``heading``        2     sin and cos of the head frame's heading
      ``base_velocity``  2     the head's planar velocity in the head frame, m/s
      ``wave_phase``     2     sin and cos of the wave's phase at the head (gait, residual modes)
      =================  ====  ===================================================================

      ``observation="terrain"`` appends ``world_up`` (3) and ``height_map`` (side^2, 25 by default);
      ``observation="paper"`` keeps only ``base_position`` and ``joint_states``.
    - **Reward**: progress towards the goal (metres per step, ``progress_weight`` 1) and 10 on
      arrival (``success_reward``); no distance term (``distance_weight`` 0).
    - **Episode end**: the goal reached (terminated) or 600 env steps, 20 s (truncated).
    - **Arguments**: :class:`SnakeEnv`'s, with the defaults above (``joints`` 5, ``preset`` "paper").

    **Version history** (a change that can change learning bumps ``-vN``; see :class:`SnakeEnv`):
    v0, initial.
    """

    task = "goal"

    def __init__(
        self,
        joints: int = _G["joints"],
        preset: str = _G["preset"],
        goal: Sequence[float] = tuple(_G["goal"]),
        goal_distribution: Mapping[str, Any] | None = _G["goal_distribution"],
        goal_radius: float = _G["goal_radius"],
        max_episode_steps: int | None = _G["max_episode_steps"],
        physics_steps_per_env_step: int = _G["physics_steps_per_env_step"],
        start: Mapping[str, Any] | None = None,
        action_scale: float = _G["action_scale"],
        action: Mapping[str, Any] | None = None,
        observation: str = _G["observation"],
        reward: Mapping[str, Any] | None = None,
        snake: Mapping[str, Any] | None = None,
        robot: str | os.PathLike[str] | Mapping[str, Any] | None = _G["robot"],
        world: str | os.PathLike[str] | Mapping[str, Any] | None = _G["world"],
        terrain: Mapping[str, Any] | None = _G["terrain"],
        height_map: Mapping[str, Any] | None = _G["height_map"],
        randomize: Mapping[str, Any] | None = _G["randomize"],
        render_mode: str | None = None,
    ) -> None:
        super().__init__(
            joints=joints,
            preset=preset,
            goal=goal,
            goal_distribution=goal_distribution,
            goal_radius=goal_radius,
            max_episode_steps=max_episode_steps,
            physics_steps_per_env_step=physics_steps_per_env_step,
            start=start,
            action_scale=action_scale,
            action=action,
            observation=observation,
            reward=reward,
            snake=snake,
            robot=robot,
            world=world,
            terrain=terrain,
            height_map=height_map,
            randomize=randomize,
            render_mode=render_mode,
        )


class SnakePegsEnv(SnakeGoalEnv):
    """A goal behind a random peg field that a steered gait jams in: ``snakesim/SnakePegs-v0``.

    The goal task (:class:`SnakeGoalEnv`: actions, control rate, observation, reward) with these
    defaults (snake-rl's ``EnvConfig::pegs_task``; docs/tasks.md):

    - **Goal**: drawn at each reset 4-6 m from the start within 45 degrees of its heading
      (``goal_distribution`` distance [4, 6], bearing [-pi/4, pi/4]); reached within 1 m.
    - **Pegs** (``terrain={"pegs": ...}``), laid out anew at each reset from the episode's seed: upright
      cylinders of ``radius`` 0.03 m and ``height`` 0.3 m on a grid of ``spacing`` 0.3 m in a band
      ``width`` 3 m wide along the start-goal line, from ``start_clear`` 1 m after the start to
      ``goal_clear`` 1 m before the goal; each grid point holds a peg with probability ``density``
      0.7 and is moved by up to ``jitter`` 0.08 m along and across.
    - **Episode end**: the goal reached (terminated) or 900 env steps, 30 s (truncated).

    - **Observation space**: the goal task's (:class:`SnakeGoalEnv`), ``observation_structure``
      ``base_position`` (2), ``joint_states`` (2N), ``goal_vector`` (2), ``heading`` (2),
      ``base_velocity`` (2), ``wave_phase`` (2); the pegs are not observed (``observation="terrain"``
      appends ``world_up`` (3) and a ``height_map`` (side^2) of the ground, which pegs are not part of).
    - **Arguments**: :class:`SnakeEnv`'s, with the defaults above.

    ``robot=`` puts a robot file's robot in the same task.

    **Version history** (a change that can change learning bumps ``-vN``; see :class:`SnakeEnv`):
    v0, initial.
    """

    task = "pegs"

    def __init__(
        self,
        goal_distribution: Mapping[str, Any] | None = _P["goal_distribution"],
        max_episode_steps: int | None = _P["max_episode_steps"],
        terrain: Mapping[str, Any] | None = _P["terrain"],
        **kwargs: Any,
    ) -> None:
        super().__init__(
            goal_distribution=goal_distribution,
            max_episode_steps=max_episode_steps,
            terrain=terrain,
            **kwargs,
        )


class SnakeRoughEnv(SnakeGoalEnv):
    """A goal across random rough ground with hills: ``snakesim/SnakeRough-v0``.

    The goal task (:class:`SnakeGoalEnv`: actions, control rate, observation, reward) with these
    defaults (snake-rl's ``EnvConfig::rough_task``; docs/tasks.md):

    - **Goal**: drawn at each reset 5-8 m from the start at any bearing (``goal_distribution``
      distance [5, 8]); reached within 1 m.
    - **Ground** (``terrain={"rough": ...}``), drawn anew at each reset from the episode's seed: the sum
      of bumps (``amplitude`` 0.08 m, ``wavelength`` 0.5 m) and hills (``hills_amplitude`` 1.2 m,
      ``hills_wavelength`` 3 m), value noise sampled every ``spacing`` 0.125 m over a square reaching
      ``margin`` 3 m beyond start and goal; Bullet's ground friction 0.5. A drawn start is raised by
      the ground's highest point within 1.5 m of the origin. No crater by default; ``{"rough":
      {"craters": {"count": 1}}}`` sinks one across the straight line to the goal, and
      ``"terminate": True`` among its keys ends an episode once the head is over its floor
      (docs/tasks.md, "A crater in the way"). No ridge by default; ``{"rough": {"ridges": {"count":
      1}}}`` raises one, 1.5 m high and 6 m long, across the straight line to the goal (docs/tasks.md,
      "A ridge across the way").
    - **Episode end**: the goal reached (terminated) or 900 env steps, 30 s (truncated); the head
      beyond the edge of the ground's square, falling off the world, ends it too (terminated,
      ``info["success"]`` False).

    - **Observation space**: the goal task's (:class:`SnakeGoalEnv`), ``observation_structure``
      ``base_position`` (2), ``joint_states`` (2N), ``goal_vector`` (2), ``heading`` (2),
      ``base_velocity`` (2), ``wave_phase`` (2); ``observation="terrain"`` appends ``world_up`` (3)
      and ``height_map`` (side^2, 25 by default), and puts the goal vector, heading, velocity and map
      in the rolled head frame (see :class:`SnakeEnv`).
    - **Arguments**: :class:`SnakeEnv`'s, with the defaults above.

    ``robot=`` puts a robot file's robot in the same task.

    **Version history** (a change that can change learning bumps ``-vN``; see :class:`SnakeEnv`):
    v0, initial.
    """

    task = "rough"

    def __init__(
        self,
        goal_distribution: Mapping[str, Any] | None = _R["goal_distribution"],
        max_episode_steps: int | None = _R["max_episode_steps"],
        terrain: Mapping[str, Any] | None = _R["terrain"],
        **kwargs: Any,
    ) -> None:
        super().__init__(
            goal_distribution=goal_distribution,
            max_episode_steps=max_episode_steps,
            terrain=terrain,
            **kwargs,
        )


class SnakeSwimEnv(SnakeGoalEnv):
    """A robot that swims to goals: ``snakesim/SnakeSwim-v0``.

    The goal task (:class:`SnakeGoalEnv`: actions, control rate, observation, reward) in water, with
    these defaults (snake-core's ``EnvConfig::swim_task``; docs/media.md, "Swimming to goals"):

    - **World**: a still pool, water 1 m deep over the plane, 20 m x 20 m (``world``: the built-in
      ``pool.yaml``, ``worlds/pool.yaml``'s water; Kelasidi et al.'s hydrodynamics, docs/media.md).
      Another ``world`` must have water. A current that pushes is the world's water entry
      (``current``), or drawn at every reset by ``randomize={"current_speed": [low, high],
      "current_heading": [low, high]}`` (m/s; radians from world +x).
    - **Goal**: drawn at each reset 3-6 m from the start at any bearing (``goal_distribution``
      distance [3, 6]), in the plane of the surface: the distance is measured across the water;
      reached within 1 m.
    - **Start**: x, y in [-0.5, 0.5] m, yaw in [-0.2, 0.2], z 0.98 m: the body's axis 2 cm under the
      pool's surface.
    - **Episode end**: the goal reached (terminated) or 900 env steps, 30 s (truncated).

    - **Observation space**: the goal task's (:class:`SnakeGoalEnv`), ``observation_structure``
      ``base_position`` (2), ``joint_states`` (2N), ``goal_vector`` (2), ``heading`` (2),
      ``base_velocity`` (2), ``wave_phase`` (2); the current is not observed (the velocity is over
      the ground, so drift shows in it). ``observation="terrain"`` appends ``world_up`` (3) and
      ``height_map`` (side^2) of the ground under the water.
    - **Arguments**: :class:`SnakeEnv`'s, with the defaults above.

    ``robot="robots/mamba-10.yaml"`` swims NTNU's Mamba as Kelasidi et al. modelled it; the default
    body is the cube snake, which floats on the surface.

    **Version history** (a change that can change learning bumps ``-vN``; see :class:`SnakeEnv`):
    v0, initial.
    """

    task = "swim"

    def __init__(
        self,
        goal_distribution: Mapping[str, Any] | None = _S["goal_distribution"],
        max_episode_steps: int | None = _S["max_episode_steps"],
        world: str | os.PathLike[str] | Mapping[str, Any] | None = _S["world"],
        **kwargs: Any,
    ) -> None:
        super().__init__(
            goal_distribution=goal_distribution,
            max_episode_steps=max_episode_steps,
            world=world,
            **kwargs,
        )


#: The env class of each task.
TASK_ENVS: dict[str, type[SnakeEnv]] = {
    cls.task: cls for cls in (SnakeEnv, SnakeGoalEnv, SnakePegsEnv, SnakeRoughEnv, SnakeSwimEnv)
}


def make_env(task: str = SnakeEnv.task, **kwargs: Any) -> SnakeEnv:
    """The env of ``task`` (``"paper"``: :class:`SnakeEnv`, ``"goal"``: :class:`SnakeGoalEnv`) with
    the given keywords, as a run's ``env`` table or a model's metadata names it."""
    if task not in TASK_ENVS:
        raise ValueError(f"task: unknown task {task!r} (expected one of: {', '.join(TASK_ENVS)})")
    return TASK_ENVS[task](**kwargs)
