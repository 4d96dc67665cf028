"""inspect.signature works on every public callable of omma (functions, constructors, methods,
static methods, exception types), its parameters are the C++ bindings' py::arg names, and they match
the type stubs (omma/__init__.pyi) name for name."""
import ast
import inspect
from pathlib import Path

import omma

# Classes that only omma's functions create (no constructor; see stubtest_allowlist.txt).
NO_CONSTRUCTOR = {"Rig", "Design", "Simulation", "FrameSet", "LiveRun"}


def public_callables():
    """(qualified name, object) of every public function, class, method and static method."""
    for name in omma.__all__:
        obj = getattr(omma, name)
        if inspect.isclass(obj):
            if name not in NO_CONSTRUCTOR:
                yield name, obj
            if issubclass(obj, BaseException):
                continue
            for attr, value in vars(obj).items():
                if (attr.startswith("_") and attr != "__init__") or isinstance(value, property):
                    continue
                if attr == "__init__" and name in NO_CONSTRUCTOR:
                    continue
                yield f"{name}.{attr}", getattr(obj, attr)
        elif callable(obj):
            yield name, obj


def test_every_public_callable_has_a_signature():
    names = []
    for name, obj in public_callables():
        sig = inspect.signature(obj)  # raises ValueError where there is none
        params = list(sig.parameters.values())
        # No catch-all (*args, **kwargs) stand-in, except where the binding takes keyword options
        # (calibrate, simulate) or the exception types' (*args).
        if not any(p.kind == p.VAR_KEYWORD for p in params):
            assert not any(p.kind == p.VAR_POSITIONAL for p in params) or name.endswith("Error"), (name, sig)
        names.append(name)
    # Everything, the new parts included.
    for expected in ("Rig.load", "stitch", "Engine", "Engine.render", "Recording", "Recording.frame_set", "record",
                     "render", "export_pto", "import_pto", "plan", "table71", "run", "LiveRun.close", "RigError",
                     "RecordingError"):
        assert expected in names
    assert len(names) > 60


def test_signatures_are_the_bindings():
    assert str(inspect.signature(omma.stitch)) == (
        "(rig: omma.Rig, frames: object, method: str = 'mrf', projection: str = 'vr180', "
        "size: object = (1080, 1080), progress: bool = False) -> object")
    sig = inspect.signature(omma.run)
    assert list(sig.parameters)[:3] == ["rig", "source", "sinks"]
    assert sig.parameters["frames"].default == 0 and sig.parameters["sinks"].default is None
    assert sig.parameters["min_weight"].default == 0.05
    assert list(inspect.signature(omma.Engine).parameters)[:2] == ["rig", "method"]  # self bound
    assert list(inspect.signature(omma.Rig.load).parameters) == ["path"]
    assert list(inspect.signature(omma.thesis_prototype_rig().to_json).parameters) == ["indent"]
    assert list(inspect.signature(omma.RigError).parameters) == ["args"]
    sig = inspect.signature(omma.calibrate)
    assert [p.kind for p in sig.parameters.values()][-1] == inspect.Parameter.VAR_KEYWORD
    # The wrappers keep the bindings' docs and behaviour (pybind11 still checks the arguments).
    assert "as `omma run`" in omma.run.__doc__ and omma.run.__module__ == "omma"
    assert omma.Rig.__module__ == "omma"
    try:
        omma.stitch(omma.thesis_prototype_rig(), [], nonsense=1)
    except TypeError as e:
        assert "incompatible function arguments" in str(e)
    else:
        raise AssertionError("no TypeError")


def stub_parameters():
    """{qualified name: parameter names} of the functions and methods in __init__.pyi."""
    tree = ast.parse((Path(omma.__file__).parent / "__init__.pyi").read_text())
    out = {}

    def params(fn):
        a = fn.args
        names = [p.arg for p in a.posonlyargs + a.args + a.kwonlyargs]
        names += [a.vararg.arg] if a.vararg else []
        names += [a.kwarg.arg] if a.kwarg else []
        return names

    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            out[node.name] = params(node)
        elif isinstance(node, ast.ClassDef):
            for f in node.body:
                if isinstance(f, ast.FunctionDef) and not any(
                        isinstance(d, ast.Name) and d.id == "property" for d in f.decorator_list):
                    out[f"{node.name}.{f.name}"] = params(f)
    return out


def test_stubs_name_the_same_parameters():
    stubs = stub_parameters()
    for name, obj in public_callables():
        if inspect.isclass(obj):
            if issubclass(obj, BaseException):
                continue
            name, obj = f"{name}.__init__", obj.__init__
        if name.startswith("open_recording"):
            continue  # an alias of Recording
        assert name in stubs, f"{name} missing from __init__.pyi"
        runtime = list(inspect.signature(obj).parameters)
        stub = stubs[name]
        if stub[:1] == ["self"] and runtime[:1] != ["self"]:
            stub = stub[1:]
        assert runtime == stub, (name, runtime, stub)
