"""Grader for ``python-library`` (seed ch. 14; contract in shared/LESSONS.md).

Black-box on the *installed* library: after ``colcon build``, a separate Python
process with the workspace sourced (``s.overlay()``), started from an empty
folder outside the source tree, imports
``python_package_with_a_library.sample_python_library`` and calls its function
and class with values the grader picks (negative and float ones included). The
files must be under ``install/<pkg>/lib/python3.*/site-packages/<pkg>/sample_python_library/``:
a library that only imports from ``src/`` would not work for other packages.
"""

from __future__ import annotations

import json
import math

from ros2course.kit import Check, Session
from ros2course.kit.packaging import installed_import, installed_subpackage

PACKAGE = "python_package_with_a_library"
SUBPACKAGE = "sample_python_library"
MODULE = f"{PACKAGE}.{SUBPACKAGE}"
FUNCTION = "sample_function_for_square_of_sum"
CLASS = "SampleClass"
#: (a, b) pairs for the function: ints, floats, negatives, zero sum, a large value (seed ch. 14.3: (a+b)**2)
CASES = [(1, 2), (0.5, 0.25), (-3, 1), (-1.5, -2.5), (2, -2), (0.1, 0.2), (1000, 1), (1.7, 0)]
#: names for SampleClass(name): the second one like ch. 15's random ten letters, passed as name=...
NAMES = ["Alice", "qyOXLBEtzZ"]
REL_TOL = 1e-9  # the seed's a**2 + 2*a*b + b**2 differs from (a+b)**2 by float rounding only

#: No node is observed: the library is imported and called in a subprocess.
WINDOW = 0.0

CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("installed", "colcon installs the sub-package sample_python_library", 2,
          "list every Python package in setup.py: packages=find_packages(exclude=['test']) "
          "(packages=[package_name] installs only the top level); sample_python_library needs its own __init__.py"),
    Check("importable", "The installed library imports from another folder with the workspace sourced", 2,
          "from python_package_with_a_library.sample_python_library import SampleClass, "
          "sample_function_for_square_of_sum must work after 'source install/setup.bash', from any folder"),
    Check("square_of_sum", "sample_function_for_square_of_sum(a, b) returns (a + b)**2", 2,
          "export the function in sample_python_library/__init__.py and return (a + b) ** 2 "
          "(that is a**2 + 2*a*b + b**2)", needs=("importable",)),
    Check("sample_class", "SampleClass(name).get_name() returns that name", 2,
          "store the name in __init__ (self._name = name) and return it from get_name(); "
          "export SampleClass in sample_python_library/__init__.py", needs=("importable",)),
    Check("layout", "The function and the class live in their private modules, re-exported by __init__.py", 1,
          "define sample_function_for_square_of_sum in sample_python_library/_sample_function.py and SampleClass "
          "in sample_python_library/_sample_class.py; the sub-package's __init__.py only imports them",
          needs=("importable",)),
]

_PROBE = """
import importlib, json, sys
cases, names = json.loads(@CASES@), json.loads(@NAMES@)
out = {}


def text(exc):
    return f"{type(exc).__name__}: {exc}"


def dump():
    with open(sys.argv[1], "w") as f:
        json.dump(out, f)


try:
    mod = importlib.import_module(sys.argv[2])
    out["file"] = str(getattr(mod, "__file__", None) or list(getattr(mod, "__path__", [])))
except BaseException as exc:
    out["error"] = text(exc)
    dump()
    sys.exit(0)
out["names"] = sorted(n for n in dir(mod) if not n.startswith("__"))
f = getattr(mod, @FUNCTION@, None)
if f is not None:
    out["function_module"] = str(getattr(f, "__module__", None))
    out["calls"] = []
    for a, b in cases:
        try:
            r = f(a, b)
            ok = isinstance(r, (int, float)) and not isinstance(r, bool)
            out["calls"].append({"a": a, "b": b, "value": float(r) if ok else None, "repr": repr(r)[:80],
                                 "type": type(r).__name__})
        except BaseException as exc:
            out["calls"].append({"a": a, "b": b, "error": text(exc)})
    try:  # by the parameter names the lesson gives, (a, b), as SampleClass is made with name=...
        r = f(a=cases[0][0], b=cases[0][1])
        out["keywords"] = {"repr": repr(r)[:80]}
    except BaseException as exc:
        out["keywords"] = {"error": text(exc)}
cls = getattr(mod, @CLASS@, None)
if cls is not None:
    out["class_module"] = str(getattr(cls, "__module__", None))
    got = []
    try:
        first = cls(names[0])
        second = cls(name=names[1])
        got = [first.get_name(), second.get_name()]
        out["names_returned"] = [repr(g)[:80] for g in got]
        out["names_ok"] = got == names
    except BaseException as exc:
        out["class_error"] = text(exc)
dump()
"""
# (the module to import comes in sys.argv[2]: ros2course.kit.packaging.installed_import passes it)
for _key, _value in {"@CASES@": json.dumps(CASES), "@NAMES@": json.dumps(NAMES), "@FUNCTION@": FUNCTION,
                     "@CLASS@": CLASS}.items():
    _PROBE = _PROBE.replace(_key, repr(_value))


