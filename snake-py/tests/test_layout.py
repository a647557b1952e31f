"""The package's layout: modules grouped by concern, imports pointing one way (no circle, counting
imports inside functions), no test hooks or private Ray APIs in shipped code, and the public names users
write keep working."""

import ast
from pathlib import Path

import snakesim

PACKAGE = Path(snakesim.__file__).parent
CONCERNS = ("envs", "runs", "agents", "sweeps", "viewer", "cli")
#: The package's top-level modules: the public face and leaves every concern may use.
TOP_LEVEL = {"__init__", "__main__", "extras", "files", "limits", "media", "wrappers"}


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in PACKAGE.rglob("*.py")}


def known_names() -> set[str]:
    """The package's Python modules and its compiled one (a leaf: it imports no Python module)."""
    return set(modules()) | {"snakesim._core"}


def imports(path: Path, known: set[str]) -> set[str]:
    """Every snakesim module ``path`` imports, at any depth (functions included): ``from a.b import c``
    is module a.b.c when that is a module, else a.b."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == "snakesim")
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "snakesim":
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                found.add(sub if sub in known else node.module)
    return {name for name in found if name in known}


def test_no_import_circle():
    graph = {name: imports(path, known_names()) - {name} for name, path in modules().items()}
    graph["snakesim._core"] = set()
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(name: str) -> None:
        state[name] = 1
        stack.append(name)
        for other in sorted(graph[name]):
            if state.get(other) == 1:
                circle = stack[stack.index(other) :] + [other]
                raise AssertionError("import circle: " + " -> ".join(circle))
            if other not in state:
                visit(other)
        stack.pop()
        state[name] = 2

    for name in sorted(graph):
        if name not in state:
            visit(name)


def test_modules_are_grouped_by_concern():
    top = {p.stem for p in PACKAGE.glob("*.py")}
    assert top == TOP_LEVEL, f"top-level modules beyond the public face and the leaves: {top - TOP_LEVEL}"
    for concern in CONCERNS:
        assert (PACKAGE / concern / "__init__.py").is_file()
    # The leaves import no concern.
    for leaf in ("snakesim.extras", "snakesim.files", "snakesim.limits"):
        assert imports(modules()[leaf], known_names()) <= {"snakesim._core"}, leaf


def test_no_test_hooks_or_private_ray_in_shipped_code():
    for path in PACKAGE.rglob("*.py"):
        text = path.read_text()
        assert "SNAKESIM_TEST" not in text, path
        assert "ray._private" not in text, path


def test_public_names_still_import():
    import gymnasium
    from snakesim.envs.wrappers import RerunLogger

    assert snakesim.SnakeEnv.__module__ == "snakesim.envs.env"
    assert RerunLogger.__module__ == "snakesim.envs.wrappers"
    for env_id in ("snakesim/Snake-v0", "snakesim/SnakeGoal-v0"):
        gymnasium.make(env_id).close()
    from snakesim import SnakeGoalEnv, SnakeVectorEnv, __version__  # noqa: F401
    from snakesim.agents import load_agent  # noqa: F401


REPO = Path(__file__).resolve().parents[2]
CRATES = ("bullet-sys", "snake-core", "snake-rl", "snake-cli", "snake-py")


def crate_modules(src: Path) -> dict[str, str]:
    """A crate's top-level modules (``src/world.rs``, ``src/env.rs`` with ``src/env/*.rs``) and their
    source without comments."""
    found: dict[str, str] = {}
    for path in sorted(src.rglob("*.rs")):
        parts = path.relative_to(src).with_suffix("").parts
        if parts[0] in ("lib", "main") or parts[-1] == "mod" and len(parts) == 1:
            continue
        text = "\n".join(line.split("//")[0] for line in path.read_text(encoding="utf-8").splitlines())
        found[parts[0]] = found.get(parts[0], "") + text
    return found


def test_no_import_circle_in_the_crates():
    """Within each crate, modules point one way: a module that another names through ``crate::``
    names none of those that lead back to it (counting every use, not only ``use`` lines)."""
    import re

    for crate in CRATES:
        mods = crate_modules(REPO / crate / "src")
        graph = {
            name: {m for m in re.findall(r"crate::(\w+)", text) if m in mods and m != name}
            | {
                m
                for group in re.findall(r"use crate::\{([^}]*)\}", text)
                for m in re.findall(r"\w+", group)
                if m in mods and m != name
            }
            for name, text in mods.items()
        }
        for start in graph:
            seen, stack = set(), [(start, [start])]
            while stack:
                node, path = stack.pop()
                for nxt in graph[node]:
                    assert nxt != start, f"{crate}: import circle {' -> '.join([*path, nxt])}"
                    if nxt not in seen:
                        seen.add(nxt)
                        stack.append((nxt, [*path, nxt]))


# -- docs/architecture.md is the map: its import layers hold, and it names every file ---------------

ARCHITECTURE = REPO / "docs" / "architecture.md"


def import_layers(text: str) -> list[list[str]]:
    """The module patterns of each row of the map's "Import layers" table, top row first."""
    import re

    section = text.split("### Import layers", 1)[1].split("\n#", 1)[0]
    rows = [line for line in section.splitlines() if line.startswith("| ") and "`snakesim" in line]
    return [re.findall(r"`(snakesim[\w.*]*)`", row.split("|")[2]) for row in rows]


