"""The type stub _core.pyi names exactly what the compiled module has."""

import ast
import inspect
import pathlib

from snakesim import _core

STUB = pathlib.Path(inspect.getfile(_core)).with_name("_core.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    names = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = {
                # Private names and dunders (__init__, __enter__, ...) are skipped, as module_names does.
                n.name
                for n in node.body
                if isinstance(n, ast.FunctionDef) and not n.name.startswith("_")
            }
        elif isinstance(node, ast.AnnAssign):
            names[node.target.id] = None
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = None
    return names


def module_names():
    names = {}
    for name, value in vars(_core).items():
        if name.startswith("__") and name != "__version__":
            continue
        if inspect.isclass(value):
            names[name] = {m for m in vars(value) if not m.startswith("_")}
        else:
            names[name] = None
    return names


def test_stub_matches_the_module():
    assert stub_names() == module_names()
