"""The shell commands and Python snippets of the docs, as snake-py/tests/test_doc_examples.py runs them.

A page's fenced ```sh and ```python blocks are its examples (other fences are output, file formats,
synopses or other languages). An HTML comment on the lines right above a block's fence says how the
test treats it; the page's reader never sees it:

    <!-- not run: REASON -->            the block is skipped; the reason is required
    <!-- test: OLD => NEW -->           a literal substitution in the block before it runs (placeholders
                                        such as a seed S; several are separated by ` ;; `)
    <!-- test before: COMMAND -->       a shell command run (shortened like the block) before the block:
                                        what the page assumes was done elsewhere, e.g. a run to export
    <!-- test prelude: FILE ARGS -->    (Python) the file's code runs first in the same interpreter, with
                                        ARGS as sys.argv[1:], e.g. a simulated robot for a control loop
                                        written for hardware

    <!-- test name: NAME -->            (Python) names the block for `test with`
    <!-- test with: NAME -->            (Python) the named block's code runs first, in the same
                                        interpreter (after any prelude): a class defined once on the
                                        page and used by two loops

Every page's inline commands (a code span outside a fence that starts with a tool: `snakesim`,
`snake-cli`, `python`, `cargo`, `bash`, `scripts/...`, with `.venv/bin/` or `./target/release/` or not;
"Trained with", "Evaluated with", a command in a sentence) run too, each as a one-line sh block at its
place on the page; a `<!-- not run: REASON -->` or `<!-- test: OLD => NEW -->` right after the closing
backtick applies to that command (`inline_commands`). A span that only names a command is left alone,
by these rules (`is_mention`), so that prose may name commands and flags freely:
  - it has a placeholder: a word in capitals (`MODEL`, `--robot R`, `T.csv`, `goal-N.yaml`), `...`,
    `[optional]`, `a|b`, or `<...>`: a synopsis;
  - it has no argument beyond the tool, its subcommand (`python -m MODULE` or `python SCRIPT`) and bare
    flags: `snakesim evaluate`, `snake-cli run --rrd`, `snakesim train --resume`, `python -m snakesim`,
    `scripts/setup --no-demo`: the name of a command or flag.
Spans in a heading (the section's subject) or a `*Dated:*` note (the section's own commands, repeated)
are not commands either.

Long commands are shortened by the rules of `shorten` (fewer episodes, a tiny training with short
episodes and a short imitation, a 2 s simulation), and an evaluation that the page already ran as the
same shortened command is echoed (`once_per_page`); with SNAKESIM_DOC_TESTS=full in the environment they
run as written. What the suite itself runs (`cargo test ...`, `python -m pytest ...`, `scripts/test`,
`scripts/fuzz`) is echoed: scripts/test runs it; so is `cargo build` (scripts/setup's), and
`cargo doc --open` (a browser). `cargo` runs on the repository's own manifest (`--manifest-path`):
from the test's folder, whose crates are links, it would build everything again.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

#: The pages whose examples run: the README, docs/ and the model cards.
PAGES = [
    "README.md",
    *(f"docs/{p.name}" for p in sorted((REPO / "docs").glob("*.md"))),
    *(f"models/{p.name}" for p in sorted((REPO / "models").glob("*.md"))),
]

RUN_LANGUAGES = {"sh": "sh", "bash": "sh", "python": "python"}
FENCE = re.compile(r"^(\s*)```(\S*)\s*$")
MARKER = re.compile(
    r"^\s*<!--\s*(not run|test before|test prelude|test name|test with|test)\s*:\s*(.*?)\s*-->\s*$"
)
#: An inline command: a code span that starts with a tool (it may wrap across lines), and the markers
#: right after it.
INLINE = re.compile(
    r"`((?:(?:\.venv/bin/|\./target/release/|venv/bin/)?(?:snakesim|snake-cli|python3?)|cargo|bash"
    r"|scripts/[\w.-]+)(?:\s[^`]*)?)`((?:\s*<!--.*?-->)*)",
    re.S,
)
#: A synopsis's placeholder: a word in capitals, `...`, `[optional]`, `a|b`, `<...>`.
PLACEHOLDER = re.compile(r"\.\.\.|\[|\||<|(?<!\w)[A-Z][A-Z0-9_]*\b")
INLINE_MARKER = re.compile(r"<!--\s*(not run|test)\s*:\s*(.*?)\s*-->", re.S)

#: Run as written, no shortening (slow: full evaluations and trainings).
FULL = os.environ.get("SNAKESIM_DOC_TESTS") == "full"

#: The shortened training: one rollout of 2 envs x 256 steps, one update epoch, one evaluation episode,
#: episodes of at most 200 steps (the paper's env runs 5,000 unless the goal is reached: an untrained
#: policy's evaluation episode took most of a tiny training's time; goal-20.yaml's 1,024-step training
#: with 500-step episodes took 10 s, this one 2.8 s).
TINY_TRAINING = {
    "timesteps": "512",
    "n_envs": "2",
    "ppo.n_steps": "256",
    "ppo.batch_size": "256",
    "ppo.n_epochs": "1",
    "eval_freq": "512",
    "eval_episodes": "1",
    "checkpoint_freq": "512",
    "env.max_episode_steps": "200",
}
#: Added where the config imitates a controller before PPO (`init:`; 65,536 steps in paper-init-20.yaml,
#: 27 s of a tiny training's 38 s).
TINY_INIT = {"init.steps": "1024"}


@dataclass
class Block:
    page: str
    line: int  # the fence's line, 1-based
    language: str  # "sh" or "python"
    text: str
    not_run: str | None = None
    substitutions: list[tuple[str, str]] = field(default_factory=list)
    before: list[str] = field(default_factory=list)
    prelude: str | None = None
    label: str | None = None  # `test name`
    uses: list[str] = field(default_factory=list)  # `test with`
    inline: bool = False  # a card's inline command, not a fenced block

    @property
    def name(self) -> str:
        return f"{self.page}:{self.line}"

    def prepared(self) -> str:
        """The block's text with its substitutions, shortened unless SNAKESIM_DOC_TESTS=full."""
        text = self.text
        for old, new in self.substitutions:
            if old not in text:
                raise ValueError(f"{self.name}: the test's substitution {old!r} is not in the block")
            text = text.replace(old, new)
        return text if self.language == "python" else shorten_script(text)


