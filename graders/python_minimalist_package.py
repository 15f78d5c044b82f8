"""Grader for ``python-minimalist-package`` (seed ch. 2.1-2.4; contract in shared/LESSONS.md).

Everything lives in ``python/minimalist_package/`` of the workspace (no ROS,
no colcon). The script is run by its own path (so its shebang and executable
bit are what is tested), the class is exercised in a child interpreter
(``graders/data/python_minimalist_package/class_probe.py``), and the learner's
``unittest`` suite is run as the lesson says, then once more against
deliberately broken versions of their class (``mutants.yaml``, patched in
memory by ``mutant_driver.py``, nothing is written in their folder): a suite
that asserts nothing catches none of them.
"""

from __future__ import annotations

import ast
import re
import sys
from pathlib import Path

import yaml

from ros2course import kit
from ros2course.kit import Check, Session, Unmet
from ros2course.kit import python_programs as py
from ros2course.kit.nodes import sigint_exit
from ros2course.kit.programs import interrupt_after, printed_lines

PROJECT = Path("python") / "minimalist_package"
SCRIPT = Path("minimalist_package") / "minimalist_script.py"
FILES = (Path("minimalist_package") / "__init__.py", Path("minimalist_package") / "_minimalist_class.py", SCRIPT,
         Path("test") / "test_minimalist_class.py")
SHEBANG = "#!/usr/bin/env python3"
GREETING = "Howdy!"
DATA = Path(__file__).resolve().parent / "data" / "python_minimalist_package"

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
#: Seconds main() runs, called directly, after its first 'Howdy!' (check main_function: one line is enough).
MAIN_SECONDS = 0.3
#: Printed by the grader's child between importing minimalist_script and calling its main().
MAIN_MARK = "<ros2course: calling main()>"

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
    Check("main_function", "main() of minimalist_package.minimalist_script prints 'Howdy!' when called", 1,
          "put the loop inside def main(); the file ends with if __name__ == \"__main__\": followed only by main(), "
          "so importing the module prints nothing", part="script"),
    Check("import_class", "'from minimalist_package import MinimalistClass' works", 1,
          "in minimalist_package/__init__.py write: from minimalist_package._minimalist_class import MinimalistClass",
          part="class"),
    Check("absolute_import", "__init__.py imports with the package's full name, not a relative import", 1,
          "write from minimalist_package._minimalist_class import MinimalistClass, not from ._minimalist_class import ...",
          part="class"),
    Check("class_attribute", "attribute_reference is the class attribute 'Hello ' that static_method() builds on", 1,
          "in the class body: attribute_reference: str = \"Hello \"; static_method() returns "
          "MinimalistClass.attribute_reference + \"World!\"", needs=("import_class",), part="class"),
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


def grade(s: Session) -> None:
    """Look at the files, run the script by its path, exercise the class, run the learner's tests."""
    project = kit.project_files(s, "layout", PROJECT, FILES)
    with s.part("script"):
        _judge_script(s, project)
    with s.part("class"):
        _judge_class(s, project)
    with s.part("tests"):
        _judge_tests(s, project)


def _judge_script(s: Session, project: Path) -> None:
    """Shebang and executable bit of minimalist_script.py, then one run ended with Ctrl+C RUN_SECONDS after 'Howdy!'."""
    script = project / SCRIPT
    if not script.is_file():
        raise Unmet(f"{SCRIPT} does not exist")
    shebang_ok = py.shebang(s, "shebang", script, SHEBANG)
    if py.executable_bit(s, "executable_bit", script) and shebang_ok:
        argv, how = [str(script)], f"./{SCRIPT.name}"
    else:  # still judge what it prints, the way the learner can run it without the shebang
        argv, how = [sys.executable, str(script)], f"python3 {SCRIPT.name} (it cannot run as ./{SCRIPT.name} yet)"
    try:
        run = interrupt_after(s, argv, "minimalist_script", RUN_SECONDS, exit_timeout=SIGINT_EXIT_TIMEOUT,
                              env=py.python_env(s), cwd=script.parent, wait_for=GREETING,
                              first_timeout=FIRST_LINE_TIMEOUT)
    except OSError as exc:
        raise Unmet(f"{how} could not be started: {exc.strerror}") from None
    howdy = printed_lines(s, "howdy", run, GREETING, how)
    s.record("rate", run.interrupted and MIN_LINES <= howdy <= MAX_LINES,
             f"{howdy} line(s): the first and those in the {RUN_SECONDS:.1f} s after it" if run.interrupted
             else f"it ended by itself after {run.seconds:.1f} s having printed {howdy} line(s)",
             f"{MIN_LINES} to {MAX_LINES} lines (one every 0.5 s: the first, then about "
             f"{RUN_SECONDS / 0.5:.0f} more before Ctrl+C)",
             hint=None if howdy <= MAX_LINES else "too many lines: is there a time.sleep(0.5) inside the loop?")
    sigint_exit(s, "sigint_exit", run, SIGINT_EXIT_TIMEOUT)
    _judge_main(s, project)


