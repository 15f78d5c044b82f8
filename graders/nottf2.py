"""Grader for ``nottf2`` (the author's Jazzy edition, "The support library nottf2"; issue 40).

Black-box on the output of ``ros2 run python_package_that_uses_nottf2 operations_showcase``: four quaternions,
each printed once as ``NAME=...Quaternion(x=.., y=.., z=.., w=..)`` (r1 = rx(pi), r1_conj = its inverse,
r2 = rz(pi), r12 = r1 r2), then it ends by itself. Expected values: nottf2's own API (``marinholab.nottf2``)
when the grader can import it, always cross-checked against the closed forms (:func:`closed_forms`). Compared
component by component, not up to sign: q and -q are one rotation, but for phi = pi r1 and its inverse are
that pair, and so are r1 r2 and r2 r1.

Then the program runs once more with a stand-in of ``marinholab.nottf2`` first on ``PYTHONPATH``
(:data:`STAND_IN`): the same functions, each returning its true result negated (the same rotation). Through
the chapter's chain a program that calls nottf2 prints -r1, conj(r1), -r2 and -(r1 r2); one that computes a
quaternion itself (math.sin and math.cos, a hand-written conjugate or product) prints another value there
(``uses_nottf2``, judged for each quantity whose value was right in the first run).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from ros2course.kit import Check, NotGradable, Session, depends, python_programs, source_package
from ros2course.kit.packaging import ros2_run_executable, setup_py_arguments
from ros2course.kit.programs import ProgramRun, run_program

PACKAGE = "python_package_that_uses_nottf2"
EXECUTABLE = "operations_showcase"
PHI = math.pi  # the chapter's angle, half a turn
TOLERANCE = 1e-9  # per component, absolute: float rounding of cos(pi/2) is 6.1e-17
EXIT_TIMEOUT = 10.0  # seconds: four lines; the interpreter and numpy start well within it
#: The program prints and exits: nothing is watched over time.
WINDOW = 0.0
#: The stand-in of marinholab.nottf2, copied as ``marinholab/nottf2/__init__.py`` into a folder first on
#: PYTHONPATH (``marinholab`` is a namespace package: the first ``marinholab/nottf2`` on sys.path wins).
STAND_IN = Path(__file__).parent / "data" / "nottf2" / "stand_in_nottf2.py"

_VALUE = "print each with print(f'...{name}={q}'), shown as name=geometry_msgs.msg.Quaternion(x=..., ...)"
CHECKS = [
    Check("build", "The package builds with colcon", 1),
    Check("depends_geometry_msgs", "package.xml declares the geometry_msgs dependency", 1,
          "add <depend>geometry_msgs</depend> (nottf2 returns geometry_msgs/msg/Quaternion messages)"),
    Check("requires_nottf2", "setup.py lists nottf2 in install_requires", 1,
          "install_requires=['setuptools', 'nottf2']: the name pip installs, not the import name marinholab.nottf2"),
    Check("executable", "ros2 run finds operations_showcase", 2,
          "register 'operations_showcase = python_package_that_uses_nottf2.operations_showcase:main' in "
          "console_scripts (setup.py), then colcon build"),
    Check("rx_pi", "It prints r1 = rx(pi), half a turn about x", 2,
          f"r1 = nottf2.rx(phi=math.pi); {_VALUE}", needs=("executable",)),
    Check("inverse", "It prints r1_conj = rotation_inverse(r1)", 2,
          f"r1_conj = nottf2.rotation_inverse(r1) (the conjugate: x, y, z negated); {_VALUE}", needs=("executable",)),
    Check("rz_pi", "It prints r2 = rz(pi), half a turn about z", 2,
          f"r2 = nottf2.rz(phi=math.pi); {_VALUE}", needs=("executable",)),
    Check("product", "It prints r12 = quaternion_multiply(r1, r2), r1 first", 2,
          f"r12 = nottf2.quaternion_multiply(r1, r2): the product is not commutative, r2 r1 differs; {_VALUE}",
          needs=("executable",)),
    Check("exit_code", "It ends by itself with exit code 0 and no traceback", 2,
          "main() prints the four lines and returns: no spin, no loop, no input()", needs=("executable",)),
    Check("uses_nottf2", "The four quaternions come from nottf2's functions", 2,
          "compute each with nottf2 (import marinholab.nottf2 as nottf2): rx, rotation_inverse, rz, "
          "quaternion_multiply; do not build them yourself from sin and cos or write your own product",
          needs=("executable",)),
]

Q = tuple[float, float, float, float]  # (x, y, z, w), the field order of geometry_msgs/msg/Quaternion


def _mul(a: Q, b: Q) -> Q:
    """Hamilton product ab of (x, y, z, w) tuples, written out (independent of nottf2's matrix form)."""
    (ax, ay, az, aw), (bx, by, bz, bw) = a, b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def closed_forms(phi: float = PHI) -> dict[str, Q]:
    """The four quaternions in closed form: rx(phi) = (sin phi/2, 0, 0, cos phi/2), ..., inverse = conjugate."""
    s, c = math.sin(phi / 2), math.cos(phi / 2)
    r1, r2 = (s, 0.0, 0.0, c), (0.0, 0.0, s, c)
    return {"r1": r1, "r1_conj": (-s, 0.0, 0.0, c), "r2": r2, "r12": _mul(r1, r2)}


def expected_values() -> tuple[dict[str, Q], str]:
    """``({name: quaternion}, source)``: nottf2's results when importable here, else the closed forms.

    Raises NotGradable when nottf2 disagrees with the closed forms (a nottf2 release changed its conventions:
    the course must be reviewed before grading anyone).
    """
    forms = closed_forms()
    try:
        import marinholab.nottf2 as ntf2  # noqa: PLC0415 - optional: needs geometry_msgs in this process
        from importlib.metadata import version  # noqa: PLC0415
    except ImportError:
        return forms, "the closed forms (nottf2 is not importable by the grader)"
    r1, r2 = ntf2.rx(phi=PHI), ntf2.rz(phi=PHI)
    got = {"r1": r1, "r1_conj": ntf2.rotation_inverse(r1), "r2": r2, "r12": ntf2.quaternion_multiply(r1, r2)}
    values = {name: (float(q.x), float(q.y), float(q.z), float(q.w)) for name, q in got.items()}
    if any(not _close(values[n], forms[n], 1e-12) for n in forms):
        raise NotGradable(f"nottf2 {version('nottf2')} disagrees with the closed forms: {values} vs {forms}")
    return values, f"nottf2 {version('nottf2')}, equal to the closed forms"


def _close(a: Q, b: Q, tol: float = TOLERANCE) -> bool:  # component by component, not up to sign
    return all(abs(p - q) <= tol for p, q in zip(a, b))


def _show(q: Q) -> str:
    return "Quaternion(" + ", ".join(f"{k}={v:.6g}" for k, v in zip("xyzw", q)) + ")"


NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf)"
#: NAME=Quaternion(...), one level of parentheses inside: numpy 2 shows nottf2's product as x=np.float64(6.1e-17)
PRINTED = re.compile(r"(?<![\w.])(r1_conj|r12|r1|r2)\s*=\s*(?:geometry_msgs\.msg\.)?"
                     r"Quaternion\(((?:[^()]|\([^()]*\))*)\)")
