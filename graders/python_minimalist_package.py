"""Grader for ``python-minimalist-package`` (seed ch. 2.1-2.4; contract in shared/LESSONS.md).

Everything lives in ``python/minimalist_package/`` of the workspace (no ROS,
no colcon). The script is run by its own path (so its shebang and executable
bit are what is tested), the class is exercised in a child interpreter, and
the learner's ``unittest`` suite is run as the lesson says, then once more
against deliberately broken versions of their class (patched in memory in a
child interpreter, nothing is written in their folder): a suite that asserts
nothing catches none of them.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import sys
import time
from pathlib import Path

from course.run.probes import wait_until
from graders import kit
from graders.kit import Check, GradingSession, Unmet
from graders.kit.programs import ProgramRun, run_program

PROJECT = Path("python") / "minimalist_package"
SCRIPT = Path("minimalist_package") / "minimalist_script.py"
FILES = (Path("minimalist_package") / "__init__.py", Path("minimalist_package") / "_minimalist_class.py", SCRIPT,
         Path("test") / "test_minimalist_class.py")
SHEBANG = "#!/usr/bin/env python3"
GREETING = "Howdy!"

#: Seconds the script runs after its first 'Howdy!' before Ctrl+C. Counting from the first line
#: (not from the start, which a loaded machine can delay by a second or more) makes the count
#: independent of start-up time: at 2 Hz the first line and 5 more (0.5 ... 2.5 s), one fewer if
#: sleeps overrun; at 1 Hz 3 lines; without a sleep, thousands.
RUN_SECONDS = 2.5
#: Accepted number of 'Howdy!' lines (first line included): 2 Hz, tolerant of jitter, not of 1 or 4 Hz.
MIN_LINES, MAX_LINES = 4, 8
FIRST_LINE_TIMEOUT = 10.0  # seconds to wait for the first line (interpreter start-up under load)
SIGINT_EXIT_TIMEOUT = 3.0  # seconds the script may take to end after Ctrl+C
CHILD_TIMEOUT = 30.0  # seconds for each child interpreter (class probe, test runs): generous under load

#: Observation time the contract needs (benchmarks read it): the script's run from its first line to Ctrl+C.
WINDOW = RUN_SECONDS

CHECKS = [
    Check("layout", "python/minimalist_package holds the package, the script and the test file", 1,
          "create python/minimalist_package/minimalist_package/{__init__.py,_minimalist_class.py,"
          "minimalist_script.py} and python/minimalist_package/test/test_minimalist_class.py"),
    Check("shebang", f"minimalist_script.py starts with '{SHEBANG}'", 1,
          f"make the very first line of minimalist_script.py exactly: {SHEBANG}", part="script"),
    Check("executable_bit", "minimalist_script.py is executable (chmod +x)", 1,
          "run once: chmod +x minimalist_package/minimalist_script.py", part="script"),
    Check("howdy", "Running ./minimalist_script.py prints 'Howdy!' lines", 2,
          "main() prints exactly Howdy! in a loop; the file ends with: if __name__ == \"__main__\": main()",
          part="script"),
    Check("rate", "It prints 'Howdy!' twice a second", 1,
          "sleep 0.5 s between two prints: time.sleep(0.5) in the loop", needs=("howdy",), part="script"),
    Check("sigint_exit", "Ctrl+C ends it with exit code 0 and no traceback", 2,
          "wrap the loop of main() in try: ... except KeyboardInterrupt: pass", part="script"),
    Check("import_class", "'from minimalist_package import MinimalistClass' works", 1,
          "in minimalist_package/__init__.py write: from minimalist_package._minimalist_class import MinimalistClass",
          part="class"),
    Check("attribute", "MinimalistClass(attribute_arg=...) stores it in .attribute (default 10.0)", 1,
          "__init__(self, attribute_arg: float = 10.0, ...) stores self.attribute = attribute_arg",
          needs=("import_class",), part="class"),
    Check("private_attribute", "The private attribute and its getter and setter work", 2,
          "store private_attribute_arg (default 20.0) in self._private_attribute; get_private_attribute() "
          "returns it, set_private_attribute(value) replaces it", needs=("import_class",), part="class"),
    Check("method", "method() returns attribute + private attribute", 1,
          "method(self) returns self.attribute + self._private_attribute", needs=("import_class",), part="class"),
    Check("static_method", "MinimalistClass.static_method() returns 'Hello World!'", 1,
          "decorate it with @staticmethod and return MinimalistClass.attribute_reference + \"World!\" "
          "(attribute_reference = \"Hello \")", needs=("import_class",), part="class"),
    Check("hints_docstrings", "Public methods have type hints and docstrings", 1,
          "annotate every argument and the return type (-> float, -> None, -> str) and give each public "
          "method a \"\"\"docstring\"\"\"", needs=("import_class",), part="class"),
    Check("unit_tests_pass", "'python -m unittest discover -v test' passes", 2,
          "run it in python/minimalist_package and fix what it reports; the test file must define "
          "a unittest.TestCase subclass with test_* methods", part="tests"),
    Check("tests_catch_bugs", "The tests fail when the class is broken", 2,
          "give every element its own test with an assert (assertEqual) on the value it must have",
          needs=("unit_tests_pass",), part="tests"),
]

#: Run in a child interpreter (cwd: the project folder): exercises the class, prints one JSON object.
_CLASS_PROBE = r'''
import inspect, json, sys
sys.path.insert(0, ".")
out = {}
def attempt(key, fn):
    try:
        out[key] = fn()
    except BaseException as exc:
        out[key] = {"error": type(exc).__name__ + ": " + str(exc)}
try:
    from minimalist_package import MinimalistClass as C
except BaseException as exc:
    print(json.dumps({"import": type(exc).__name__ + ": " + str(exc)}))
    raise SystemExit(0)
out["import"] = ""
attempt("default_attribute", lambda: repr(C().attribute))
attempt("attribute", lambda: repr(C(attribute_arg=3.5, private_attribute_arg=4.25).attribute))
def private():
    c = C(attribute_arg=3.5, private_attribute_arg=4.25)
    seen = {"stored": repr(getattr(c, "_private_attribute", "(no _private_attribute)")),
            "default": repr(C().get_private_attribute()), "get": repr(c.get_private_attribute())}
    c.set_private_attribute(7.75)
    seen["after_set"] = repr(c.get_private_attribute())
    seen["stored_after_set"] = repr(getattr(c, "_private_attribute", "(no _private_attribute)"))
    return seen
attempt("private", private)
attempt("method", lambda: repr(C(attribute_arg=3.5, private_attribute_arg=4.25).method()))
attempt("static", lambda: repr(C.static_method()))
attempt("static_instance", lambda: repr(C().static_method()))
def hints():
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
attempt("hints", hints)
print(json.dumps(out))
'''

#: Broken versions of the class, each applied to the class in memory before the learner's tests run:
#: (name shown to the learner, Python statements over C, the class).
MUTANTS = [
    ("__init__ stores attribute_arg + 1 in .attribute",
     "_i = C.__init__\ndef _init(self, *a, **k):\n    _i(self, *a, **k)\n    self.attribute = self.attribute + 1.0\n"
     "C.__init__ = _init"),
    ("__init__ stores private_attribute_arg + 1",
     "_i = C.__init__\ndef _init(self, *a, **k):\n    _i(self, *a, **k)\n"
     "    self._private_attribute = self._private_attribute + 1.0\nC.__init__ = _init"),
    ("get_private_attribute() returns the value + 1",
     "_g = C.get_private_attribute\nC.get_private_attribute = lambda self: _g(self) + 1.0"),
    ("set_private_attribute() does nothing", "C.set_private_attribute = lambda self, value: None"),
    ("method() returns the sum + 1", "_m = C.method\nC.method = lambda self: _m(self) + 1.0"),
    ("static_method() returns 'Hello World?'", "C.static_method = staticmethod(lambda: 'Hello World?')"),
]

#: Runs the learner's suite once per mutant (plus once unbroken, as a control), each in a forked child
#: of one interpreter; prints one JSON list of [tests run, passed?] per run.
_MUTANT_DRIVER = r'''
import io, json, os, sys, unittest
sys.path.insert(0, ".")
MUTANTS = json.loads(sys.argv[1])
results = []
for patch in [""] + MUTANTS:
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        verdict = [0, False]
        try:
            sys.stdout = sys.stderr = io.StringIO()
            from minimalist_package import MinimalistClass as C
            exec(patch, {"C": C})
            suite = unittest.defaultTestLoader.discover("test")
            result = unittest.TextTestRunner(stream=io.StringIO(), verbosity=0).run(suite)
            verdict = [result.testsRun, result.wasSuccessful()]
        except BaseException as exc:
            verdict = [0, False, type(exc).__name__ + ": " + str(exc)]
        os.write(write, json.dumps(verdict).encode())
        os._exit(0)
    os.close(write)
    data = b""
    while chunk := os.read(read, 65536):
        data += chunk
    os.close(read)
    os.waitpid(pid, 0)
    results.append(json.loads(data.decode() or "[0, false]"))
print(json.dumps(results))
'''


def python_env(s: GradingSession) -> dict[str, str]:
    """The grading environment with the course's Python first on PATH (so ``env python3`` finds it).

    Output is unbuffered so what the script printed is kept even if it must be killed,
    and no ``__pycache__`` folders are written into the learner's project.
    """
    env = dict(s.base_env)
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    env["PYTHONUNBUFFERED"] = "1"
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    return env


def run_until_ctrl_c(s: GradingSession, argv: list[str], *, env: dict[str, str],
                     cwd: Path) -> tuple[ProgramRun, bool]:
    """Run the script; RUN_SECONDS after its first 'Howdy!' press Ctrl+C (SIGINT to its group).

    Like :func:`graders.kit.programs.interrupt_after`, but the observation window
    starts at the first line instead of at the start, so a slow interpreter start
    on a loaded machine does not change the count. Ctrl+C comes after
    FIRST_LINE_TIMEOUT s if no line comes.

    Returns:
        ``(run, ended_early)``: what it did (``seconds``: wall time from start to exit
        or stop; ``timed_out``: still running SIGINT_EXIT_TIMEOUT s after Ctrl+C), and
        whether it ended by itself before Ctrl+C.

    Raises:
        OSError: the program cannot be started.
    """
    proc = s.start_program(argv, "minimalist_script", env=env, cwd=cwd,
                           deadline=FIRST_LINE_TIMEOUT + RUN_SECONDS + SIGINT_EXIT_TIMEOUT + 10.0)
    begin = time.monotonic()
    with s.phase("run"):
        wait_until(lambda: proc.poll() is not None or GREETING in proc.stdout(), FIRST_LINE_TIMEOUT)
        window = RUN_SECONDS if GREETING in proc.stdout() else 0.0
        ended_early = wait_until(lambda: proc.poll() is not None, window)
        if not ended_early:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.killpg(proc.pid, signal.SIGINT)
        exited = ended_early or wait_until(lambda: proc.poll() is not None, SIGINT_EXIT_TIMEOUT, interval=0.01)
    elapsed = time.monotonic() - begin
    report = proc.stop(sigint_timeout=0.1, sigterm_timeout=1.0)
    run = ProgramRun(report.returncode, proc.stdout(), proc.stderr(), not exited, elapsed, report.traceback)
    return run, ended_early


def _last_line(text: str) -> str:
    """The last non-blank line of ``text`` ("" if none)."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else ""


