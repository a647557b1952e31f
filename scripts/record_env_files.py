"""Records in native models the robot and world files they name, as the files are now (issue 47).

    .venv/bin/python scripts/record_env_files.py models/*.safetensors [--check]

A model trained before models recorded their files (metadata ``env_files``, docs/formats.md) names its
robot and world by path only, so editing ``robots/yaw-pitch-16.yaml`` would change the robot it acts on.
Run from the directory the model was trained in (the repository's root for the shipped models, whose
``robot`` keyword is ``robots/yaw-pitch-16.yaml``), before the files are edited, this adds ``env_files``
with the files' texts as they are now. Only the metadata changes: the safetensors header is rewritten
with the one key added and every tensor's bytes are copied as they are (the header's other keys keep
their values). A model without a robot or world file is left alone. ``--check`` writes nothing and
fails when a model lacks the record or its record differs from the files.
"""

from __future__ import annotations

import argparse
import json
import struct
import sys
from pathlib import Path

from snakesim.envs.config import env_config, env_file_records
from snakesim.files import write_atomically


def read(path: Path) -> tuple[dict, bytes]:
    """The header (JSON) and the tensors' bytes of a safetensors file."""
    raw = path.read_bytes()
    (size,) = struct.unpack("<Q", raw[:8])
    return json.loads(raw[8 : 8 + size]), raw[8 + size :]


def records_now(meta: dict) -> dict | None:
    """The env_files of a model's env keywords, from the files as they are now."""
    keywords = {"joints": int(meta["joints"]), "preset": meta["preset"], **json.loads(meta["env"])}
    if not any(keywords.get(key) for key in ("robot", "world")):
        return None
    text = env_config(**keywords)  # checks the keywords
    return env_file_records(json.loads(text))


def _writer(content: bytes):
    """Writes ``content`` to the file it is given."""
    return lambda target: Path(target).write_bytes(content)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("models", nargs="+", type=Path)
    parser.add_argument(
        "--check", action="store_true", help="write nothing; fail on a missing or stale record"
    )
    args = parser.parse_args()
    failed = False
    for path in args.models:
        header, data = read(path)
        meta = header["__metadata__"]
        records = records_now(meta)
        if records is None:
            print(f"{path}: no robot or world file; left alone")
            continue
        text = json.dumps(records, separators=(",", ":"), sort_keys=True)
        if meta.get("env_files") is not None and json.loads(meta["env_files"]) == records:
            print(f"{path}: records {', '.join(records)} as they are now")
            continue
        if args.check:
            print(f"{path}: its env_files are missing or differ from the files now", file=sys.stderr)
            failed = True
            continue
        meta["env_files"] = text
        encoded = json.dumps(header, separators=(",", ":")).encode()
        encoded += b" " * (-len(encoded) % 8)  # the data starts 8-byte aligned, as safetensors writes it
        write_atomically(path, _writer(struct.pack("<Q", len(encoded)) + encoded + data))
        recorded = ", ".join(f"{key} {record['path']}" for key, record in records.items())
        print(f"{path}: recorded {recorded}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