FIELD = re.compile(rf"\b([xyzw])\s*=\s*(?:(?:np|numpy)\.)?(?:float(?:64|32)?\(\s*)?({NUMBER})")


def parse(text: str) -> dict[str, list[Q | str]]:
    """Each name's printed quaternions, in order (the text inside the parentheses when a field is missing)."""
    found: dict[str, list[Q | str]] = {}
    for match in PRINTED.finditer(text):
        fields = {k: float(v) for k, v in FIELD.findall(match.group(2))}
        got = tuple(fields[k] for k in "xyzw") if len(fields) == 4 else match.group(2)[:80]
        found.setdefault(match.group(1), []).append(got)
    return found


def _sharing(text: str, name: str) -> list[str]:
    """The other names printed on the line of ``name``'s first print (the lesson: each "on a line of its own";
    the independent review of stop 82 got full marks with all four on one summary line)."""
    for line in text.splitlines():
        names = [m.group(1) for m in PRINTED.finditer(line)]
        if name in names:
            return sorted(set(names) - {name})
    return []


def _mistakes(want: dict[str, Q]) -> dict[str, dict[str, Q]]:
    """The values a usual slip prints instead, per name, to say which slip it was."""
    s, c = math.sin(PHI / 2), math.cos(PHI / 2)
    ry, rx = (0.0, s, 0.0, c), (s, 0.0, 0.0, c)
    return {"r1": {"ry(pi): about y, not x": ry, "rz(pi): about z, not x": want["r2"],
                   "r1_conj: the inverse printed as r1": want["r1_conj"]},
            "r1_conj": {"r1 itself: the inverse is left out": want["r1"]},
            "r2": {"ry(pi): about y, not z": ry, "rx(pi): about x, not z": rx},
            "r12": {"r2 r1: the operands in the wrong order": _mul(want["r2"], want["r1"]),
                    "r1 r1_conj, the identity: r1 times its inverse": _mul(want["r1"], want["r1_conj"]),
                    "r1 alone: r2 never multiplied": want["r1"]}}