def _json_output(run: ProgramRun, what: str) -> object:
    """The JSON the child printed last on stdout.

    Raises:
        Unmet: the child printed none (it crashed, or the learner's code ended the interpreter).
    """
    try:
        return json.loads(_last_line(run.stdout))
    except ValueError:
        detail = _last_line(run.traceback) or _last_line(run.stderr) or run.describe()
        raise Unmet(f"{what} did not finish: {detail}") from None


def grade(s: GradingSession) -> None:
    """Look at the files, run the script by its path, exercise the class, run the learner's tests."""
    project = kit.project_files(s, "layout", PROJECT, FILES)
    env = python_env(s)
    with s.part("script"):
        _judge_script(s, project, env)
    with s.part("class"):
        _judge_class(s, project, env)
    with s.part("tests"):
        _judge_tests(s, project, env)


def _judge_script(s: GradingSession, project: Path, env: dict[str, str]) -> None:
    """Static checks of minimalist_script.py, then one run of RUN_SECONDS ended with Ctrl+C."""
    script = project / SCRIPT
    if not script.is_file():
        raise Unmet(f"{SCRIPT} does not exist")
    first = script.read_bytes().split(b"\n", 1)[0].decode("utf-8", errors="replace")
    shebang_ok = first.rstrip() == SHEBANG and not first.endswith("\r")
    observed = f"first line: {first!r}" if first.strip() else "the first line is empty"
    hint = None
    if first.startswith("#!") and "python" in first and "env" not in first:
        hint = (f"a fixed path such as {first.strip()} runs the system's Python and ignores your venv; "
                f"{SHEBANG} runs the first python3 on PATH (the venv's, when it is active)")
    elif first.endswith("\r"):
        hint = "the file has Windows line endings (CRLF); save it with LF line endings"
    s.record("shebang", shebang_ok, observed, f"exactly {SHEBANG!r} as the first line", hint=hint)
    executable = os.access(script, os.X_OK)
    s.record("executable_bit", executable, f"permissions {script.stat().st_mode & 0o777:o}"
             + ("" if executable else " (no x: ./minimalist_script.py says 'Permission denied')"),
             "executable by you (chmod +x)")

    if shebang_ok and executable:
        argv, how = [str(script)], f"./{SCRIPT.name}"
    else:  # still judge what it prints, the way the learner can run it without the shebang
        argv, how = [sys.executable, str(script)], f"python3 {SCRIPT.name} (it cannot run as ./{SCRIPT.name} yet)"
    try:
        run, ended_early = run_until_ctrl_c(s, argv, env=env, cwd=script.parent)
    except OSError as exc:
        raise Unmet(f"{how} could not be started: {exc.strerror}") from None
    lines = [line.strip() for line in run.stdout.splitlines() if line.strip()]
    howdy = sum(1 for line in lines if line == GREETING)
    others = sorted({line for line in lines if line != GREETING})
    observed = f"ran {how}: {howdy} {GREETING!r} line(s)"
    if others:
        observed += f", other output: {', '.join(repr(o) for o in others[:3])}"
    if not howdy and run.traceback:
        observed += f"; it crashed: {_last_line(run.traceback)}"
    elif not howdy and run.stderr.strip():
        observed += f"; stderr: {_last_line(run.stderr)!r}"
    s.record("howdy", howdy > 0, observed, f"lines that read exactly {GREETING!r} on stdout")
    if ended_early:
        rate_seen = f"it ended by itself after {run.seconds:.1f} s having printed {howdy} line(s)"
    else:
        rate_seen = f"{howdy} line(s): the first and those in the {RUN_SECONDS:.1f} s after it"
    s.record("rate", not ended_early and MIN_LINES <= howdy <= MAX_LINES, rate_seen,
             f"{MIN_LINES} to {MAX_LINES} lines (one every 0.5 s: the first, then about "
             f"{RUN_SECONDS / 0.5:.0f} more before Ctrl+C)",
             hint=None if howdy <= MAX_LINES else "too many lines: is there a time.sleep(0.5) inside the loop?")
    expected = f"exit code 0 within {SIGINT_EXIT_TIMEOUT:.0f} s of Ctrl+C, no traceback"
    if ended_early:
        observed = f"it had already ended by itself ({run.describe()}) before Ctrl+C"
    elif run.timed_out:
        observed = f"still running {SIGINT_EXIT_TIMEOUT:.0f} s after Ctrl+C (stopped)"
    elif run.traceback:
        observed = f"exit code {run.returncode} with a traceback: {_last_line(run.traceback)}"
    else:
        observed = f"exit code {run.returncode}, no traceback"
    s.record("sigint_exit", not ended_early and not run.timed_out and run.returncode == 0 and not run.traceback,
             observed, expected)


