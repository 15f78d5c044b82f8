"""Kit steps that grade a learner's own tests: run them against the course's reference and its mutants.

A lesson on testing (issue 20: ``colcon test``, pytest, ``launch_testing``) is graded the
way mutation testing grades any test suite: the learner's tests must **pass** on a correct
package (the course's reference) and **fail** on each hidden wrong one (a *mutant*: the
reference with one declared edit). Each mutant is a check of its own, so the feedback names
the bugs the tests let through.

How a run is made, and why:

* :func:`prepare_cases` copies, as the grader, the reference package once per case
  (``reference`` and each mutant, the edit applied) into a folder the submission then owns
  (:meth:`Session.submission_folder`), and the learner's ``test/`` folder into each
  copy: never a symbolic link, FIFO or device (``ros2course.sandbox.copy_logs``), so a link
  planted in ``test/`` cannot make the grader copy a file only it may read.
* :func:`run_tests` runs ``python -m pytest test`` in a copy, as ``colcon test`` runs an
  ``ament_python`` package's tests (colcon-core ``task/python/test/pytest.py``: pytest in the
  package folder, with the workspace's environment), as the submission, within a deadline.
  The copy is put first on ``PYTHONPATH``: an ``import`` of the package, and the console
  script a ``launch_testing`` test starts (its entry point is loaded by import), load the
  case's modules, not the learner's installed ones. So no case needs a ``colcon build``
  (10 s each on a loaded 2-core machine): the learner's built workspace provides the
  ament index entry and the executable, the case provides the code.
* The verdict is pytest's exit status (0 all passed, 1 some failed, 5 none collected:
  pytest's ``ExitCode``), with the short summary's ``FAILED``/``ERROR`` lines as what was
  observed. Nothing the submission wrote is read back.
"""

from __future__ import annotations

import dataclasses
import os
import re
import shutil
import stat
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from ros2course import sandbox
from ros2course.kit.session_protocol import Session
from ros2course.kit.packaging import colcon_python
from ros2course.run.probes import wait_until

#: pytest's exit statuses (``pytest.ExitCode``), in words for feedback.
_EXIT_WORDS = {0: "all passed", 1: "some failed", 2: "interrupted", 3: "pytest's internal error",
               4: "a usage error (bad arguments or a conftest.py that does not import)", 5: "no tests were collected"}
#: The counts in pytest's last line (``2 failed, 7 passed in 0.12s``).
_COUNT = re.compile(r"(\d+) (passed|failed|errors?|skipped|xfailed|xpassed|deselected)\b")
#: The short test summary's lines for failed tests (``-rfE``), naming a test file (not unittest's own
#: ``FAILED (failures=1)``, which a launch test's captured output holds).
_FAILED = re.compile(r"^(FAILED|ERROR) (\S+\.py\b\S*)(?: - (.*))?$", re.MULTILINE)
#: An exception line of a failure's traceback (``AssertionError: Lists differ: ...``): pytest prefixes
#: it with ``E``; a ``launch_testing`` test's unittest report does not, and its short summary line
#: says only ``(failures=1)``, so these lines are what tells the learner why.
_ERROR_LINE = re.compile(r"^(?:E +)?([A-Za-z_][\w.]*(?:Error|Exception)(?:: .*)?)$", re.MULTILINE)
#: Bytes of a learner's ``test/`` folder copied into each case (a test suite is kilobytes).
TESTS_CAP = 2_000_000


@dataclasses.dataclass(frozen=True)
class DeclaredMutant:
    """A hidden wrong version of a reference package, by the course's author: the learner's tests must fail on it.

    Declared by hand, with the words of its feedback, unlike the mutants ``dev mutate``
    generates to measure a grader (:class:`ros2course.dev.mutants.Mutant`, universalmutator's):
    two tools of one method, mutation analysis, with one name each.

    Attributes:
        check: the id of the check it grades (``catches_doubled_sum``), one check per mutant.
        package: the ROS package it changes (its folder name under the reference ``src/``).
        file: the file it changes, relative to the package folder.
        replace: text of the reference file to replace (must occur exactly once).
        with_: what replaces it.
        what: the wrong package in words, for feedback (``a library whose function returns (a + b) * 2``).
        hint: how a test would catch it (shown when the tests let it through).
    """

    check: str
    package: str
    file: str
    replace: str
    with_: str
    what: str
    hint: str

    def apply(self, package_folder: Path) -> None:
        """Make the edit in a copy of the reference package.

        Raises:
            ValueError: ``replace`` does not occur exactly once (the course's mutant no longer
                matches its reference: a course bug, never the learner's).
        """
        path = package_folder / self.file
        text = path.read_text(encoding="utf-8")
        if text.count(self.replace) != 1:
            raise ValueError(f"mutant {self.check}: {self.replace!r} occurs {text.count(self.replace)} times "
                             f"in the reference's {self.package}/{self.file}, not once")
        path.write_text(text.replace(self.replace, self.with_), encoding="utf-8")


