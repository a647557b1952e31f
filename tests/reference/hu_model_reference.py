"""Hu, Nirody, Scott and Shelley's quasi-static slithering model (PNAS 106:10081, 2009), independent of
Bullet: given a snake's shape over time, the body's velocity is the one for which the net friction
force and torque on the body vanish.

Usage: hu_model_reference.py SPEC.json OUT_DIR. SPEC holds, per case, the coefficients (forward,
backward, transverse) and the sampled shape: time step between samples, and for every sample and
element its position (x, y), skin axis (tx, ty, the direction the head points) and normal force (the
simulator's, for the weighted variant). Writes OUT_DIR/hu_model.json: per case, for the model as Hu et
al. wrote it (equal weight on every element, "equal") and for the same balance with each element's
force scaled by its normal force ("weighted"), the mean velocity (vx, vy) and rotation rate over the
samples, the largest force and torque residual left, and how many samples Newton's method left above
1e-8 (the law is not smooth where an element's sliding direction crosses its skin axis).

The shape velocity of element i is its velocity less the body's rigid motion: the body's velocity V is
the elements' mean velocity and its rotation rate w makes the shape velocity carry no angular momentum
about the centre (Hu et al.'s centre-of-mass and mean-orientation frame). The model replaces (V, w) with
the (U, W) that balance friction: element i slides at u_i = U + W x r_i + (shape velocity)_i and feels
-N (mu_t (u.n) n + mu_a (u.t) t), u unit, mu_a = forward if u.t > 0 else backward.
"""

import json
import sys

import numpy as np

# Below this sliding speed (m/s) the unit direction is smoothed, u / sqrt(|u|^2 + EPS^2): the law's
# direction is undefined at rest, and Newton's method needs a derivative there. It is three orders of
# magnitude below the elements' speeds in the tests.
EPS = 1e-5


def forces(u, t, mu_f, mu_b, mu_t):
    """Friction per element (N = 1) for sliding velocities u (k x 2) and skin axes t (k x 2)."""
    norm = np.sqrt((u * u).sum(axis=1) + EPS * EPS)
    uh = u / norm[:, None]
    n = np.stack([-t[:, 1], t[:, 0]], axis=1)
    ut = (uh * t).sum(axis=1)
    un = (uh * n).sum(axis=1)
    mu_a = np.where(ut > 0, mu_f, mu_b)
    return -(mu_t * un)[:, None] * n - (mu_a * ut)[:, None] * t


def residual(x, r, w_shape, t, mu, weight):
    """Net force (2) and torque (1) per unit weight on the body moving at U = x[:2], W = x[2]."""
    rot = np.stack([-r[:, 1], r[:, 0]], axis=1) * x[2]
    f = forces(x[:2] + rot + w_shape, t, *mu) * weight[:, None]
    torque = (r[:, 0] * f[:, 1] - r[:, 1] * f[:, 0]).sum()
    return np.array([f[:, 0].sum(), f[:, 1].sum(), torque]) / weight.sum()


def solve(r, w_shape, t, mu, weight, x0):
    """Newton's method with a finite-difference Jacobian and a halving line search on |residual|."""
    x = x0.copy()
    g = residual(x, r, w_shape, t, mu, weight)
    for _ in range(100):
        if np.abs(g).max() < 1e-11:
            break
        jac = np.empty((3, 3))
        for j in range(3):
            h = 1e-7 * max(1.0, abs(x[j]))
            e = np.zeros(3)
            e[j] = h
            jac[:, j] = (residual(x + e, r, w_shape, t, mu, weight) - g) / h
        try:
            step = -np.linalg.solve(jac, g)
        except np.linalg.LinAlgError:
            step = -np.linalg.lstsq(jac, g, rcond=None)[0]
        lam = 1.0
        while lam > 1e-6:
            trial = x + lam * step
            gt = residual(trial, r, w_shape, t, mu, weight)
            if np.abs(gt).max() < np.abs(g).max():
                break
            lam *= 0.5
        x, g = trial, gt
    return x, g


def run_case(case, use_weights):
    mu = (case["forward"], case["backward"], case["transverse"])
    pos = np.array(case["positions"])  # samples x elements x 2
    axis = np.array(case["axes"])
    dt = case["sample_dt"]
    weights = np.array(case["weights"]) if use_weights else None
    vel = (pos[2:] - pos[:-2]) / (2 * dt)  # central differences at samples 1 .. n-2
    x = np.zeros(3)
    us, ws, worst, unconverged = [], [], 0.0, 0
    for k in range(vel.shape[0]):
        p, v = pos[k + 1], vel[k]
        t = axis[k + 1] / np.linalg.norm(axis[k + 1], axis=1)[:, None]
        r = p - p.mean(axis=0)
        big_v = v.mean(axis=0)
        rel = v - big_v
        w = (r[:, 0] * rel[:, 1] - r[:, 1] * rel[:, 0]).sum() / (r * r).sum()
        w_shape = rel - np.stack([-r[:, 1], r[:, 0]], axis=1) * w
        weight = np.ones(len(p)) if weights is None else weights[k + 1]
        best = None
        # Started from the previous sample's answer; where the line search stalls (a heavy element
        # sliding at almost zero speed makes the residual nearly kinked), from rest and from the mean
        # shape velocity's opposite too, keeping the smallest residual.
        for start in (x, np.zeros(3), np.array([-big_v[0], -big_v[1], 0.0])):
            xs, gs = solve(r, w_shape, t, mu, weight, start)
            if best is None or np.abs(gs).max() < np.abs(best[1]).max():
                best = (xs, gs)
            if np.abs(gs).max() < 1e-11:
                break
        x, g = best
        worst = max(worst, float(np.abs(g).max()))
        unconverged += int(np.abs(g).max() > 1e-8)
        us.append(x[:2].copy())
        ws.append(x[2])
    us = np.array(us)
    return {
        "model_velocity": us.mean(axis=0).tolist(),
        "model_rotation": float(np.mean(ws)),
        "worst_residual": worst,
        "unconverged": unconverged,
        "samples": len(us),
    }


def main():
    spec = json.load(open(sys.argv[1]))
    out = [{"equal": run_case(c, False), "weighted": run_case(c, True)} for c in spec["cases"]]
    json.dump(out, open(f"{sys.argv[2]}/hu_model.json", "w"))


if __name__ == "__main__":
    main()
