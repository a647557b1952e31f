"""Every shell command and Python snippet of README.md, docs/*.md and models/*.md runs as written.

Each page's ```sh and ```python blocks run in order in a fresh folder laid out as the repository root
after `bash scripts/setup` (the inputs linked, `out/` empty, no `runs/`), with `.venv/bin` and
`target/release` on PATH as the README says; so do the pages' inline commands (a model card's "Trained
with: `snake-cli train ...`", a command in a sentence), each at its place, unless the span only names a
command (a placeholder such as `MODEL`, or no argument: `snakesim evaluate`). Long commands are
shortened (one evaluation episode, a 512-step training of 200-step episodes, a 2 s simulation; the
rules and the markers a page may set: snake-py/tests/_doc_blocks.py); SNAKESIM_DOC_TESTS=full runs
them as written. A block or command that cannot run here says why in its source (`<!-- not run:
REASON -->`), and each page's test asserts that every other one ran. The pages of
docs._doc_blocks.SECOND_HALF run in snake-py/tests/test_doc_examples_more.py, on the other core."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _doc_blocks as docs  # noqa: E402

#: At most this many blocks and inline commands are not run (35 of 154 on 2026-11-29; each says why):
#: 19 blocks and card commands (installs, setup, Ray, minutes-long fits and builds, the paper's zip), and
#: 16 inline commands of docs/ and the cards: 6 benchmarks, imitations and builds of 24 s to 8 minutes
#: (experiments.md's two bench_train runs, update_bench, candle_update_bench, imitate_controllers;
#: guide.md's randomize_bench), 3 of Ray's start-ups of 20 s (experiments.md's sweep and its resume,
#: sweeps.md's resume), 2 card_numbers.py runs (12 minutes, and they rewrite models/measured/), 4 that
#: need what no test makes (a 7M-step checkpoint, the 15 runs of a plot, the seed-S run of a synopsis,
#: calibration.md's 5-minute fit's robot) and media.md's abbreviated fit.
MOST_NOT_RUN = 35


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


def test_the_cards_inline_commands_are_collected_with_their_markers():
    cards = [page for page in docs.PAGES if page.startswith("models/")]
    inline = {page: [b for b in docs.blocks(page) if b.inline] for page in cards}
    for page in cards:  # every card found (new ones too) runs the commands it says it was made with
        text, commands = (docs.REPO / page).read_text(), [b.text for b in docs.blocks(page)]
        if "**Evaluated with**" in text:
            assert any(" evaluate " in c for c in commands), page
        if "**Trained with**" in text:
            assert any(" train " in b.text for b in inline[page]), page
    detour = [b for b in inline["models/pegs-10.md"] if "detour_pegs.py" in b.text]
    assert [b.prepared() for b in detour] == [
        ".venv/bin/python experiments/pegs-detour/detour_pegs.py 1 900000 10\n"
    ]
    zips = [b for b in inline["models/paper-10.md"] if "ppo_10_20000000_steps.zip" in b.text]
    assert len(zips) == 1 and "not shipped" in zips[0].not_run
    # A fenced block's commands are the block's, not inline ones.
    fenced = docs.fenced_blocks("models/robust-yaw-pitch-16.md")
    assert fenced and not any(
        b.line == f.line for b in inline["models/robust-yaw-pitch-16.md"] for f in fenced
    )
    assert all(b.text.count("\n") == 1 for bs in inline.values() for b in bs)


def test_the_docs_inline_commands_run_and_spans_that_name_commands_do_not():
    guide = [b.text for b in docs.inline_commands("docs/guide.md")]
    assert "snake-cli run --world worlds/rough.yaml\n" in guide
    media = [b.text for b in docs.inline_commands("docs/media.md")]
    assert not any(text.startswith("snakesim validate 'water.*'") for text in media)  # a heading's
    for span in [
        "snakesim evaluate MODEL --randomize FILE.yaml",  # placeholders
        "snake-cli run --robot R --targets T.csv",
        "snake-cli train --config snake-py/configs/goal-N.yaml",
        "snakesim replay ...",
        "snake-cli run --targets ... --output log.csv",
        "snakesim view FILE.rrd --serve|--spawn",
        "snake-cli run --robot FILE --gait NAME [--world FILE]",
        "snakesim evaluate",  # names: no argument
        "snake-cli run --rrd",
        "snakesim train --resume",
        "python -m snakesim",
        "scripts/setup --no-demo",
        ".venv/bin/python scripts/bench_env.py",
    ]:
        assert docs.is_mention(span), span
    for span in [
        "snakesim evaluate baseline:gait",
        "snake-cli run --world worlds/rough.yaml",
        "cargo run --release -p snake-core --example gait",
        ".venv/bin/python -m pytest snake-py/tests/test_calibrate.py -p no:xdist",
        "bash scripts/fuzz --seconds 3600 urdf",
        "snakesim validate 'friction.slope-*'",
    ]:
        assert not docs.is_mention(span), span


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
    (
        "snake-cli run --joints 10 --seconds 10 --plot a.png",
        "snake-cli run --joints 10 --seconds 2 --plot a.png",
    ),
    ("snake-cli run --world w.yaml  # x", "snake-cli run --world w.yaml --seconds 2  # x"),
    (
        "cargo run --release -p snake-core --example gait",
        'cargo run --manifest-path "$DOCS_REPO/Cargo.toml" --release -p snake-core --example gait',
    ),
    ("cargo test -p snakesim-tests", "echo 'run by scripts/test: cargo test -p snakesim-tests'"),
    ("bash scripts/fuzz --seconds 3 urdf", "echo 'run by scripts/test: bash scripts/fuzz --seconds 3 urdf'"),
    ("cargo build --release -j 2", "echo 'run by scripts/setup: cargo build --release -j 2'"),
    ("cargo doc -p snake-core --open", "echo 'not run (needs a display): cargo doc -p snake-core --open'"),
]


@pytest.mark.skipif(docs.FULL, reason="SNAKESIM_DOC_TESTS=full: nothing is shortened")
@pytest.mark.parametrize(("command", "shortened"), SHORTENED)
def test_the_shortening_rules(command, shortened):
    assert docs.shorten(command) == shortened


@pytest.mark.skipif(docs.FULL, reason="SNAKESIM_DOC_TESTS=full: nothing is shortened")
def test_a_training_is_shortened_to_one_small_rollout():
    train = docs.shorten("snake-cli train --config c.yaml --timesteps 5242880 --set eval_freq=65536 --seed S")
    assert train.startswith("snake-cli train --config c.yaml --seed S --set timesteps=512 --set n_envs=2")
    assert "5242880" not in train and "65536" not in train and "--set eval_freq=512" in train
    assert train.endswith("--set env.max_episode_steps=200") and "init.steps" not in train


def test_an_imitating_training_imitates_briefly():
    train = docs.shorten("snake-cli train --config snake-py/configs/paper-init-20.yaml --set init.steps=9")
    assert train.endswith("--set env.max_episode_steps=200 --set init.steps=1024") and "=9" not in train


def test_a_sweep_keeps_each_grids_first_value():
    assert docs.first_grid_values("snakesim sweep c.yaml --grid a.b=1e-4,3e-4 --grid c=x,y,z --out s") == (
        "snakesim sweep c.yaml --grid a.b=1e-4 --grid c=x --out s"
    )
    lists = "snakesim sweep c.yaml --grid 'env.goal=[0, -10],[5, 5]'"
    assert docs.first_grid_values(lists) == lists  # the shell's quoting: left as written


#: Pages whose measured numbers are dated section by section (those of the cards, docs/tasks.md and the
#: README are generated: test_card_numbers.py): the commands, the day and the commits that last changed
#: them (git blame on 2026-11-29, not re-measured).
DATED_PAGES = [
    "docs/experiments.md",
    "docs/friction.md",
    "docs/gaits.md",
    "docs/media.md",
    "docs/parity.md",
    "docs/packaging.md",
]
DATED = re.compile(
    r"\*Dated: measured with .+; .+ last changed \d{4}-\d\d-\d\d(?: to \d{4}-\d\d-\d\d)? "
    r"\(commits? [0-9a-f]{7}(?:, [0-9a-f]{7})*, by `git blame`\) and were not measured again since\.\*"
)
MEASURED_ROW = re.compile(r"^\|.*\d\.\d")


def sections(page: str) -> list[tuple[int, str, list[str]]]:
    """The page's headings (level, text) and their lines outside fences, up to the next heading."""
    found = [(0, page, [])]
    for line in docs.outside_fences((docs.REPO / page).read_text()).split("\n"):
        heading = re.match(r"^(#{1,6}) (.*)", line)
        if heading:
            found.append((len(heading.group(1)), heading.group(2), []))
        else:
            found[-1][2].append(line)
    return found