@dataclasses.dataclass(frozen=True)
class TestRun:
    """What one run of a learner's tests did (:func:`run_tests`).

    Attributes:
        returncode: pytest's exit status (None: still running at the deadline, stopped).
        counts: ``{"passed": 7, "failed": 2, ...}`` from pytest's last line.
        failed: ``"test/test_x.py::test_y - AssertionError: ..."`` per failed or erroring test.
        errors: the distinct exception lines of the failures' tracebacks, in order.
        tail: the last lines of its output (for a run that did not get as far as a summary).
        seconds: wall time.
        timeout: the deadline it ran under, in seconds.
    """

    returncode: int | None
    counts: dict[str, int]
    failed: tuple[str, ...]
    errors: tuple[str, ...]
    tail: str
    seconds: float
    timeout: float

    @property
    def passed(self) -> bool:
        """Every collected test passed (pytest exit status 0)."""
        return self.returncode == 0

    @property
    def caught(self) -> bool:
        """At least one test failed or errored (exit status 1), the verdict a mutant must get."""
        return self.returncode == 1

    def summary(self) -> str:
        """One phrase: ``2 failed, 7 passed in 1.3 s``, or how the run ended without a summary."""
        if self.returncode is None:
            return f"still running after {self.timeout:.0f} s (stopped): a test that waits for ever?"
        counted = ", ".join(f"{n} {word}" for word, n in self.counts.items())
        if self.returncode in (0, 1) and counted:
            return f"{counted} in {self.seconds:.1f} s"
        words = _EXIT_WORDS.get(self.returncode, f"exit status {self.returncode}")
        return f"pytest ended with {words}" + (f" ({counted})" if counted else "") + (
            f"; its last line: {self.tail.splitlines()[-1][:160]!r}" if self.tail.strip() and self.returncode > 1 else "")

    def failures(self, limit: int = 3) -> str:
        """The first ``limit`` failed tests with their messages, ``; ``-separated ("" if none), then the
        exception lines their summaries left out (a launch test's summary says only ``(failures=1)``)."""
        shown = [f[:200] for f in self.failed[:limit]]
        text = "; ".join(shown) + (f"; and {len(self.failed) - limit} more" if len(self.failed) > limit else "")
        unsaid = [e[:200] for e in self.errors if e not in text][:limit]
        return "; ".join([text, *unsaid]) if text and unsaid else text or "; ".join(unsaid)


def learner_tests(s: Session, package: str) -> Path | None:
    """The learner's ``src/<package>/test`` folder, or None when there is none, or it (or its package
    folder) is a symbolic link (the grader copies what it holds: it must be the learner's own files)."""
    folder = s.workspace_root / "src"
    for part in (package, "test"):
        folder = folder / part
        try:
            if not stat.S_ISDIR(os.lstat(folder).st_mode):
                return None
        except OSError:
            return None
    return folder


def prepare_cases(s: Session, packages: Sequence[str], mutants: Sequence[DeclaredMutant]) -> dict[str, Path]:
    """Copies of the reference packages holding the learner's tests: ``{case: folder}``.

    ``folder/<package>`` is a package folder (the reference's files, its own ``test/``
    replaced by the learner's); cases are ``"reference"`` and each mutant's check id
    (only its own package is copied, edited).

    Args:
        packages: the packages whose tests are run, each declared in the lesson's ``references:``
            (their sources come from :meth:`Session.reference_package`).

    Raises:
        ValueError: a mutant does not apply to its reference (a course bug).
        CourseError: a package is not among the lesson's ``references`` (a course bug).
    """
    sources = {package: s.reference_package(package) for package in dict.fromkeys([*packages,
                                                                                   *(m.package for m in mutants)])}

    def copy(case_folder: Path, package: str, mutant: DeclaredMutant | None) -> None:
        target = case_folder / package
        shutil.copytree(sources[package], target, ignore=shutil.ignore_patterns("test", "__pycache__",
                                                                               "*.egg-info"))
        if mutant is not None:
            mutant.apply(target)
        tests = learner_tests(s, package)
        if tests is not None:
            sandbox.copy_logs(tests, target / "test", cap=TESTS_CAP)

    def fill(root: Path) -> None:
        for package in packages:
            copy(root / "reference", package, None)
        for mutant in mutants:
            copy(root / mutant.check, mutant.package, mutant)

    root = s.submission_folder("test-cases", fill)
    return {"reference": root / "reference", **{m.check: root / m.check for m in mutants}}


