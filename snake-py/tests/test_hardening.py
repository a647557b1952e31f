"""Misuse that must end in a result or a clear error: never a hang, a crash or a traceback."""

from __future__ import annotations

import subprocess
import sys
import textwrap

# Each scenario runs in its own interpreter with a time limit: a deadlock fails the test, not CI.
_THREADS = textwrap.dedent(
    """
    import threading, numpy as np
    from snakesim import SnakeEnv, SnakeVecEnv

    def hammer(targets):
        errors = []
        def wrap(f):
            def run():
                try:
                    f()
                except Exception as e:  # a clear error is acceptable, a hang is not
                    errors.append(repr(e))
            return run
        ts = [threading.Thread(target=wrap(f)) for f in targets]
        [t.start() for t in ts]
        [t.join() for t in ts]
        return errors

    e = SnakeEnv(); e.reset(seed=0)
    def steps():
        for _ in range(1500):
            e.step(np.zeros(5, np.float32))
    def poses():
        for _ in range(1500):
            e.cube_poses(); e.goal
    def resets():
        for s in range(30):
            e.reset(seed=s)
    assert not hammer([steps, steps]), "step + step"
    assert not hammer([steps, poses]), "step + cube_poses"
    assert not hammer([resets, resets, steps]), "reset + reset + step"

    v = SnakeVecEnv(3); v.seed(0); v.reset()
    def vsteps():
        for _ in range(500):
            v.step_async(np.zeros((3, 5), np.float32)); v.step_wait()
    def vresets():
        for s in range(20):
            v.reset()
    hammer([vsteps, vsteps, vresets])
    print("done")
    """
)


def test_concurrent_use_from_threads_is_serialised_not_a_deadlock():
    proc = subprocess.run([sys.executable, "-c", _THREADS], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "done"