def blocks(page: str) -> list[Block]:
    """Every ```sh and ```python block of a page (path from the repository root), with its markers, and
    its inline commands, in the order of the page."""
    return sorted(fenced_blocks(page) + inline_commands(page), key=lambda b: b.line)


def is_mention(span: str) -> bool:
    """Whether an inline span that starts with a tool only names a command (see the module's docstring):
    a placeholder, or no argument beyond the tool, its subcommand and bare flags."""
    if PLACEHOLDER.search(span):
        return True
    words = span.split()
    if words[0] == "bash":
        words = words[1:]
    tool, rest = Path(words[0]).name, words[1:]
    if tool in ("snakesim", "snake-cli", "cargo"):
        rest = rest[1:]
    elif tool.startswith("python"):
        rest = rest[2:] if rest[:1] == ["-m"] else rest[1:]
    return all(word.startswith("-") for word in rest)


def parse_substitutions(where: str, value: str) -> list[tuple[str, str]]:
    pairs = []
    for pair in value.split(" ;; "):
        old, sep, new = pair.partition(" => ")
        if not sep:
            raise ValueError(f"{where}: expected <!-- test: OLD => NEW -->")
        pairs.append((old, new))
    return pairs


def outside_fences(text: str) -> str:
    """The page with every fenced block's lines blanked (line numbers kept)."""
    lines, inside = text.split("\n"), False
    for i, line in enumerate(lines):
        if inside or FENCE.match(line):
            inside = not (inside and line.strip() == "```")
            lines[i] = ""
    return "\n".join(lines)


def inline_commands(page: str) -> list[Block]:
    """The page's inline commands outside fences, each a one-line sh block (a command wrapped over
    lines joined by spaces), with the markers that follow its closing backtick."""
    text = outside_fences((REPO / page).read_text())
    found = []
    for match in INLINE.finditer(text):
        line = text.count("\n", 0, match.start()) + 1
        command = " ".join(match.group(1).split())
        # A heading names its section's subject; a *Dated:* note repeats the commands its section gives.
        if is_mention(command) or text[text.rfind("\n", 0, match.start()) + 1 :].startswith(("#", "*Dated:")):
            continue
        block = Block(page, line, "sh", command + "\n", inline=True)
        for kind, value in INLINE_MARKER.findall(match.group(2)):
            value = " ".join(value.split())
            if not value:
                raise ValueError(f"{page}:{line}: an empty <!-- {kind}: --> marker")
            if kind == "not run":
                block.not_run = value
            else:
                block.substitutions += parse_substitutions(f"{page}:{line}", value)
        found.append(block)
    return found


