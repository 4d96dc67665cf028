"""Real Python signatures for the compiled functions and methods of omma._omma.

pybind11 functions are builtins whose signature lives only in the first line of their docstring
("stitch(rig: omma._omma.Rig, frames: object, method: str = 'mrf', ...) -> object"), which
`inspect.signature` cannot read (it needs __text_signature__, which pybind11 does not provide). This
module replaces every public compiled function, method, static method and constructor by a thin
Python function that forwards its arguments unchanged to the compiled one (pybind11 still checks
and converts them, with its own messages) and carries an inspect.Signature parsed from that first
line: parameter names, kinds and defaults exactly as the C++ binding declares them (py::arg), the
annotations as pybind11 prints them (omma._omma.X shown as X). The cost is one Python call per call.
"""
import ast
import inspect
import os
import typing

__all__ = ["wrap_module"]


class _Default:
    """A default value whose repr is pybind11's text (for defaults ast.literal_eval cannot read)."""

    def __init__(self, text):
        self.text = text

    def __repr__(self):
        return self.text


def _annotation(node, namespace):
    if node is None:
        return inspect.Parameter.empty
    text = ast.unparse(node).replace("omma._omma.", "")
    try:
        return eval(text, namespace)  # noqa: S307 -- pybind11's own type names, not user input
    except Exception:
        return text


def _default(node):
    try:
        return ast.literal_eval(node)
    except (ValueError, SyntaxError, TypeError):
        return _Default(ast.unparse(node))


def signature_from_doc(name, doc, namespace):
    """The inspect.Signature of pybind11's first docstring line `name(params) -> ret`; None if absent."""
    if not doc:
        return None
    first = doc.split("\n", 1)[0].strip()
    if not first.startswith(name + "("):
        return None
    try:
        tree = ast.parse("def " + first + ": pass")
    except SyntaxError:
        return None
    fn = tree.body[0]
    a = fn.args
    P = inspect.Parameter
    params = []
    positional = [(p, P.POSITIONAL_ONLY) for p in a.posonlyargs] + [(p, P.POSITIONAL_OR_KEYWORD) for p in a.args]
    defaults = [None] * (len(positional) - len(a.defaults)) + list(a.defaults)
    for (p, kind), d in zip(positional, defaults):
        params.append(P(p.arg, kind, default=P.empty if d is None else _default(d),
                        annotation=_annotation(p.annotation, namespace)))
    if a.vararg:
        params.append(P(a.vararg.arg, P.VAR_POSITIONAL, annotation=_annotation(a.vararg.annotation, namespace)))
    for p, d in zip(a.kwonlyargs, a.kw_defaults):
        params.append(P(p.arg, P.KEYWORD_ONLY, default=P.empty if d is None else _default(d),
                        annotation=_annotation(p.annotation, namespace)))
    if a.kwarg:
        params.append(P(a.kwarg.arg, P.VAR_KEYWORD, annotation=_annotation(a.kwarg.annotation, namespace)))
    return inspect.Signature(params, return_annotation=_annotation(fn.returns, namespace))


def _rest_of_doc(doc):
    """The docstring without pybind11's signature line."""
    parts = (doc or "").split("\n", 1)
    return parts[1].strip() if len(parts) > 1 else ""


def _wrap(fn, name, qualname, namespace):
    sig = signature_from_doc(name, fn.__doc__, namespace)
    if sig is None:
        raise RuntimeError(f"omma: no signature in the docstring of {qualname}")

    def wrapper(*args, **kwargs):
        return fn(*args, **kwargs)

    wrapper.__name__ = name
    wrapper.__qualname__ = qualname
    wrapper.__module__ = "omma"
    wrapper.__doc__ = _rest_of_doc(fn.__doc__)
    wrapper.__signature__ = sig
    wrapper._omma_compiled = fn  # the pybind11 function it forwards to
    return wrapper


def _is_compiled(obj):
    return type(obj).__name__ == "builtin_function_or_method"


def _wrap_class(cls, namespace):
    for name, attr in list(vars(cls).items()):
        if name.startswith("_") and name != "__init__":
            continue
        qual = f"{cls.__name__}.{name}"
        if isinstance(attr, staticmethod) and _is_compiled(attr.__func__):
            setattr(cls, name, staticmethod(_wrap(attr.__func__, name, qual, namespace)))
        elif type(attr).__name__ == "instancemethod" and _is_compiled(attr.__func__):
            setattr(cls, name, _wrap(attr.__func__, name, qual, namespace))


def wrap_module(compiled, target):
    """Puts a signature-carrying wrapper of every public function of `compiled` into the dict
    `target` (the package's namespace) and wraps the methods of its classes in place."""
    namespace = {"os": os, "typing": typing, **{k: getattr(typing, k) for k in typing.__all__}}
    try:
        import numpy
        namespace["numpy"] = numpy
    except ImportError:
        pass
    namespace.update({k: v for k, v in vars(compiled).items() if not k.startswith("__")})
    for name, obj in list(vars(compiled).items()):
        if name.startswith("__"):
            continue
        if _is_compiled(obj):
            target[name] = _wrap(obj, name, name, namespace)
        elif isinstance(obj, type) and not issubclass(obj, BaseException):
            _wrap_class(obj, namespace)
            obj.__module__ = "omma"
            target[name] = obj
        else:
            target[name] = obj