def run_tests(s: Session, package_folder: Path, label: str, *, env: dict[str, str],
              timeout: float) -> TestRun:
    """Run ``python -m pytest test`` in ``package_folder`` as ``colcon test`` would, as the submission.

    Args:
        package_folder: a case's copy of a package (:func:`prepare_cases`).
        label: log file name (``<label>.stdout.log`` in the check's log folder).
        env: the environment (the learner's sourced workspace; a private ROS domain for tests
            that launch nodes); the case's folder is put first on ``PYTHONPATH``.
        timeout: seconds before the run is stopped (a test that waits for ever).
    """
    run_env = dict(env)
    run_env["PYTHONPATH"] = os.pathsep.join(p for p in (str(package_folder), env.get("PYTHONPATH", "")) if p)
    run_env["PYTHONDONTWRITEBYTECODE"] = "1"
    run_env["COLUMNS"] = "200"  # pytest cuts its short summary's lines to the terminal's width (80 in a pipe)
    argv = [colcon_python(s), "-m", "pytest", "-p", "no:cacheprovider", "-q", "-rfE", "--color=no", "test"]
    proc = s.start_program(argv, label, env=run_env, cwd=package_folder, deadline=timeout + 10.0)
    begin = time.monotonic()
    with s.phase("tests"):
        finished = wait_until(lambda: proc.poll() is not None, timeout, interval=0.05)
    seconds = time.monotonic() - begin
    report = proc.stop(sigint_timeout=1.0, sigterm_timeout=2.0)
    out = proc.stdout()
    last = [line for line in out.splitlines() if line.strip()][-1:] or [""]
    counts = {word.rstrip("s") if word.startswith("error") else word: int(n) for n, word in _COUNT.findall(last[0])}
    failed = tuple(f"{m.group(2)}" + (f" - {m.group(3)}" if m.group(3) else "") for m in _FAILED.finditer(out))
    errors = tuple(dict.fromkeys(m.group(1).strip() for m in _ERROR_LINE.finditer(out)))
    tail = "\n".join(out.splitlines()[-6:] + proc.stderr().splitlines()[-4:])
    return TestRun(report.returncode if finished else None, counts, failed, errors, tail, seconds, timeout)


def judge_reference(s: Session, check_id: str, run: TestRun, where: str, expected: str) -> bool:
    """Record ``check_id``: the learner's tests (in ``where``, e.g. ``src/pkg/test``) passed on the reference."""
    observed = f"on the course's reference, your tests in {where}: {run.summary()}"
    if run.failed:
        observed += f"; {run.failures()}"
    elif not run.passed and run.returncode is not None and run.returncode > 1:
        observed += f"; output: {run.tail[-400:]!r}"
    s.record(check_id, run.passed, observed, expected)
    return run.passed


def judge_mutant(s: Session, mutant: DeclaredMutant, run: TestRun) -> bool:
    """Record ``mutant.check``: the learner's tests failed on the mutant (it was *caught*)."""
    if run.caught:
        observed = f"your tests failed on it, as they should: {run.summary()}" + (
            f" ({run.failures(1)})" if run.failed else "")
    elif run.passed:
        observed = f"your tests passed on it ({run.summary()}): this bug would go unnoticed"
    else:
        observed = f"your tests did not fail on it: {run.summary()}"
    s.record(mutant.check, run.caught, observed, f"at least one of your tests fails on {mutant.what}",
             None if run.caught else mutant.hint)
    return run.caught


def run_cases(s: Session, jobs: Sequence[Callable[[], None]], workers: int = 2) -> None:
    """Run independent case jobs (each calls :func:`run_tests` and records its check), ``workers`` at once.

    Runs are learner programs in their own process groups: two at a time keeps a 2-core
    machine responsive for the tests' own timing. A grader fault in a job is raised here.
    """
    import concurrent.futures  # noqa: PLC0415 - only the cases that run at once need threads

    with concurrent.futures.ThreadPoolExecutor(max_workers=workers, thread_name_prefix="ros2course-tests") as pool:
        for done in [pool.submit(job) for job in jobs]:
            done.result()
