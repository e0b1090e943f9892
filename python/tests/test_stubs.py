"""The type stubs against the library: the names, parameters, defaults and option vocabularies
that radiosity/_native.pyi declares are the ones radiosity._native has."""

import ast
import inspect
import pathlib
import subprocess
import sys

import pytest

import radiosity
from radiosity import _native

PACKAGE = pathlib.Path(radiosity.__file__).resolve().parent
STUB = PACKAGE / "_native.pyi"


def stub():
    return ast.parse(STUB.read_text(), filename=str(STUB))


def public(name):
    return not name.startswith("_")


def declared(body):
    """The names a stub's module or class body declares, by name: its definitions."""
    found = {}
    for node in body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            found[node.name] = node
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            found[node.target.id] = node
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    found[target.id] = node
    return found


def runtime_names(obj):
    return {name for name in dir(obj) if not (name.startswith("__") and name.endswith("__"))}


def test_the_package_ships_its_stubs_and_py_typed():
    assert (PACKAGE / "py.typed").is_file()
    assert STUB.is_file()


def test_every_name_of_the_native_module_is_in_the_stub_and_back():
    names = {n for n in declared(stub().body) if public(n)}
    assert names == runtime_names(_native)


def test_every_member_of_the_native_classes_is_in_the_stub_and_back():
    classes = {n: c for n, c in declared(stub().body).items() if isinstance(c, ast.ClassDef)}
    for name, node in classes.items():
        if not public(name) or name == "RadiosityError":
            continue
        members = set(declared(node.body))
        runtime = runtime_names(getattr(_native, name))
        assert {m for m in members if not m.startswith("__")} == runtime, name
        # The dunders the stub declares exist.
        for member in members:
            assert hasattr(getattr(_native, name), member), f"{name}.{member}"


def stub_functions():
    """(qualified name, runtime object, stub node) of each function and method of the stub."""
    for name, node in declared(stub().body).items():
        if not public(name):
            continue
        if isinstance(node, ast.FunctionDef):
            yield name, getattr(_native, name), node
        elif isinstance(node, ast.ClassDef):
            cls = getattr(_native, name)
            for member, fn in declared(node.body).items():
                if isinstance(fn, ast.FunctionDef) and not any(
                    isinstance(d, ast.Name) and d.id == "property" for d in fn.decorator_list
                ):
                    yield f"{name}.{member}", getattr(cls, member), fn


def stub_parameters(fn):
    """[(name, has a default, the default's value or None)] of a stub's function."""
    args = fn.args
    positional = args.posonlyargs + args.args
    defaults = [None] * (len(positional) - len(args.defaults)) + list(args.defaults)
    out = [(a.arg, d is not None, d) for a, d in zip(positional, defaults)]
    out += [(a.arg, d is not None, d) for a, d in zip(args.kwonlyargs, args.kw_defaults)]
    return out


def test_parameters_and_defaults_match_the_stub():
    checked = 0
    for name, obj, fn in stub_functions():
        try:
            signature = inspect.signature(obj)
        except (ValueError, TypeError):
            continue  # no text signature (a slot such as __len__)
        checked += 1
        expected = stub_parameters(fn)
        runtime = list(signature.parameters.values())
        assert [p.name for p in runtime] == [e[0] for e in expected], name
        for parameter, (_, has_default, default) in zip(runtime, expected):
            where = f"{name}({parameter.name})"
            assert (parameter.default is not inspect.Parameter.empty) == has_default, where
            # PyO3 writes a default it cannot spell (a tuple) as `...`.
            if has_default and parameter.default is not Ellipsis:
                assert ast.literal_eval(default) == parameter.default, where
    assert checked >= 10


def literal_values(node, aliases):
    """The strings of a `Literal[...]` annotation, through aliases and `Optional[...]`."""
    if isinstance(node, ast.Name):
        return aliases.get(node.id)
    if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name):
        if node.value.id == "Optional":
            return literal_values(node.slice, aliases)
        if node.value.id == "Literal":
            elements = node.slice.elts if isinstance(node.slice, ast.Tuple) else [node.slice]
            return [ast.literal_eval(e) for e in elements]
    return None


