"""Every shell command and Python snippet of README.md, docs/*.md and models/*.md runs as written.

Each page's ```sh and ```python blocks run in order in a fresh folder laid out as the repository root
after `bash scripts/setup` (the inputs linked, `out/` empty, no `runs/`), with `.venv/bin` and
`target/release` on PATH as the README says. Long commands are shortened (one evaluation episode, a
1,024-step training; the rules and the markers a page may set: snake-py/tests/_doc_blocks.py);
SNAKESIM_DOC_TESTS=full runs them as written. A block that cannot run here says why in its source
(`<!-- not run: REASON -->`), and each page's test asserts that every other block ran. The pages of
docs._doc_blocks.SECOND_HALF run in snake-py/tests/test_doc_examples_more.py, on the other core."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _doc_blocks as docs  # noqa: E402

#: At most this many blocks are not run (17 of 63 on 2026-11-29: installs, setup, Ray, minutes-long
#: fits and builds); each says why.
MOST_NOT_RUN = 20


@pytest.mark.parametrize("page", docs.pages_with_examples(second_half=False))
def test_every_example_of_the_page_runs(page, tmp_path):
    docs.check_page(page, tmp_path)


def test_few_blocks_are_not_run_and_each_says_why():
    skipped = [b for page in docs.PAGES for b in docs.blocks(page) if b.not_run]
    assert all(len(b.not_run) > 10 for b in skipped), [b.name for b in skipped]
    assert len(skipped) <= MOST_NOT_RUN, "\n".join(f"{b.name}: {b.not_run}" for b in skipped)


def test_the_pages_are_split_in_two():
    first, second = docs.pages_with_examples(False), docs.pages_with_examples(True)
    assert "README.md" in first and "docs/deploy.md" in second and not set(first) & set(second)
    assert sorted(first + second) == sorted(p for p in docs.PAGES if docs.blocks(p))


def test_the_collector_finds_the_examples_and_their_markers():
    readme = docs.blocks("README.md")
    assert [b.language for b in readme][:3] == ["sh", "sh", "sh"]
    assert any(b.language == "python" and "gymnasium.make" in b.text for b in readme)
    assert sum(len(docs.blocks(page)) for page in docs.PAGES) > 50


#: A command and what the test runs instead.
SHORTENED = [
    (
        "snakesim evaluate m.safetensors --episodes 100 --seed 9  # x",
        "snakesim evaluate m.safetensors --episodes 1 --seed 9  # x",
    ),
    (".venv/bin/snakesim evaluate baseline:steer", ".venv/bin/snakesim evaluate baseline:steer --episodes 1"),
    ("snakesim replay m --episodes 3 --out a.png", "snakesim replay m --episodes 1 --out a.png --seconds 2"),
    ("snake-cli bench --joints 5,10", "snake-cli bench --joints 5,10 --repeats 1 --steps 240"),
    ("snakesim train --run-dir runs/x --resume", "snakesim train --run-dir runs/x --resume"),
    ("snakesim plot runs/s{1,2} --out a.png", "snakesim plot runs/s{1,2} --out a.png"),
    ("snakesim view a.rrd --serve  # open it", "serve_check snakesim view a.rrd --serve  # open it"),
    ("snakesim replay m --spawn", "echo 'not run (needs a display): snakesim replay m --spawn'"),
    ("ls runs", "ls runs"),
]


@pytest.mark.skipif(docs.FULL, reason="SNAKESIM_DOC_TESTS=full: nothing is shortened")
@pytest.mark.parametrize(("command", "shortened"), SHORTENED)
def test_the_shortening_rules(command, shortened):
    assert docs.shorten(command) == shortened


@pytest.mark.skipif(docs.FULL, reason="SNAKESIM_DOC_TESTS=full: nothing is shortened")
def test_a_training_is_shortened_to_one_small_rollout():
    train = docs.shorten("snake-cli train --config c.yaml --timesteps 5242880 --set eval_freq=65536 --seed S")
    assert train.startswith("snake-cli train --config c.yaml --seed S --set timesteps=1024 --set n_envs=4")
    assert "5242880" not in train and "65536" not in train and "--set eval_freq=1024" in train