def fenced_blocks(page: str) -> list[Block]:
    lines = (REPO / page).read_text().split("\n")
    found = []
    i = 0
    while i < len(lines):
        fence = FENCE.match(lines[i])
        if not fence:
            i += 1
            continue
        indent, language = fence.groups()
        start = i
        i += 1
        body = []
        while i < len(lines) and lines[i].strip() != "```":
            body.append(lines[i][len(indent) :] if lines[i].startswith(indent) else lines[i])
            i += 1
        i += 1
        if language not in RUN_LANGUAGES:
            continue
        block = Block(page, start + 1, RUN_LANGUAGES[language], "\n".join(body) + "\n")
        j = start - 1
        while j >= 0 and (marker := MARKER.match(lines[j])):
            kind, value = marker.groups()
            if not value:
                raise ValueError(f"{page}:{j + 1}: an empty <!-- {kind}: --> marker")
            if kind == "not run":
                block.not_run = value
            elif kind == "test":
                block.substitutions += parse_substitutions(f"{page}:{j + 1}", value)
            elif kind == "test before":
                block.before.insert(0, value)
            elif kind == "test name":
                block.label = value
            elif kind == "test with":
                block.uses.insert(0, value)
            else:
                block.prelude = value
            j -= 1
        found.append(block)
    return found


# --- shortening ---------------------------------------------------------------------------------

#: What the test suite itself runs: echoed.
SUITE = re.compile(r"^(?:cargo test\b|(?:\S*/)?python3? -m pytest\b|(?:bash )?scripts/(?:test|fuzz)\b)")
#: How a command names the tool, stripped before the rules look at it.
TOOL = re.compile(r"^(?:\.venv/bin/|venv/bin/|\./target/release/)?(snakesim|snake-cli)\s+(\S+)")


def shorten_script(text: str) -> str:
    """A shell block, command by command (a backslash-continued line is one command)."""
    out = []
    pending = ""
    for line in text.split("\n"):
        if line.rstrip().endswith("\\"):
            pending += line.rstrip()[:-1] + " "
            continue
        out.append(shorten(pending + line))
        pending = ""
    return "\n".join(out)


def shorten(command: str) -> str:
    """The rules, each for one kind of long command, as text edits (brace expansions, globs and
    variables stay the shell's). `--serve` runs until Ctrl-C: the runner's `serve_check` runs it on free
    ports (`--web-port`, `--grpc-port`) and stops it once it has printed its address. `--spawn` and
    `rerun FILE` open a native viewer, which needs a display: the command is echoed, not run."""
    body, comment = split_comment(command)
    words = body.split()
    if "--spawn" in words or "--open" in words or (words and Path(words[0]).name == "rerun"):
        return f"echo {shlex.quote('not run (needs a display): ' + body.strip())}"
    if SUITE.match(body.strip()):
        return f"echo {shlex.quote('run by scripts/test: ' + body.strip())}"
    if body.strip().startswith("cargo build"):
        return f"echo {shlex.quote('run by scripts/setup: ' + body.strip())}"
    if words[:1] == ["cargo"] and len(words) > 1:
        manifest = f'cargo {words[1]} --manifest-path "$DOCS_REPO/Cargo.toml"'
        return body.replace(f"cargo {words[1]}", manifest, 1) + comment
    if "--serve" in words:
        return f"serve_check {body.strip()}{comment}"
    tool = TOOL.match(body.strip())
    if FULL or tool is None:
        return command
    kind = tool.group(2)
    if kind == "bench":
        body = with_flag(with_flag(body, "--repeats", "1"), "--steps", "240")
    elif kind == "evaluate":
        body = with_flag(body, "--episodes", "1")
    elif kind == "replay":
        body = with_flag(with_flag(body, "--episodes", "1", append=False), "--seconds", "2")
    elif kind == "run":
        body = with_flag(body, "--seconds", "2")
    elif kind in ("train", "sweep", "search") and "--resume" not in words:
        if kind == "sweep":
            body = first_grid_values(with_flag(body, "--seeds", "1", append=False))
        if kind == "search":
            body = with_flag(body, "--trials", "2", append=False)
        body = tiny_training(body)
    return body + comment