def record_value(s: Session, check_id: str, name: str, what: str, printed: dict, want: dict[str, Q],
                 source: str, run: ProgramRun) -> bool:
    """Record ``check_id``: ``name`` was printed as a quaternion equal to the expected one, component by component."""
    expected = (f"one line with {name}=Quaternion(x=, y=, z=, w=) equal to {what} = {_show(want[name])} "
                f"(each component within {TOLERANCE:g}; from {source})")
    items = printed.get(name, [])
    if not items:
        lines = [line.strip() for line in (run.stdout + run.stderr).splitlines() if line.strip()]
        shown = " | ".join(repr(line[:100]) for line in lines[:4]) or "nothing"
        return s.record(check_id, False, f"no {name}=...Quaternion(...) in the output ({run.describe()}); "
                        f"it printed: {shown}", expected)
    if isinstance(got := items[0], str):
        return s.record(check_id, False, f"{name}=Quaternion({got}): x, y, z and w are not all numbers", expected)
    observed = f"{name}={_show(got)}"
    slip = [why for why, q in _mistakes(want)[name].items() if _close(got, q)]
    if not _close(got, want[name]) and slip:
        observed += f", which is {slip[0]}"
    if len(items) > 1:  # the chapter's output: each quantity once
        observed += f"; {name}= printed {len(items)} times (is main() also called when the module is imported?)"
    sharing = _sharing(run.stdout + "\n" + run.stderr, name)
    if sharing:
        observed += f"; on the same line as {', '.join(sharing)}: each quaternion goes on a line of its own"
    return s.record(check_id, _close(got, want[name]) and len(items) == 1 and not sharing, observed, expected)


def record_requires(s: Session) -> bool:
    """``requires_nottf2``: setup.py's install_requires names the PyPI distribution nottf2 (the author's setup.py)."""
    expected = "'nottf2' in setup.py's install_requires (a version specifier is fine)"
    found = source_package(s, PACKAGE)
    if found is None:
        return s.record("requires_nottf2", False, f"no package {PACKAGE} in src/", expected)
    arguments, problem = setup_py_arguments(s, found[0])
    if problem:
        return s.record("requires_nottf2", False, problem, expected)
    listed = arguments.get("install_requires") or []
    listed = [listed] if isinstance(listed, str) else [str(r) for r in listed]
    names = [re.split(r"[\s<>=!~;\[(]", r.strip(), maxsplit=1)[0].lower().replace("_", "-") for r in listed]
    observed = f"install_requires={listed!r}"
    if "nottf2" not in names and any("nottf2" in n for n in names):
        observed += " (marinholab.nottf2 is the import name; pip knows the package as nottf2)"
    return s.record("requires_nottf2", "nottf2" in names, observed, expected)