def layer_of(module: str, layers: list[list[str]]) -> int | None:
    """The first layer whose patterns name ``module`` (``snakesim.cli.*`` names the subpackage)."""
    for index, patterns in enumerate(layers):
        for pattern in patterns:
            package = pattern[:-2]
            if module == pattern or (
                pattern.endswith(".*") and (module == package or module.startswith(f"{package}."))
            ):
                return index
    return None


def upward_imports(graph: dict[str, set[str]], layers: list[list[str]]) -> list[str]:
    """Every import of ``graph`` (module -> the modules it imports) that points to a higher layer."""
    return sorted(
        f"{a} -> {b}"
        for a, targets in graph.items()
        for b in targets
        if layer_of(b, layers) < layer_of(a, layers)  # type: ignore[operator]
    )


def package_graph() -> dict[str, set[str]]:
    graph = {name: imports(path, known_names()) - {name} for name, path in modules().items()}
    graph["snakesim._core"] = set()
    return graph


def test_imports_point_down_the_maps_layers():
    layers = import_layers(ARCHITECTURE.read_text(encoding="utf-8"))
    graph = package_graph()
    unplaced = sorted(m for m in graph if layer_of(m, layers) is None)
    assert not unplaced, f"modules in no row of docs/architecture.md's import layers: {unplaced}"
    assert not upward_imports(graph, layers), upward_imports(graph, layers)


def test_a_planted_upward_import_is_caught():
    layers = import_layers(ARCHITECTURE.read_text(encoding="utf-8"))
    graph = package_graph()
    # An env that imports the command, a leaf that imports an agent: both point up.
    graph["snakesim.envs.env"] = graph["snakesim.envs.env"] | {"snakesim.cli.app"}
    graph["snakesim.files"] = graph["snakesim.files"] | {"snakesim.agents"}
    assert upward_imports(graph, layers) == [
        "snakesim.envs.env -> snakesim.cli.app",
        "snakesim.files -> snakesim.agents",
    ]
    # And from a module's text, as the real check reads it.
    planted = REPO / "snake-py" / "python" / "snakesim" / "envs" / "env.py"
    text = planted.read_text() + "\n\ndef _planted():\n    from snakesim.sweeps import plan  # noqa: F401\n"
    import tempfile

    with tempfile.NamedTemporaryFile("w", suffix=".py") as f:
        f.write(text)
        f.flush()
        graph["snakesim.envs.env"] = imports(Path(f.name), known_names())
    assert "snakesim.envs.env -> snakesim.sweeps.plan" in upward_imports(graph, layers)


#: The files the map must name: every source, test, example, fuzz target and script of the project.
MAPPED = (
    "bullet-sys/shim/*",
    "*/src/**/*.rs",
    "*/tests/**/*.rs",
    "tests/*.rs",
    "*/examples/*.rs",
    "fuzz/fuzz_targets/*.rs",
    "snake-py/python/snakesim/**/*.py",
    "snake-py/tests/*.py",
    "tests/reference/*.py",
    "scripts/*",
)


def test_the_map_names_every_source_and_test_file():
    text = ARCHITECTURE.read_text(encoding="utf-8")
    files = {
        p.relative_to(REPO).as_posix()
        for pattern in MAPPED
        for p in REPO.glob(pattern)
        if p.is_file() and "target" not in p.relative_to(REPO).parts
    }
    # A subpackage's __init__ is the subpackage itself, which its concern's row names.
    files = {
        f for f in files if not f.endswith("/__init__.py") or f == "snake-py/python/snakesim/__init__.py"
    }
    missing = sorted(f for f in files if f"`{f}`" not in text)
    assert not missing, f"docs/architecture.md names none of: {missing}"
