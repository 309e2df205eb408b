"""The type stubs name what the extension module has: every class, function and method
the module registers is in _volux.pyi, and nothing the stubs name is missing."""

import ast
import inspect
import pathlib

import volux
from volux import _volux

STUB = pathlib.Path(volux.__file__).with_name("_volux.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    names = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = None
        elif isinstance(node, ast.AnnAssign):
            names[node.target.id] = None
    return names


def test_the_stubs_match_the_module():
    stubs = stub_names()
    public = {n for n in dir(_volux) if not n.startswith("_") or n == "__version__"}
    assert public - set(stubs) == set(), "registered but not in the stubs"
    assert {n for n in stubs if not n.startswith("_") or n == "__version__"} - public == set(), "in the stubs but not registered"
    for cls, methods in stubs.items():
        if methods is None:
            continue
        obj = getattr(_volux, cls)
        have = {n for n, _ in inspect.getmembers(obj) if not n.startswith("__")}
        named = {m for m in methods if not m.startswith("__")}
        assert named <= have, (cls, named - have)
