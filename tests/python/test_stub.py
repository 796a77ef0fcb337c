"""The type stub errfield.pyi sits beside the module and names exactly what the module exports."""
import ast
import os

import errfield


def stub_tree():
    path = os.path.join(os.path.dirname(errfield.__file__), "errfield.pyi")
    assert os.path.exists(path), "errfield.pyi must be installed beside the module"
    with open(path) as f:
        return ast.parse(f.read())


def test_stub_lists_the_module_and_class_members():
    tree = stub_tree()
    stub = {n.name: n for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    module = {n for n in dir(errfield) if not n.startswith("_")}
    assert set(stub) == module
    for name, node in stub.items():
        if not isinstance(node, ast.ClassDef) or issubclass(getattr(errfield, name), BaseException):
            continue
        declared = {n.name for n in node.body if isinstance(n, ast.FunctionDef)}
        declared |= {n.target.id for n in node.body if isinstance(n, ast.AnnAssign)}
        public = {n for n in dir(getattr(errfield, name)) if not n.startswith("_")}
        assert public == declared - {"__init__", "__call__", "__len__"}, name
