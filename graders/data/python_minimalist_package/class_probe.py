"""Class probe of ``python-minimalist-package`` (run by graders/python_minimalist_package.py).

Run in a child interpreter with the learner's ``python/minimalist_package`` as
the working directory. Imports ``MinimalistClass``, exercises each element the
lesson asks for (3.5 and 4.25 as arguments; the class attribute
last, since one key changes it for a moment) and prints one JSON object: each
key maps to the repr of what came back, or ``{"error": "..."}`` when the
learner's code raised (each key is computed on fresh instances, independently).
"""

import inspect
import json
import sys

sys.path.insert(0, ".")
out = {}


def attempt(key, fn):
    try:
        out[key] = fn()
    except BaseException as exc:  # the learner's code failed: say how
        out[key] = {"error": type(exc).__name__ + ": " + str(exc)}


try:
    from minimalist_package import MinimalistClass as C
except BaseException as exc:
    print(json.dumps({"import": type(exc).__name__ + ": " + str(exc)}))
    raise SystemExit(0) from None
out["import"] = ""


def after_set(attribute):
    """What the instance holds (``attribute``: a name, or None for the getter) after set_private_attribute(7.75)."""
    c = C(attribute_arg=3.5, private_attribute_arg=4.25)
    c.set_private_attribute(7.75)
    return repr(c.get_private_attribute() if attribute is None else getattr(c, attribute))


def hints():
    """Public methods (and __init__) without type hints or docstrings, one sentence each."""
    problems = []
    for name, member in vars(C).items():
        if name.startswith("_") and name != "__init__":
            continue
        func = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
        if not inspect.isfunction(func):
            continue
        sig = inspect.signature(func)
        params = [p for i, p in enumerate(sig.parameters.values())
                  if not (i == 0 and p.name in ("self", "cls") and not isinstance(member, staticmethod))]
        bare = [p.name for p in params if p.annotation is inspect.Parameter.empty]
        if bare:
            problems.append(f"{name}(): argument(s) {', '.join(bare)} without a type hint")
        if name != "__init__" and sig.return_annotation is inspect.Signature.empty:
            problems.append(f"{name}(): no return type (-> ...)")
        if name != "__init__" and not (inspect.getdoc(func) or "").strip():
            problems.append(f"{name}(): no docstring")
    return problems


attempt("default_attribute", lambda: repr(C().attribute))
attempt("attribute", lambda: repr(C(attribute_arg=3.5, private_attribute_arg=4.25).attribute))
attempt("private_stored", lambda: repr(C(attribute_arg=3.5, private_attribute_arg=4.25)._private_attribute))
attempt("private_get", lambda: repr(C(attribute_arg=3.5, private_attribute_arg=4.25).get_private_attribute()))
attempt("private_default", lambda: repr(C().get_private_attribute()))
attempt("private_after_set", lambda: after_set(None))
attempt("private_stored_after_set", lambda: after_set("_private_attribute"))
attempt("method", lambda: repr(C(attribute_arg=3.5, private_attribute_arg=4.25).method()))
attempt("static", lambda: repr(C.static_method()))
attempt("static_kind", lambda: repr(type(vars(C).get("static_method")).__name__))  # @staticmethod, not @classmethod
attempt("static_instance", lambda: repr(C().static_method()))
attempt("reference", lambda: repr(C.attribute_reference))
attempt("reference_instance", lambda: repr(C().attribute_reference))


def static_from_reference():
    """What static_method() returns while MinimalistClass.attribute_reference is 'Bye ' (restored afterwards)."""
    missing = object()
    saved = C.__dict__.get("attribute_reference", missing)
    C.attribute_reference = "Bye "
    try:
        return repr(C.static_method())
    finally:
        if saved is missing:
            del C.attribute_reference
        else:
            C.attribute_reference = saved


attempt("static_from_reference", static_from_reference)
attempt("hints", hints)
print(json.dumps(out))
