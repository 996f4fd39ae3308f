"""The checked-in stubs (_bkpbs.pyi) describe the native module: same public names, same
parameters (names, kinds, defaults present) for every function, class and method."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import bkpbs
from bkpbs import _bkpbs

STUB = Path(bkpbs.__file__).with_name("_bkpbs.pyi")


def stub_tree():
    return ast.parse(STUB.read_text())


def public(names):
    return {n for n in names if not n.startswith("_") or n == "__version__"}


def stub_params(fn: ast.FunctionDef, method: bool):
    a = fn.args
    out = []
    pos = a.posonlyargs + a.args
    defaults = [None] * (len(pos) - len(a.defaults)) + list(a.defaults)
    for arg, d in zip(pos, defaults):
        out.append((arg.arg, "POSITIONAL_OR_KEYWORD", d is not None))
    if a.vararg:
        out.append((a.vararg.arg, "VAR_POSITIONAL", False))
    for arg, d in zip(a.kwonlyargs, a.kw_defaults):
        out.append((arg.arg, "KEYWORD_ONLY", d is not None))
    if a.kwarg:
        out.append((a.kwarg.arg, "VAR_KEYWORD", False))
    if method and out and out[0][0] == "self":
        out = out[1:]
    return out


def native_params(obj):
    sig = inspect.signature(obj)
    return [
        (p.name, p.kind.name, p.default is not inspect.Parameter.empty)
        for p in sig.parameters.values()
        if p.name != "self"
    ]


def test_module_names_match():
    stub = set()
    for node in stub_tree().body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            stub.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            stub.add(node.target.id)
        elif isinstance(node, ast.Assign):
            stub.update(t.id for t in node.targets)
    assert public(stub) == public(dir(_bkpbs)) - {"annotations"}


def test_function_signatures_match():
    for node in stub_tree().body:
        if isinstance(node, ast.FunctionDef):
            assert native_params(getattr(_bkpbs, node.name)) == stub_params(node, False), node.name


def test_class_members_and_signatures_match():
    for node in stub_tree().body:
        if not isinstance(node, ast.ClassDef):
            continue
        cls = getattr(_bkpbs, node.name)
        members = {n.name: n for n in node.body if isinstance(n, ast.FunctionDef)}
        native = {
            n for n, v in vars(cls).items()
            if not n.startswith("_") and (callable(v) or inspect.isdatadescriptor(v) or isinstance(v, staticmethod))
        }
        assert public(members) == native, node.name
        if "__init__" in members:
            assert native_params(cls) == stub_params(members["__init__"], True), node.name
        for name, fn in members.items():
            if name.startswith("_"):
                continue
            is_property = any(isinstance(d, ast.Name) and d.id == "property" for d in fn.decorator_list)
            if is_property:
                assert inspect.isdatadescriptor(vars(cls)[name]), f"{node.name}.{name}"
            else:
                assert native_params(getattr(cls, name)) == stub_params(fn, True), f"{node.name}.{name}"


def test_exceptions_match():
    for name, base in [("BkpbsError", ValueError), ("SumoError", RuntimeError)]:
        assert issubclass(getattr(_bkpbs, name), base)