def stub_vocabularies():
    """{option: {(where, values)}}: each parameter or field of the stub typed by a Literal."""
    tree = stub()
    aliases = {}
    for node in tree.body:
        if isinstance(node, ast.Assign) and len(node.targets) == 1:
            values = literal_values(node.value, aliases)
            if values is not None:
                aliases[node.targets[0].id] = values
    found = {}

    def note(option, where, annotation):
        values = literal_values(annotation, aliases)
        if values is not None:
            found.setdefault(option, []).append((where, values))

    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            for field in node.body:
                if isinstance(field, ast.AnnAssign) and isinstance(field.target, ast.Name):
                    note(field.target.id, f"{node.name}.{field.target.id}", field.annotation)
        if isinstance(node, ast.FunctionDef):
            for arg in node.args.args + node.args.kwonlyargs:
                if arg.annotation is not None:
                    note(arg.arg, f"{node.name}({arg.arg})", arg.annotation)
    return found


def test_the_stub_s_vocabularies_are_the_library_s():
    library = _native.option_values()
    found = stub_vocabularies()
    assert set(found) == set(library)
    for option, places in found.items():
        for where, values in places:
            assert values == library[option], where
    # The run options of both TypedDicts are the package's options.
    fields = {}
    for node in stub().body:
        if isinstance(node, ast.ClassDef) and node.name in ("_RunOptions", "_RunKwargs"):
            fields[node.name] = [
                (f.target.id, ast.dump(f.annotation)) for f in node.body if isinstance(f, ast.AnnAssign)
            ]
    assert fields["_RunOptions"] == fields["_RunKwargs"]
    assert [name for name, _ in fields["_RunOptions"]] == list(radiosity._DEFAULTS)


@pytest.mark.parametrize("option", sorted(_native.option_values()))
def test_an_unknown_value_is_refused_with_the_valid_ones(option):
    valid = _native.option_values()[option]
    bogus = "not-a-" + option.replace("_", "-")
    with pytest.raises(radiosity.RadiosityError) as refused:
        if option in ("nonplanar", "duplicates", "coplanar"):
            radiosity.Scene.load("no-such-scene.obj", **{option: bogus})
        else:
            radiosity.solve(radiosity.Scene.builtin("cube"), refine=0, **{option: bogus})
    message = str(refused.value)
    assert f"{option} '{bogus}' is not known" in message
    for value in valid:
        assert value in message
    # And each valid value is accepted (as far as parsing: a valid value fails no earlier).
    for value in valid:
        if option in ("nonplanar", "duplicates", "coplanar"):
            with pytest.raises(radiosity.RadiosityError) as missing:
                radiosity.Scene.load("no-such-scene.obj", **{option: value})
            assert "is not known" not in str(missing.value)


EXAMPLE = '''
import numpy as np
import radiosity

scene = radiosity.Scene.builtin("five-piece", params=(5.0, 2.0, 1.0))
names: list[str] = scene.face_names
run = radiosity.solve(scene, refine=1, method="linear", mesh="discontinuity", solver="lu")
u: np.ndarray = run.u
error: float = run.error
op = radiosity.operator(scene, refine=1, operator="compressed", progress=lambda s, d, t: None)
v = op.solve(np.ones(len(scene)))
F = radiosity.view_factors(scene, refine=0, each_direction=True)
room = radiosity.Scene.load("room.toml", coplanar="keep")
mesh = radiosity.from_arrays([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], 0.5, coplanar="merge")
'''

WRONG = '''
import radiosity

scene = radiosity.Scene.builtin("cube")
radiosity.solve(scene, operator="sparse")
radiosity.solve(scene, refin=2)
radiosity.Scene.load("room.toml", coplanar="glue")
'''


def mypy(tmp_path, source):
    api = pytest.importorskip("mypy.api")
    script = tmp_path / "example.py"
    script.write_text(source)
    out, err, status = api.run(
        ["--no-incremental", "--cache-dir", str(tmp_path / "cache"), "--python-executable",
         sys.executable, str(script)]
    )
    return out + err, status


def test_mypy_accepts_the_api_used_right_and_refuses_it_used_wrong(tmp_path):
    out, status = mypy(tmp_path, EXAMPLE)
    assert status == 0, out
    out, status = mypy(tmp_path, WRONG)
    assert status == 1, out
    for line in (5, 6, 7):
        assert f"example.py:{line}: error" in out, out