def _fmt(value: object) -> str:
    """A probe value for feedback: the repr the child sent, or the error it raised."""
    if isinstance(value, dict) and "error" in value:
        return f"raises {value['error']}"
    return str(value)


def _equal(value: object, expected: float) -> bool:
    """Whether a repr the child sent is the number ``expected`` (floats compared to 1e-9)."""
    try:
        return isinstance(value, str) and abs(float(value) - expected) < 1e-9
    except ValueError:
        return False


def _judge_class(s: GradingSession, project: Path, env: dict[str, str]) -> None:
    """Exercise MinimalistClass in a child interpreter and judge each element."""
    run = run_program(s, [sys.executable, "-c", _CLASS_PROBE], "class_probe", timeout=CHILD_TIMEOUT, env=env,
                      cwd=project)
    probe = _json_output(run, "Importing and exercising MinimalistClass")
    if not isinstance(probe, dict):
        raise Unmet("the class probe printed something unexpected")
    if probe.get("import"):
        s.record("import_class", False, f"the import fails: {probe['import']}",
                 "minimalist_package/__init__.py imports MinimalistClass from _minimalist_class")
        raise Unmet("MinimalistClass cannot be imported")
    s.record("import_class", True, "imported", "the package exports MinimalistClass")

    default, attr = probe.get("default_attribute"), probe.get("attribute")
    s.record("attribute", _equal(attr, 3.5) and _equal(default, 10.0),
             f"MinimalistClass(attribute_arg=3.5, ...).attribute: {_fmt(attr)}; "
             f"MinimalistClass().attribute: {_fmt(default)}", "3.5, and 10.0 by default")

    priv = probe.get("private")
    if isinstance(priv, dict) and "error" not in priv:
        parts = {"stored": 4.25, "get": 4.25, "default": 20.0, "after_set": 7.75, "stored_after_set": 7.75}
        ok = all(_equal(priv.get(k), v) for k, v in parts.items())
        observed = (f"with private_attribute_arg=4.25: _private_attribute {priv['stored']}, "
                    f"get_private_attribute() {priv['get']}; after set_private_attribute(7.75): getter "
                    f"{priv['after_set']}, _private_attribute {priv['stored_after_set']}; "
                    f"default getter {priv['default']}")
    else:
        ok, observed = False, f"using it {_fmt(priv)}"
    s.record("private_attribute", ok, observed,
             "4.25, 4.25; then 7.75, 7.75; default 20.0 (the value lives in self._private_attribute)")

    method = probe.get("method")
    s.record("method", _equal(method, 7.75), f"MinimalistClass(3.5, 4.25).method(): {_fmt(method)}",
             "7.75 (3.5 + 4.25)")

    static, static_i = probe.get("static"), probe.get("static_instance")
    s.record("static_method", static == repr("Hello World!") and static_i == repr("Hello World!"),
             f"MinimalistClass.static_method(): {_fmt(static)}; on an instance: {_fmt(static_i)}",
             "'Hello World!' both ways")

    hints = probe.get("hints")
    if isinstance(hints, list):
        s.record("hints_docstrings", not hints, "; ".join(hints) if hints else "every public method has both",
                 "type hints on every argument and return value, and a docstring, on each public method")
    else:
        s.record("hints_docstrings", False, f"inspecting the methods {_fmt(hints)}", "methods inspect can read")