def split_comment(command: str) -> tuple[str, str]:
    """A command and its trailing `# comment` (the docs quote no `#`)."""
    match = re.search(r"\s+#.*$", command)
    return (command[: match.start()], command[match.start() :]) if match else (command.rstrip(), "")


def with_flag(body: str, flag: str, value: str, append: bool = True) -> str:
    """Sets `flag` to `value` where the command gives it; else appends it (`append`) or leaves it."""
    pattern = re.compile(rf"(\s){re.escape(flag)}(?:\s+|=)\S+")
    if pattern.search(body):
        return pattern.sub(rf"\g<1>{flag} {value}", body)
    return f"{body} {flag} {value}" if append else body


GRID = re.compile(r"(\s--grid(?:\s+|=))([\w.]+=)([^\s,\[\]'\"]+)(?:,[^\s\[\]'\"]+)+(?=\s|$)")


def first_grid_values(body: str) -> str:
    """A sweep's `--grid KEY=V1,V2,...` cut to V1 (one trial less per value: Ray starts each)."""
    return GRID.sub(r"\g<1>\g<2>\g<3>", body)


#: The flags and --set keys of a training's size, which tiny_training replaces.
SIZE_FLAGS = re.compile(r"\s--(?:timesteps|n-envs|eval-freq|eval-episodes|checkpoint-freq)(?:\s+|=)\S+")
SIZE_SETS = re.compile(
    r"\s--set(?:\s+|=)(?:" + "|".join(re.escape(k) for k in {**TINY_TRAINING, **TINY_INIT}) + r")=\S+"
)
CONFIG = re.compile(r"\s--config(?:\s+|=)(\S+)")


def tiny_training(body: str) -> str:
    """Drops the command's own sizes and sets TINY_TRAINING's (and TINY_INIT's where its config
    imitates)."""
    body = SIZE_SETS.sub("", SIZE_FLAGS.sub("", body))
    sizes = dict(TINY_TRAINING)
    config = CONFIG.search(body)
    if config and (REPO / config.group(1)).is_file():
        if re.search(r"^init:", (REPO / config.group(1)).read_text(), re.M):
            sizes.update(TINY_INIT)
    return body + "".join(f" --set {key}={value}" for key, value in sizes.items())


# --- running ------------------------------------------------------------------------------------

#: What a block may read, linked into its folder; what it writes (out/, runs/, sweeps/, docs/figures/)
#: stays in the folder.
LINKED = [
    ".venv",
    "target",
    "models",
    "robots",
    "worlds",
    "experiments",
    "scripts",
    "tests",
    "snake-py",
    "snake-core",
    "snake-rl",
    "snake-cli",
    "bullet-sys",
    "fuzz",
    "Cargo.toml",
    "Cargo.lock",
    "requirements.lock",
    "requirements-test.lock",
    "README.md",
]
#: A block's time limit, seconds (a shortened block takes a few).
TIMEOUT = None if FULL else 240

#: `--serve` runs until Ctrl-C: started, stopped once it has printed its address, which must come.
SERVE_CHECK = r"""
serve_check() {
    # A log of its own: an earlier serve's address must not stop this one before it has started.
    local log web grpc
    log=$(mktemp serve-XXXXXX.log)
    # Free ports, not the defaults (9090, 9876): another test may be serving there at the same time.
    read -r web grpc < <(python -c 'import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("127.0.0.1", 0))
print(*(x.getsockname()[1] for x in s))')
    # Its own process group: the viewer's server goes with it.
    setsid "$@" --web-port "$web" --grpc-port "$grpc" > "$log" 2>&1 &
    local pid=$!
    for _ in $(seq 600); do
        # A background command of a script ignores SIGINT: TERM stands for Ctrl-C.
        if grep -q 'http://127.0.0.1' "$log"; then kill -TERM -- -$pid; wait $pid || true; return 0; fi
        kill -0 $pid 2>/dev/null || break
        sleep 0.1
    done
    kill -TERM -- -$pid 2>/dev/null; cat "$log"; echo "serve_check: no address from: $*"; return 1
}
"""


def sandbox(tmp_path: Path) -> Path:
    root = tmp_path / "repo"
    root.mkdir()
    for name in LINKED:
        if (REPO / name).exists():
            (root / name).symlink_to(REPO / name)
    (root / "out").mkdir()  # scripts/setup's demo makes it
    (root / "docs" / "figures").mkdir(parents=True)
    return root