def grade(s: Session) -> None:
    """Read package.xml and setup.py, run the executable once, judge its four quaternions and its exit."""
    want, source = expected_values()
    depends(s, "depends_geometry_msgs", PACKAGE, ("geometry_msgs",))
    record_requires(s)
    path = ros2_run_executable(s, "executable", PACKAGE, EXECUTABLE)
    # not a node (the chapter's program uses no rclpy): a program, with the workspace sourced as 'ros2 run' has it
    run = run_program(s, [str(path)], EXECUTABLE, timeout=EXIT_TIMEOUT, env=s.overlay())
    printed = parse(run.stdout + "\n" + run.stderr)  # print() or a logger (ros2 run shows its records on stderr)
    for check_id, name, what in (("rx_pi", "r1", "rx(pi)"), ("inverse", "r1_conj", "rotation_inverse(r1)"),
                                 ("rz_pi", "r2", "rz(pi)"), ("product", "r12", "quaternion_multiply(r1, r2)")):
        record_value(s, check_id, name, what, printed, want, source, run)
    expected = f"exit code 0 within {EXIT_TIMEOUT:.0f} s, no traceback"
    s.record("exit_code", not run.timed_out and run.returncode == 0 and not run.traceback, run.describe(), expected)
    right = [name for check_id, name in (("rx_pi", "r1"), ("inverse", "r1_conj"), ("rz_pi", "r2"), ("product", "r12"))
             if s.results[check_id].passed]
    uses_nottf2(s, path, right)


def uses_nottf2(s: Session, path, names: list[str]) -> bool:
    """Record ``uses_nottf2``: run the program again with :data:`STAND_IN` first on PYTHONPATH; each of ``names``
    (the quantities it printed right) must now be the stand-in's value (its chain: -r1, conj(r1), -r2,
    -(r1 r2)). ``path``: the executable. Fraction: the share of ``names`` that are."""
    expected = ("with a stand-in of marinholab.nottf2 whose functions return their result negated (the same "
                "rotation), the values the stand-in gives: " + ", ".join(
                    f"{n}={_show(q)}" for n, q in _stand_in_chain().items() if n in names))
    if not names:
        return s.record("uses_nottf2", False, "no quaternion was right in the first run: nothing to compare",
                        expected)

    env = python_programs.stand_in_env(s, "nottf2-stand-in", {"marinholab/nottf2/__init__.py": STAND_IN})
    run = run_program(s, [str(path)], f"{EXECUTABLE}.stand-in", timeout=EXIT_TIMEOUT, env=env)
    printed, want = parse(run.stdout + "\n" + run.stderr), _stand_in_chain()
    got = {n: printed[n][0] for n in names if printed.get(n) and not isinstance(printed[n][0], str)}
    own = [n for n in names if n not in got or not _close(got[n], want[n])]
    observed = "; ".join(f"{n}={_show(got[n])}" if n in got else f"{n}: not printed ({run.describe()})"
                         for n in names)
    if own:
        observed += f": {', '.join(own)} not the stand-in's (computed without nottf2?)"
    return s.record("uses_nottf2", not own, observed, expected, fraction=(len(names) - len(own)) / len(names))


def _stand_in_chain() -> dict[str, Q]:
    """What the chapter's chain prints through :data:`STAND_IN`: -r1, conj(-r1) negated, -r2, -((-r1)(-r2))."""
    forms = closed_forms()
    r1, r2 = tuple(-v for v in forms["r1"]), tuple(-v for v in forms["r2"])
    conj = (r1[0], r1[1], r1[2], -r1[3])  # -(conjugate of r1'): x, y, z kept, w negated
    return {"r1": r1, "r1_conj": conj, "r2": r2, "r12": tuple(-v for v in _mul(r1, r2))}