def _judge_tests(s: GradingSession, project: Path, env: dict[str, str]) -> None:
    """Run the learner's suite as the lesson says, then against each broken class."""
    run = run_program(s, [sys.executable, "-m", "unittest", "discover", "-v", "test"], "unittest",
                      timeout=CHILD_TIMEOUT, env=env, cwd=project)
    ran = re.findall(r"^Ran (\d+) tests? in", run.stderr, flags=re.MULTILINE)
    count = int(ran[-1]) if ran else 0
    summary = _last_line(run.stderr) or run.describe()
    failing = re.findall(r"^(?:FAIL|ERROR): (\S+)", run.stderr, flags=re.MULTILINE)
    observed = f"ran {count} test(s), exit code {run.returncode}: {summary}"
    if failing:
        observed += f" (failing: {', '.join(sorted(set(failing))[:5])})"
    errors = re.findall(r"^(\w*(?:Error|Exception): .*)$", run.stderr, flags=re.MULTILINE)
    if errors:
        observed += f"; last error: {errors[-1].strip()}"
    s.record("unit_tests_pass", run.returncode == 0 and count > 0 and not run.timed_out, observed,
             "at least one test, all passing (OK, exit code 0)",
             hint="no tests were found: name the file test_*.py and the methods test_*" if count == 0 else None)
    s.require("unit_tests_pass")

    patches = json.dumps([code for _, code in MUTANTS])
    run = run_program(s, [sys.executable, "-c", _MUTANT_DRIVER, patches], "unittest_broken_class",
                      timeout=CHILD_TIMEOUT, env=env, cwd=project)
    verdicts = _json_output(run, "Running your tests against broken classes")
    if not isinstance(verdicts, list) or len(verdicts) != len(MUTANTS) + 1:
        raise Unmet("the broken-class runs printed something unexpected")
    control = verdicts[0]
    if not (control[0] > 0 and control[1]):
        s.record("tests_catch_bugs", False, "your tests do not pass when loaded with unittest's own test loader "
                 f"from {PROJECT}: {control[2] if len(control) > 2 else 'some test fails'}",
                 "the suite passes unchanged, then fails for each broken class")
        return
    missed = [name for (name, _), (_, passed, *_) in zip(MUTANTS, verdicts[1:]) if passed]
    caught = len(MUTANTS) - len(missed)
    observed = f"your tests failed (caught the bug) for {caught} of {len(MUTANTS)} broken classes"
    if missed:
        observed += "; they still passed when " + "; when ".join(missed)
    s.record("tests_catch_bugs", not missed, observed,
             f"every one of the {len(MUTANTS)} broken classes makes at least one test fail",
             fraction=caught / len(MUTANTS))
