"""multicue.pyi lists exactly the public names of the module, and every one has a docstring."""

import ast
import pathlib

import multicue


def stub_names():
    path = pathlib.Path(multicue.__file__).with_name("multicue.pyi")
    tree = ast.parse(path.read_text())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
    return {n for n in names if not n.startswith("_")}, tree


def test_stub_matches_the_module():
    names, _ = stub_names()
    public = {n for n in dir(multicue) if not n.startswith("_")}
    assert names == public


def test_stub_lists_the_point_cloud_members():
    _, tree = stub_names()
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "PointCloud")
    members = set()
    for node in cls.body:
        if isinstance(node, ast.FunctionDef):
            members.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            members.add(node.target.id)
    public = {n for n in dir(multicue.PointCloud) if not n.startswith("_")}
    assert members - {"__init__", "__len__"} == public


def test_every_function_and_class_has_a_docstring():
    for name in dir(multicue):
        obj = getattr(multicue, name)
        if callable(obj) and not name.startswith("_"):
            assert obj.__doc__, name
    assert multicue.__doc__
    assert multicue.__version__.count(".") == 2