def _record_function(s: Session, result: dict) -> None:
    """``square_of_sum``: the probe's calls of the function returned (a + b)**2 (seed ch. 14.3)."""
    expected = ("(a + b)**2 for " + ", ".join(f"({a}, {b})" for a, b in CASES)
                + " (an int for two ints), called positionally and as (a=..., b=...)")
    calls = result.get("calls")
    if calls is None:
        s.record("square_of_sum", False, f"{MODULE} has no {FUNCTION}; it exports: "
                 f"{', '.join(result.get('names', [])) or 'nothing'}", expected)
        return
    wrong = []
    for call in calls:
        a, b = call["a"], call["b"]
        want = (a + b) ** 2
        if "error" in call:
            wrong.append(f"({a}, {b}) raised {call['error']}")
        elif call["value"] is None:
            wrong.append(f"({a}, {b}) returned {call['repr']}, not a number")
        elif not math.isclose(call["value"], want, rel_tol=REL_TOL, abs_tol=1e-12):
            wrong.append(f"({a}, {b}) returned {call['repr']} instead of {want!r}")
        elif isinstance(want, int) and call.get("type") != "int":
            # (a + b)**2 of two ints is an int (the lesson's own try-out prints f(1, 2) as 9); math.pow gives 9.0
            wrong.append(f"({a}, {b}) returned {call['repr']} (a {call.get('type')}), not the int {want!r}")
    keywords = result.get("keywords") or {}
    if "error" in keywords:
        a, b = CASES[0]
        wrong.append(f"{FUNCTION}(a={a}, b={b}) raised {keywords['error']}: the parameters are not named a and b")
    right = len(calls) - len(wrong)
    observed = (f"correct for all {len(calls)} pairs, also called as (a=..., b=...)" if not wrong
                else f"{right}/{len(calls)} right; " + "; ".join(wrong[:3]) + (" ..." if len(wrong) > 3 else ""))
    s.record("square_of_sum", not wrong, observed, expected)


def _record_class(s: Session, result: dict) -> None:
    """``sample_class``: two instances gave back the names they were made with (seed ch. 14.3)."""
    expected = (f"{CLASS}({NAMES[0]!r}).get_name() == {NAMES[0]!r} and "
                f"{CLASS}(name={NAMES[1]!r}).get_name() == {NAMES[1]!r}, each instance keeping its own name")
    if "names_returned" not in result and "class_error" not in result:
        s.record("sample_class", False, f"{MODULE} has no {CLASS}; it exports: "
                 f"{', '.join(result.get('names', [])) or 'nothing'}", expected)
    elif "class_error" in result:
        s.record("sample_class", False, f"creating or asking the instances raised {result['class_error']}", expected)
    else:
        s.record("sample_class", bool(result.get("names_ok")),
                 f"get_name() returned {' and '.join(result['names_returned'])}", expected)


#: Where each public name must be defined (seed ch. 14.2: one private module per piece).
HOMES = {FUNCTION: (f"{MODULE}._sample_function", "function_module"),
         CLASS: (f"{MODULE}._sample_class", "class_module")}


def _record_layout(s: Session, result: dict) -> None:
    """``layout``: the function and the class are defined in ``_sample_function.py`` and ``_sample_class.py``
    (their ``__module__``), so ``sample_python_library/__init__.py`` only re-exports them (seed ch. 14.2)."""
    expected = ", ".join(f"{name} defined in {home}" for name, (home, _) in HOMES.items())
    found = {name: result.get(key) for name, (_, key) in HOMES.items()}
    wrong = [f"{name} is defined in {found[name]}" if found[name] else f"{MODULE} has no {name}"
             for name, (home, _) in HOMES.items() if found[name] != home]
    observed = ("; ".join(wrong) if wrong
                else ", ".join(f"{name} from {found[name]}" for name in HOMES))
    s.record("layout", not wrong, observed, expected, fraction=(len(HOMES) - len(wrong)) / len(HOMES))


def grade(s: Session) -> None:
    """Check the install tree, then import and exercise the installed library in a subprocess."""
    installed = installed_subpackage(s, "installed", PACKAGE, SUBPACKAGE)
    result = installed_import(s, "importable", MODULE, f"from {MODULE} import {CLASS}, {FUNCTION} works from "
                              "outside src/, using the installed copy",
                              note="" if installed else " (it is not installed, see above)", code=_PROBE)
    _record_function(s, result)
    _record_class(s, result)
    _record_layout(s, result)