def environment(root: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{root / '.venv' / 'bin'}:{root / 'target' / 'release'}:{env.get('PATH', '')}"
    env.pop("VIRTUAL_ENV", None)
    env["DOCS_REPO"] = str(REPO)  # cargo's manifest (shorten)
    env["MPLBACKEND"] = "Agg"
    env["PYTHONUNBUFFERED"] = "1"  # serve_check reads the address as it is printed
    return env


def run(block: Block, root: Path, text: str) -> None:
    if block.language == "python":
        code, arguments = text, []
        if block.prelude:
            prelude, *arguments = block.prelude.split()
            code = (REPO / prelude).read_text() + "\n" + text
        script = root / f"block-{block.line}.py"
        script.write_text(code)
        command = [str(root / ".venv" / "bin" / "python"), script.name, *arguments]
    else:
        script = root / f"block-{block.line}.sh"
        script.write_text("set -eo pipefail\n" + SERVE_CHECK + text)
        command = ["bash", script.name]
    try:
        done = subprocess.run(
            command, cwd=root, env=environment(root), capture_output=True, text=True, timeout=TIMEOUT
        )
    except subprocess.TimeoutExpired as e:
        pytest.fail(f"{block.name} ran over {TIMEOUT} s:\n{text}\n{e.stdout}\n{e.stderr}")
    if done.returncode != 0:
        pytest.fail(
            f"{block.name} failed (exit {done.returncode}):\n--- as run:\n{text}\n--- stdout:\n"
            f"{done.stdout[-3000:]}\n--- stderr:\n{done.stderr[-3000:]}"
        )


#: The pages of snake-py/tests/test_doc_examples_more.py (the rest: test_doc_examples.py), two files so
#: that xdist (one file per worker) runs them on both cores. Measured 2026-11-29 (CPU seconds of their
#: commands): README 14, guide 26, tasks 23, formats 9, the rest of docs/ 7, models/[e-g]* 13 in the
#: first; deploy 20, experiments 18, sweeps 9 (and Ray's start-up, about 20 s of wall time that
#: is not CPU), models/[p-z]* 20 in the second.
SECOND_HALF = (
    "docs/experiments.md",
    "docs/sweeps.md",
    "docs/deploy.md",
    *(f"models/{c}" for c in "pqrstuvwxyz"),
)


def pages_with_examples(second_half: bool) -> list[str]:
    return [p for p in PAGES if blocks(p) and p.startswith(SECOND_HALF) == second_half]


def once_per_page(text: str, seen: set[str]) -> str:
    """A shortened `evaluate` that printed only (no --json) and already ran on the page as the same
    command (the README's tour and its full-size runs, shortened alike) is echoed, not run again: the
    same episodes, the same output."""
    if FULL:
        return text
    out = []
    for line in text.split("\n"):
        body = " ".join(split_comment(line)[0].split())
        tool = TOOL.match(body)
        if tool and tool.group(2) == "evaluate" and "--json" not in body:
            key = body[tool.start(1) :]  # .venv/bin/snakesim and snakesim alike
            if key in seen:
                line = f"echo {shlex.quote('ran above on this page: ' + body)}"
            seen.add(key)
        out.append(line)
    return "\n".join(out)


def check_page(page: str, tmp_path: Path) -> None:
    """Runs the page's blocks in order in one folder; fails on the first that fails, naming it."""
    root = sandbox(tmp_path)
    found = blocks(page)
    named = {b.label: b for b in found if b.label}
    evaluated: set[str] = set()
    ran = []
    for block in found:
        if block.not_run:
            continue
        for command in block.before:
            run(Block(page, block.line, "sh", command + "\n"), root, shorten_script(command))
        unknown = [name for name in block.uses if name not in named]
        if unknown:
            raise ValueError(f"{block.name}: <!-- test with: {unknown[0]} -->: no block of that name")
        start = time.monotonic()
        text = block.prepared() if block.language == "python" else once_per_page(block.prepared(), evaluated)
        run(block, root, "".join(named[name].prepared() + "\n" for name in block.uses) + text)
        print(f"{block.name}: {time.monotonic() - start:.1f} s")  # pytest -rP shows each block's time
        ran.append(block.line)
    assert ran == [b.line for b in found if not b.not_run]
