"""The Rust tests of `bash scripts/test` on every core: what `cargo test --release --workspace` runs, with its
test binaries run side by side instead of one after another (most of them run one long test on one core).

    python3 scripts/rust_tests.py [--jobs N] [CARGO TEST ARGS...]

Builds the test binaries once (`cargo test --release --workspace --no-run`, the release profile that
`cargo build --release` and scripts/setup built the crates in), then runs them and the doc tests
(`cargo test --release --workspace --doc`) N at a time (default: the number of CPUs), each as cargo would:
in its package's folder, with its output kept and shown whole if it fails. Prints one line per binary
with its time, and exits 1 if any failed.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

# The longest first (seconds on the 2-core machine, loaded: learning 109, env_memory 63, parity 62,
# hu_model 44, ppo_reference 37, world_parity 35, urdf_parity 18; the rest 10 or less), so that none
# starts last and leaves a core idle at the end. The others follow in cargo's order.
LONGEST_FIRST = [
    "learning",
    "env_memory",
    "parity",
    "hu_model",
    "ppo_reference",
    "world_parity",
    "urdf_parity",
]


def build(cargo_args: list[str]) -> list[dict]:
    """Builds the test binaries; returns one job per binary: name, program, package folder."""
    cmd = [
        "cargo",
        "test",
        "--release",
        "--workspace",
        "--no-run",
        "--message-format=json-render-diagnostics",
    ]
    proc = subprocess.run(cmd + cargo_args, stdout=subprocess.PIPE, text=True)
    if proc.returncode != 0:
        sys.exit(f"error: {' '.join(cmd)} failed (exit {proc.returncode})")
    jobs = []
    for line in proc.stdout.splitlines():
        msg = json.loads(line) if line.startswith("{") else {}
        if msg.get("reason") != "compiler-artifact" or not msg.get("profile", {}).get("test"):
            continue
        if not msg.get("executable"):
            continue
        target = msg["target"]
        kind = "unittests" if target["kind"] != ["test"] else Path(target["src_path"]).name
        package = Path(msg["manifest_path"]).parent
        jobs.append(
            {
                "name": f"{package.name} {kind}",
                "key": target["name"],
                "argv": [msg["executable"]],
                "cwd": package,
            }
        )
    return jobs


def run(job: dict) -> tuple[dict, int, str, float]:
    start = time.monotonic()
    proc = subprocess.run(
        job["argv"], cwd=job["cwd"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    return job, proc.returncode, proc.stdout, time.monotonic() - start


def summary(output: str) -> str:
    results = [line for line in output.splitlines() if line.startswith("test result:")]
    return "; ".join(r.removeprefix("test result: ").split("; finished")[0] for r in results)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    args, cargo_args = parser.parse_known_args()
    root = Path(__file__).resolve().parents[1]
    os.chdir(root)
    start = time.monotonic()
    jobs = build(cargo_args)
    built = time.monotonic() - start
    print(f"built {len(jobs)} test binaries in {built:.0f} s; running them {args.jobs} at a time", flush=True)
    rank = {key: i for i, key in enumerate(LONGEST_FIRST)}
    jobs.sort(key=lambda job: rank.get(job["key"], len(rank)))  # stable: the rest in cargo's order
    doc = ["cargo", "test", "--release", "--workspace", "--doc", "--quiet", *cargo_args]
    # The doc tests compile each example (both cores) before running it: after the longest binaries.
    jobs.insert(
        min(len(LONGEST_FIRST), len(jobs)), {"name": "doc tests", "key": "doc", "argv": doc, "cwd": root}
    )
    failed = []
    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        for done in as_completed([pool.submit(run, job) for job in jobs]):
            job, code, output, seconds = done.result()
            status = "ok" if code == 0 else f"FAILED (exit {code})"
            print(f"{seconds:6.1f} s  {status:4}  {job['name']}: {summary(output)}", flush=True)
            if code != 0:
                failed.append((job, output))
    for job, output in failed:
        print(f"\n---- {job['name']} ({' '.join(map(str, job['argv']))}, in {job['cwd']}) ----\n{output}")
    passed, seconds = len(jobs) - len(failed), time.monotonic() - start
    print(f"Rust tests: {passed} of {len(jobs)} binaries passed, {seconds:.0f} s")
    if failed:
        print("error: failed: " + ", ".join(job["name"] for job, _ in failed), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