@pytest.mark.parametrize("page", DATED_PAGES)
def test_a_sections_measured_numbers_are_dated(page):
    dated_levels: list[int] = []  # the levels of the dated headings above, innermost last
    undated = []
    for level, title, lines in sections(page):
        dated_levels = [lv for lv in dated_levels if lv < level]
        notes = [line for line in lines if line.startswith("*Dated:")]
        assert all(DATED.fullmatch(n) for n in notes), (page, title, notes)
        if notes:
            dated_levels.append(level)
        if any(MEASURED_ROW.match(line) for line in lines) and not dated_levels:
            undated.append(title)
    assert not undated, f"{page}: sections with measured tables and no *Dated:* line: {undated}"


@pytest.mark.skipif(docs.FULL, reason="SNAKESIM_DOC_TESTS=full: nothing is shortened")
def test_an_evaluation_the_page_already_ran_is_not_repeated():
    seen: set[str] = set()
    first = docs.once_per_page(".venv/bin/snakesim evaluate m --episodes 1  # 1 min", seen)
    again = docs.once_per_page(
        "snakesim evaluate m --episodes 1\nsnakesim evaluate m --episodes 1 --json a.json", seen
    )
    assert first == ".venv/bin/snakesim evaluate m --episodes 1  # 1 min"
    assert again.split("\n") == [
        "echo 'ran above on this page: snakesim evaluate m --episodes 1'",
        "snakesim evaluate m --episodes 1 --json a.json",  # it writes a file: run again
    ]
