"""Stable-Baselines3 2.x / PyTorch side of snake-rl's reference tests (tests/ppo_reference.rs).

    python ppo_reference.py SPEC.json OUT_DIR

SPEC.json holds a list of cases; each is one of:

- "ppo": network weights (SB3 state-dict names), one minibatch and PPO's settings. SB3's own
  ``PPO.train()`` runs one epoch over a rollout buffer holding exactly that minibatch (batch_size = its
  rows), so the loss terms come from SB3's logger, the clipped gradients from the parameters' ``.grad``
  and the parameters after one Adam step from the policy. Before training, ``evaluate_actions`` gives
  the log-probabilities, entropies and values, and the distribution the action means. With an
  "anchor" (a weight w and an anchor action per row), the loss gains ``w * mse_loss(mean,
  targets)`` (snakesim's `init.anchor`): torch's autograd gives that term's gradient on a fresh copy
  of the policy, added to SB3's, and ``torch.optim.Adam(eps=1e-5)`` takes the step with the sum
  (such cases set max_grad_norm beyond reach: the gradients are compared unclipped).
- "adam": parameters and a sequence of gradients through ``torch.optim.Adam(eps=1e-5)``.
- "gae": a recorded rollout through SB3's ``RolloutBuffer.compute_returns_and_advantage``.
- "normalize": a sequence of observation and reward batches through SB3's ``VecNormalize``.

OUT_DIR/<name>.json receives the results of each case.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import torch
from gymnasium import spaces

HERE = Path(__file__).resolve().parent


def f32(values, shape=None):
    a = np.asarray(values, dtype=np.float32)
    return a.reshape(shape) if shape is not None else a


def floats(t) -> list[float]:
    return [float(x) for x in np.asarray(t.detach().cpu() if torch.is_tensor(t) else t).ravel()]


class _Dummy:
    """A VecEnv stand-in: PPO only needs the spaces and the env count to build itself."""


def make_ppo(case):
    from snakesim.runs.policies import policy_kwargs
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv

    obs_dim, act_dim, rows = case["obs_dim"], case["act_dim"], case["rows"]
    obs_space = spaces.Box(-np.inf, np.inf, (obs_dim,), dtype=np.float32)
    act_space = spaces.Box(-1.0, 1.0, (act_dim,), dtype=np.float32)

    import gymnasium

    class Stub(gymnasium.Env):
        observation_space = obs_space
        action_space = act_space

        def reset(self, *, seed=None, options=None):
            return np.zeros(obs_dim, np.float32), {}

        def step(self, action):
            return np.zeros(obs_dim, np.float32), 0.0, False, False, {}

    s = case["settings"]
    model = PPO(
        "MlpPolicy",
        DummyVecEnv([Stub]),
        n_steps=rows,
        batch_size=rows,
        n_epochs=1,
        learning_rate=s["learning_rate"],
        clip_range=s["clip_range"],
        clip_range_vf=s["clip_range_vf"],
        normalize_advantage=s["normalize_advantage"],
        ent_coef=s["ent_coef"],
        vf_coef=s["vf_coef"],
        max_grad_norm=s["max_grad_norm"],
        policy_kwargs=policy_kwargs(case["arch"]),
        device="cpu",
        seed=0,
    )
    state = {}
    own = model.policy.state_dict()
    for name, values in case["tensors"].items():
        aliases = [name]
        if name.startswith("features_extractor."):
            rest = name[len("features_extractor.") :]
            aliases += [f"pi_features_extractor.{rest}", f"vf_features_extractor.{rest}"]
        for alias in aliases:
            state[alias] = torch.tensor(f32(values, own[alias].shape))
    missing = set(own) - set(state)
    if missing:
        raise SystemExit(f"the case lacks tensors {sorted(missing)}")
    model.policy.load_state_dict(state)
    return model


def run_ppo(case):
    from stable_baselines3.common.logger import Logger

    model = make_ppo(case)
    rows, obs_dim, act_dim = case["rows"], case["obs_dim"], case["act_dim"]
    obs = torch.tensor(f32(case["obs"], (rows, obs_dim)))
    actions = torch.tensor(f32(case["actions"], (rows, act_dim)))
    with torch.no_grad():
        values, log_prob, entropy = model.policy.evaluate_actions(obs, actions)
        mean = model.policy.get_distribution(obs).distribution.mean

    buffer = model.rollout_buffer
    buffer.reset()
    buffer.observations[:] = f32(case["obs"], (rows, 1, obs_dim))
    buffer.actions[:] = f32(case["actions"], (rows, 1, act_dim))
    buffer.log_probs[:] = f32(case["old_log_prob"], (rows, 1))
    buffer.advantages[:] = f32(case["advantages"], (rows, 1))
    buffer.returns[:] = f32(case["returns"], (rows, 1))
    buffer.values[:] = f32(case["old_values"], (rows, 1))
    buffer.pos = rows
    buffer.full = True

    logger = Logger(folder=None, output_formats=[])
    model.set_logger(logger)
    model.train()
    logged = dict(logger.name_to_value)

    named = dict(model.policy.named_parameters())
    grads = {name: named[name].grad.clone() for name in case["tensors"]}
    params_after = {name: named[name].detach().clone() for name in case["tensors"]}
    stats = {
        key: float(logged[f"train/{key}"])
        for key in (
            "policy_gradient_loss",
            "value_loss",
            "entropy_loss",
            "approx_kl",
            "clip_fraction",
            "loss",
        )
    }
    if case.get("anchor"):
        anchor = case["anchor"]
        fresh = make_ppo(case).policy
        targets = torch.tensor(f32(anchor["targets"], (rows, act_dim)))
        mse = torch.nn.functional.mse_loss(fresh.get_distribution(obs).distribution.mean, targets)
        (anchor["weight"] * mse).backward()
        fresh_named = dict(fresh.named_parameters())
        for name in grads:
            if fresh_named[name].grad is not None:
                grads[name] = grads[name] + fresh_named[name].grad
        stats["anchor_loss"] = float(mse)
        stats["loss"] += anchor["weight"] * float(mse)
        adam = torch.optim.Adam(fresh.parameters(), lr=case["settings"]["learning_rate"], eps=1e-5)
        adam.zero_grad()
        for name, p in fresh_named.items():
            p.grad = grads[name].clone() if name in grads else torch.zeros_like(p)
        adam.step()
        params_after = {name: fresh_named[name].detach().clone() for name in case["tensors"]}
    return {
        "mean": floats(mean),
        "log_prob": floats(log_prob),
        "entropy": floats(entropy),
        "values": floats(values.flatten()),
        "stats": stats,
        "grads": {name: floats(g) for name, g in grads.items()},
        "params_after": {name: floats(p) for name, p in params_after.items()},
    }


def run_adam(case):
    params = torch.tensor(f32(case["params"]), requires_grad=True)
    opt = torch.optim.Adam([params], lr=case["lr"], eps=1e-5)
    for grad in case["grads"]:
        opt.zero_grad()
        params.grad = torch.tensor(f32(grad))
        opt.step()
    state = opt.state[params]
    return {
        "params": floats(params),
        "exp_avg": floats(state["exp_avg"]),
        "exp_avg_sq": floats(state["exp_avg_sq"]),
    }


def run_gae(case):
    from stable_baselines3.common.buffers import RolloutBuffer

    n_steps, n_envs = case["n_steps"], case["n_envs"]
    buffer = RolloutBuffer(
        n_steps,
        spaces.Box(-1, 1, (1,), np.float32),
        spaces.Box(-1, 1, (1,), np.float32),
        device="cpu",
        gamma=case["gamma"],
        gae_lambda=case["gae_lambda"],
        n_envs=n_envs,
    )
    rewards = f32(case["rewards"], (n_steps, n_envs))
    starts = f32(case["episode_starts"], (n_steps, n_envs))
    values = f32(case["values"], (n_steps, n_envs))
    for t in range(n_steps):
        buffer.add(
            np.zeros((n_envs, 1), np.float32),
            np.zeros((n_envs, 1), np.float32),
            rewards[t],
            starts[t],
            torch.tensor(values[t]),
            torch.zeros(n_envs),
        )
    buffer.compute_returns_and_advantage(
        last_values=torch.tensor(f32(case["last_values"])), dones=np.array(case["dones"], dtype=bool)
    )
    return {"advantages": floats(buffer.advantages), "returns": floats(buffer.returns)}


def run_normalize(case):
    from stable_baselines3.common.vec_env import VecNormalize
    from stable_baselines3.common.vec_env.base_vec_env import VecEnv

    obs_dim, n_envs = case["obs_dim"], case["n_envs"]
    steps = case["steps"]

    class Replay(VecEnv):
        """Hands out the recorded batches in order."""

        def __init__(self):
            super().__init__(
                n_envs,
                spaces.Box(-np.inf, np.inf, (obs_dim,), np.float32),
                spaces.Box(-1, 1, (1,), np.float32),
            )
            self.k = 0

        def reset(self):
            return f32(case["reset_obs"], (n_envs, obs_dim))

        def step_async(self, actions):
            pass

        def step_wait(self):
            s = steps[self.k]
            self.k += 1
            dones = np.array(s["dones"], dtype=bool)
            return f32(s["obs"], (n_envs, obs_dim)), f32(s["rewards"]), dones, [{} for _ in range(n_envs)]

        def close(self):
            pass

        def get_attr(self, *a, **k):
            return [None] * n_envs

        def set_attr(self, *a, **k):
            pass

        def env_method(self, *a, **k):
            return [None] * n_envs

        def env_is_wrapped(self, *a, **k):
            return [False] * n_envs

    venv = VecNormalize(Replay(), gamma=case["gamma"])
    out = {"reset_obs": floats(venv.reset()), "obs": [], "rewards": []}
    for _ in steps:
        obs, rewards, _, _ = venv.step(np.zeros((n_envs, 1), np.float32))
        out["obs"].append(floats(obs))
        out["rewards"].append(floats(rewards))
    out["obs_mean"] = floats(venv.obs_rms.mean)
    out["obs_var"] = floats(venv.obs_rms.var)
    out["ret_var"] = floats(np.atleast_1d(venv.ret_rms.var))
    return out


def main() -> None:
    spec_path, out_dir = Path(sys.argv[1]), Path(sys.argv[2])
    sys.path.insert(0, str(HERE))
    torch.set_num_threads(1)
    runners = {"ppo": run_ppo, "adam": run_adam, "gae": run_gae, "normalize": run_normalize}
    for case in json.loads(spec_path.read_text()):
        result = runners[case["kind"]](case)
        (out_dir / f"{case['name']}.json").write_text(json.dumps(result))


if __name__ == "__main__":
    main()
