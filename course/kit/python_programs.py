"""Kit steps that run a learner's plain Python code (no ROS) in a child interpreter.

A lesson's probe program (a file under ``graders/data/<lesson>/``, never an
inline string) imports the learner's module in a child of the grader's own
interpreter, exercises it and prints one JSON object as its last line of
stdout; the grader judges that object. The child runs through
:func:`ros2course.kit.programs.run_program` (own process group, deadline, capped
output), so a learner's infinite loop or ``sys.exit()`` cannot hang or end
the grader.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import sys
from collections.abc import Mapping
from pathlib import Path

from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course.kit.programs import ProgramRun, last_line, run_program

#: Variables that would make a child interpreter import something other than what the learner wrote
#: (the ROS overlay's PYTHONPATH, an activated venv, a startup file).
_FOREIGN = ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME", "PYTHONSTARTUP")


def python_env(s: Session, **extra: str) -> dict[str, str]:
    """The grading environment for a plain-Python child: the course's Python first on PATH, no foreign imports.

    ``env python3`` (a learner's shebang) then finds the course's interpreter; output
    is unbuffered, so what a child printed is kept even if it must be killed, and no
    ``__pycache__`` folder is written into the learner's project.

    Args:
        extra: more variables (e.g. ``PIP_NO_INDEX="1"``), added last.
    """
    env = {k: v for k, v in s.base_env.items() if k not in _FOREIGN}
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    env.update(PYTHONUNBUFFERED="1", PYTHONDONTWRITEBYTECODE="1", **extra)
    return env


def stand_in_env(s: Session, name: str, files: Mapping[str, str | Path]) -> dict[str, str]:
    """The sourced workspace's environment (``s.overlay()``) with a stand-in Python library first on PYTHONPATH.

    For a requirement "use this library" whose output is the same without it (graders/README, "a stand-in
    of what the learner must use"): run the learner's program again in this environment and judge that
    it prints the stand-in's values. ``files`` maps a path relative to the folder put on PYTHONPATH
    (``"marinholab/nottf2/__init__.py"``) to its text, or to a file (a :class:`~pathlib.Path`) copied
    there. The folder is ``s.submission_folder(name)``, so ``grade``'s isolation lets the submission read it.
    """
    def fill(folder: Path) -> None:
        for rel, content in files.items():
            target = folder / rel
            target.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, Path):
                shutil.copyfile(content, target)
            else:
                target.write_text(content, encoding="utf-8")

    stand_in = s.submission_folder(name, fill)
    env = s.overlay()
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(stand_in), env.get("PYTHONPATH", "")) if p)
    return env


def json_output(run: ProgramRun, what: str) -> object:
    """The JSON value a child printed as its last line of stdout.

    Args:
        what: the action, for the message (e.g. "Importing and exercising MinimalistClass").

    Raises:
        Unmet: it printed none (it crashed, timed out, or the learner's code ended the interpreter);
            the message quotes the traceback's or stderr's last line.
    """
    try:
        return json.loads(last_line(run.stdout))
    except ValueError:
        detail = run.exception() or last_line(run.stderr) or run.describe()
        raise Unmet(f"{what} did not finish: {detail}") from None


def run_probe(s: Session, probe: Path, args: list[str], label: str, *, cwd: Path, what: str,
              timeout: float = 30.0, env: dict[str, str] | None = None) -> object:
    """Run ``python <probe> <args...>`` in ``cwd`` and return the JSON value it printed last.

    Args:
        probe: the probe program (a file under ``graders/data/``).
        timeout: seconds before the child is stopped (generous: interpreters start slowly under load).
        env: default :func:`python_env`.

    Raises:
        Unmet: as :func:`json_output`.
    """
    run = run_program(s, [sys.executable, str(probe), *args], label, timeout=timeout,
                      env=python_env(s) if env is None else env, cwd=cwd)
    return json_output(run, what)


def shebang(s: Session, check_id: str, script: Path, wanted: str = "#!/usr/bin/env python3") -> bool:
    """Record ``check_id``: the first line of ``script`` is exactly ``wanted`` (LF line endings).

    The rule is the tutorial's (ch. 2.4): ``#!/usr/bin/env python3`` runs the first
    ``python3`` on PATH, so an activated venv's interpreter; a fixed ``/usr/bin/python3``
    ignores the venv, and a CRLF line makes the kernel look for ``python3\\r``.
    """
    first = script.read_bytes().split(b"\n", 1)[0].decode("utf-8", errors="replace")
    hint = None
    if first.startswith("#!") and "python" in first and "env" not in first:
        hint = (f"a fixed path such as {first.strip()} runs the system's Python and ignores your venv; "
                f"{wanted} runs the first python3 on PATH (the venv's, when it is active)")
    elif first.endswith("\r"):
        hint = "the file has Windows line endings (CRLF); save it with LF line endings"
    return s.record(check_id, first.rstrip() == wanted and not first.endswith("\r"),
                    f"first line: {first!r}" if first.strip() else "the first line is empty",
                    f"exactly {wanted!r} as the first line", hint=hint)


def executable_bit(s: Session, check_id: str, script: Path) -> bool:
    """Record ``check_id``: the learner may execute ``script`` (``chmod +x``; ``./script`` says "Permission denied"
    otherwise)."""
    ok = os.access(script, os.X_OK)
    return s.record(check_id, ok, f"permissions {script.stat().st_mode & 0o777:o}"
                    + ("" if ok else f" (no x: ./{script.name} says 'Permission denied')"),
                    "executable by you (chmod +x)")


def shown(value: object) -> str:
    """A value a probe sent, for feedback: its repr as sent, or ``raises <error>``."""
    if isinstance(value, dict) and "error" in value:
        return f"raises {value['error']}"
    return str(value)


def matches(sent: object, wanted: object) -> bool:
    """Whether a repr a probe sent stands for ``wanted`` (floats compared to 1e-9, anything else by repr)."""
    if isinstance(wanted, float):
        try:
            return isinstance(sent, str) and abs(float(sent) - wanted) < 1e-9
        except ValueError:
            return False
    return sent == repr(wanted)


def judge_values(s: Session, check_id: str, sent: dict, rows: list[tuple[str, str, object]],
                 expected: str) -> bool:
    """Record ``check_id``: every value a probe sent is the one wanted.

    Args:
        sent: the probe's JSON object (key -> repr, or ``{"error": ...}``).
        rows: ``(expression shown to the learner, key in sent, wanted value)``.
    """
    ok = all(matches(sent.get(key), wanted) for _, key, wanted in rows)
    return s.record(check_id, ok, "; ".join(f"{text}: {shown(sent.get(key))}" for text, key, _ in rows), expected)


def unit_tests(s: Session, check_id: str, cwd: Path, *, timeout: float = 30.0) -> ProgramRun:
    """Run ``python -m unittest discover -v test`` in ``cwd`` (as the tutorial does, ch. 2.3) and record ``check_id``.

    Passes with at least one test run and exit code 0; the observed text names the
    failing tests and the last error line.
    """
    run = run_program(s, [sys.executable, "-m", "unittest", "discover", "-v", "test"], "unittest",
                      timeout=timeout, env=python_env(s), cwd=cwd)
    ran = re.findall(r"^Ran (\d+) tests? in", run.stderr, flags=re.MULTILINE)
    count = int(ran[-1]) if ran else 0
    failing = sorted(set(re.findall(r"^(?:FAIL|ERROR): (\S+)", run.stderr, flags=re.MULTILINE)))
    errors = re.findall(r"^(\w*(?:Error|Exception): .*)$", run.stderr, flags=re.MULTILINE)
    observed = (f"ran {count} test(s), exit code {run.returncode}: {last_line(run.stderr) or run.describe()}"
                + (f" (failing: {', '.join(failing[:5])})" if failing else "")
                + (f"; last error: {errors[-1].strip()}" if errors else ""))
    s.record(check_id, run.returncode == 0 and count > 0 and not run.timed_out, observed,
             "at least one test, all passing (OK, exit code 0)",
             hint="no tests were found: name the file test_*.py and the methods test_*" if count == 0 else None)
    return run


def mutants_caught(s: Session, check_id: str, driver: Path, mutants: list[dict], cwd: Path, *,
                   timeout: float = 30.0) -> bool:
    """Record ``check_id``: the learner's test suite fails for each broken version of their code (mutation testing).

    A suite that calls the code but asserts nothing passes on any of them. Partial
    credit: the share of broken versions caught.

    Args:
        driver: the lesson's mutation driver (graders/data/<lesson>/): argv[1] a JSON list of patches; it
            prints a JSON list ``[tests run, passed?(, error)]`` for the unbroken suite, then one per patch.
        mutants: ``{"name": what is broken, as the learner reads it, "patch": Python statements}`` each.

    Raises:
        Unmet: the driver printed nothing usable, or the suite fails even unbroken under unittest's own loader
            (``check_id`` is recorded failed first).
    """
    verdicts = run_probe(s, driver, [json.dumps([m["patch"] for m in mutants])], "unittest_broken_code", cwd=cwd,
                         timeout=timeout, what="Running your tests against broken versions of your code")
    if not isinstance(verdicts, list) or len(verdicts) != len(mutants) + 1:
        raise Unmet("the runs against broken code printed something unexpected")
    control, *broken = verdicts
    if not (control[0] > 0 and control[1]):
        s.record(check_id, False, "your tests do not pass when loaded with unittest's own test loader "
                 f"from {cwd.name}: {control[2] if len(control) > 2 else 'some test fails'}",
                 "the suite passes unchanged, then fails for each broken version")
        raise Unmet("the suite does not pass under unittest's own loader")
    missed = [mutant["name"] for mutant, (_, passed, *_) in zip(mutants, broken) if passed]
    caught = len(mutants) - len(missed)
    return s.record(check_id, not missed, f"your tests failed (caught the bug) for {caught} of {len(mutants)} "
                    "broken versions" + ("; they still passed when " + "; when ".join(missed) if missed else ""),
                    f"every one of the {len(mutants)} broken versions makes at least one test fail",
                    fraction=caught / len(mutants))
