"""The type stubs (cairn/_cairn.pyi) declare exactly the public names of the extension module, and
every public function and class of it has a docstring."""

import ast
import pathlib

import cairn
from cairn import _cairn


def stub_names():
    stub = pathlib.Path(_cairn.__file__).with_name("_cairn.pyi")
    tree = ast.parse(stub.read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return names


def module_names():
    return {name for name in dir(_cairn) if not name.startswith("_")} | {"__version__"}


def test_stubs_declare_every_public_name():
    declared = stub_names()
    assert module_names() - declared == set(), "missing from _cairn.pyi"
    # Type aliases and private TypedDicts (a result's dict layout) exist only in the stubs.
    stub_only = {"F64", "F32", "I64", "ArrayLike"}
    extra = {n for n in declared - module_names() if n not in stub_only and not n.startswith("_")}
    assert extra == set(), "declared in _cairn.pyi but not in the module"


def test_everything_public_has_a_docstring():
    undocumented = []
    for name in module_names() - {"__version__"}:
        member = getattr(_cairn, name)
        if not (getattr(member, "__doc__", None) or "").strip():
            undocumented.append(name)
    assert undocumented == []
    assert cairn.__version__ == _cairn.__version__
