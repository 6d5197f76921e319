"""Every public function and class of the module has a docstring, and the type stubs
(lazyboe/_lazyboe.pyi) declare exactly what the module has."""

import ast
import pathlib

import lazyboe
from lazyboe import _lazyboe


def public(names):
    return {n for n in names if not n.startswith("_")}


def stub_tree():
    path = pathlib.Path(_lazyboe.__file__).with_name("_lazyboe.pyi")
    return ast.parse(path.read_text())


def stub_members(node):
    names = set()
    for item in node.body:
        if isinstance(item, (ast.FunctionDef, ast.ClassDef)):
            if not item.name.startswith("_"):
                names.add(item.name)
        elif isinstance(item, ast.AnnAssign):
            names.add(item.target.id)
    return names


def test_docstrings_everywhere():
    for name in lazyboe.__all__:
        obj = getattr(lazyboe, name)
        assert obj.__doc__ and obj.__doc__.strip(), name
        if isinstance(obj, type):
            for member in public(vars(obj)):
                assert getattr(obj, member).__doc__, f"{name}.{member}"


def test_stubs_match_the_module():
    tree = stub_tree()
    classes = {c.name: c for c in tree.body if isinstance(c, ast.ClassDef)}
    top = stub_members(tree) - {"Path", "ArrayLike", "Progress"}
    assert top == public(dir(_lazyboe)) | {"__version__"}
    for name, node in classes.items():
        real = public(vars(getattr(_lazyboe, name)))
        assert stub_members(node) == real, name