def _judge_main(s: Session, project: Path) -> None:
    """``main_function``: import minimalist_script (it prints nothing), then call main(): it prints 'Howdy!'.

    What an installed console script (and ``ros2 run`` later) does; a loop under the ``if __name__`` block,
    or at the top of the module, is not in main().
    """
    code = f"import minimalist_package.minimalist_script as m\nprint({MAIN_MARK!r}, flush=True)\nm.main()\n"
    run = interrupt_after(s, [sys.executable, "-c", code], "minimalist_script_main", MAIN_SECONDS,
                          exit_timeout=SIGINT_EXIT_TIMEOUT, env=py.python_env(s), cwd=project, wait_for=GREETING,
                          first_timeout=FIRST_LINE_TIMEOUT)
    before, marked, after = run.stdout.partition(MAIN_MARK)
    printed = [line.strip() for line in before.splitlines() if line.strip()]
    at_import = printed.count(GREETING)
    called = [line.strip() for line in after.splitlines()].count(GREETING)
    guard = _guard_problem(project / SCRIPT)
    if not marked:
        observed = (f"importing minimalist_package.minimalist_script printed {at_import} 'Howdy!' line(s) and never "
                    "returned: the loop runs at import, not in main()" if at_import else
                    f"importing minimalist_package.minimalist_script failed: {run.exception() or run.describe()}")
    elif printed:  # the lesson: importing the module "must print nothing", a banner as much as a Howdy!
        observed = (f"importing the module already printed {len(printed)} line(s) before main() was called: "
                    + "; ".join(repr(line) for line in printed[:3]))
    else:
        observed = f"main() printed {called} 'Howdy!' line(s)" + (
            "" if called else f" and {'raised: ' + run.exception() if run.traceback else 'returned'}")
    if guard:
        observed += f"; {guard}"
    s.record("main_function", bool(marked) and not printed and called > 0 and not guard, observed,
             "'import minimalist_package.minimalist_script' prints nothing; calling its main() prints Howdy! "
             "(what an installed console script does); the file ends with if __name__ == \"__main__\": followed "
             "only by main()")


def _guard_problem(script: Path) -> str:
    """What breaks the lesson's "end the file with ``if __name__ == "__main__":`` followed only by a call to
    ``main()``" (task 1), or "" when the file does so (or has no such guard, or does not parse: then ``howdy`` and
    ``main_function`` already fail). That block runs when the script is started by its path, never when a console
    script calls ``main()``: anything else in it makes the two ways of starting differ."""
    try:
        tree = ast.parse(script.read_text(encoding="utf-8"), filename=str(script))
    except (OSError, UnicodeDecodeError, SyntaxError):
        return ""
    guard = next((node for node in reversed(tree.body) if isinstance(node, ast.If)
                  and {"__main__", "__name__"} <= set(re.findall(r"\w+", ast.unparse(node.test)))), None)
    body = [ast.unparse(stmt) for stmt in guard.body] + (["else: ..."] if guard.orelse else []) if guard else []
    if guard is not None and body != ["main()"]:
        return f"its if __name__ == \"__main__\": block (line {guard.lineno}) holds {'; '.join(body)}, not only main()"
    if guard is not None and tree.body[-1] is not guard:
        return f"code follows its if __name__ == \"__main__\": block (line {tree.body[-1].lineno}): it must end the file"
    return ""


def _judge_class(s: Session, project: Path) -> None:
    """Exercise MinimalistClass in a child interpreter (class_probe.py), judge each element (class_expectations)."""
    _absolute_import(s, project / "minimalist_package" / "__init__.py")
    probe = py.run_probe(s, DATA / "class_probe.py", [], "class_probe", cwd=project, timeout=CHILD_TIMEOUT,
                         what="Importing and exercising MinimalistClass")
    if not isinstance(probe, dict):
        raise Unmet("the class probe printed something unexpected")
    failure = probe.get("import")
    if not s.record("import_class", not failure, f"the import fails: {failure}" if failure else "imported",
                    "minimalist_package/__init__.py imports MinimalistClass from _minimalist_class"):
        raise Unmet("MinimalistClass cannot be imported")
    expectations = yaml.safe_load((DATA / "class_expectations.yaml").read_text(encoding="utf-8"))
    for check_id, wanted in expectations.items():
        py.judge_values(s, check_id, probe, [tuple(row) for row in wanted["rows"]], wanted["expected"])
    hints = probe.get("hints")
    s.record("hints_docstrings", hints == [], "; ".join(hints) if isinstance(hints, list) and hints else
             "every public method has both" if hints == [] else f"inspecting the methods {py.shown(hints)}",
             "type hints on every argument and return value, and a docstring, on each public method")


def _absolute_import(s: Session, init: Path) -> None:
    """``absolute_import``: no ``from . import ...`` (a relative import) in the package's __init__.py."""
    expected = "from minimalist_package._minimalist_class import MinimalistClass (the package's full name)"
    try:
        tree = ast.parse(init.read_text(encoding="utf-8"), filename=str(init))
    except (OSError, UnicodeDecodeError, SyntaxError) as exc:
        s.record("absolute_import", False, f"__init__.py cannot be read as Python: {exc}", expected)
        return
    relative = [f"line {node.lineno}: from {'.' * node.level}{node.module or ''} import "
                + ", ".join(alias.name for alias in node.names)
                for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.level > 0]
    s.record("absolute_import", not relative, "relative import(s) in __init__.py: " + "; ".join(relative)
             if relative else "__init__.py has no relative import", expected)


def _judge_tests(s: Session, project: Path) -> None:
    """Run the learner's suite as the lesson says, then against each broken class of mutants.yaml."""
    py.unit_tests(s, "unit_tests_pass", project, timeout=CHILD_TIMEOUT)
    s.require("unit_tests_pass")
    mutants = yaml.safe_load((DATA / "mutants.yaml").read_text(encoding="utf-8"))
    py.mutants_caught(s, "tests_catch_bugs", DATA / "mutant_driver.py", mutants, project, timeout=CHILD_TIMEOUT)
