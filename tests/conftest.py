"""Shared fixtures: workspaces, the reference solution, running the CLI."""

from __future__ import annotations

import contextlib
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest
from ros2course.lesson.catalog import content_root, load_catalog
from ros2course.lesson.workspace import Workspace
from ros2course.ros import env as env_mod

ROOT = content_root()
SOLUTIONS = ROOT / "solutions" / "src"

env_mod.activate_process()

#: Test modules whose tests each take a minute or more (the validation of every lesson,
#: repeated grades). They are collected early so that, with pytest-xdist's work stealing,
#: the longest tests start first and the short ones fill the gaps at the end.
LONG_MODULES = ("test_validate.py", "test_batch_ros.py", "test_benchmarks.py", "test_repeat.py", "test_wheel.py",
                "test_mutate.py", "test_second_course.py", "test_report_html.py")
#: Modules whose tests (or module fixtures) take :func:`cpu_lock`. They are collected before
#: everything else: xdist's work stealing hands the first half of the collection to one worker
#: and steals from the end of a queue, so they run one after the other on that worker instead
#: of leaving the other worker waiting for the lock (8 worker-minutes idle in a CI run).
CPU_LOCK_MODULES = ("test_batch_ros.py", "test_hostile_class.py")


@pytest.fixture(autouse=True)
def bundled_course_after_each_test():
    """Every test ends on the bundled course: a test that chose another (``use_course``, an
    in-process CLI call with ``--course``) must not hand it to the next test in this worker."""
    yield
    from ros2course.lesson import use_course

    use_course(None)


@pytest.fixture(autouse=True, scope="session")
def private_cache_dir(tmp_path_factory: pytest.TempPathFactory):
    """ros2course's cache folder (the catalog index of ``list``) under pytest's temp folder, not ~/.cache."""
    os.environ["ROS2COURSE_CACHE_DIR"] = str(tmp_path_factory.mktemp("cache"))
    yield


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The tests that take the CPU lock first, then the long ones, then the rest (stable order otherwise).

    See :data:`CPU_LOCK_MODULES` and :data:`LONG_MODULES`.
    """
    # The cases of a parametrized test keep their order: a longest-first order (tests/durations.json) made
    # the fresh-clone rehearsal of ff8114f take 57.8 min instead of 45-47 (four validations at once early in
    # the run); the durations file stays, for measuring, not for ordering.
    def rank(item: pytest.Item) -> int:
        name = item.path.name
        if name in CPU_LOCK_MODULES or "cpu_exclusive" in getattr(item, "fixturenames", ()):
            return 0
        return 1 + (LONG_MODULES.index(name) if name in LONG_MODULES else len(LONG_MODULES))

    items.sort(key=rank)


#: Seconds (setup + call) each of the slowest tests took in a recorded CI run (a record for comparing runs).
DURATIONS_FILE = Path(__file__).with_name("durations.json")
#: When set, the run writes every test's seconds there in :data:`DURATIONS_FILE`'s format (to refresh it).
DURATIONS_OUT = "ROS2COURSE_TEST_DURATIONS_OUT"


def pytest_configure(config: pytest.Config) -> None:
    """The controller makes the run's CPU lock file (see :func:`cpu_lock`); xdist workers inherit its path."""
    if not hasattr(config, "workerinput") and "ROS2COURSE_TESTS_CPU_LOCK" not in os.environ:
        import tempfile

        folder = tempfile.mkdtemp(prefix="ros2course-tests-")
        os.environ["ROS2COURSE_TESTS_CPU_LOCK"] = os.path.join(folder, "cpu.lock")
        config._ros2course_lock_folder = folder  # removed by pytest_unconfigure


class RunUsage:
    """How busy the test run kept the machine (issue 37's CI budget: 45 min on 2 cores).

    Printed at the end of the run (controller only): wall time, the test time each xdist worker
    reported (setup, call and teardown) and when it finished its last test, and the CPU's busy
    share from ``/proc/stat`` over the run. A worker finishing long before the other, or a CPU
    far from busy, says where the suite's time is lost (not a timed assert: a figure for the log).
    """

    def __init__(self) -> None:
        self.start = time.monotonic()
        self.cpu = self._cpu_ticks()
        self.busy: dict[str, float] = {}
        self.last: dict[str, float] = {}
        self.seconds: dict[str, float] = {}

    @staticmethod
    def _cpu_ticks() -> tuple[int, int] | None:
        """(all ticks, idle + iowait ticks) of ``/proc/stat``'s cpu line; None off Linux."""
        try:
            fields = [int(v) for v in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
        except (OSError, ValueError):
            return None
        return sum(fields), fields[3] + fields[4]

    def add(self, report: pytest.TestReport) -> None:
        """Count one phase report (setup, call or teardown) of one worker."""
        node = getattr(report, "node", None)
        worker = getattr(getattr(node, "gateway", None), "id", None) or "main"
        self.busy[worker] = self.busy.get(worker, 0.0) + report.duration
        self.last[worker] = time.monotonic() - self.start
        if report.when in ("setup", "call"):
            self.seconds[report.nodeid] = self.seconds.get(report.nodeid, 0.0) + report.duration

    def write_durations(self, path: str) -> None:
        """Every test's seconds (setup + call), slowest first, in :data:`DURATIONS_FILE`'s format."""
        import json

        ordered = dict(sorted(((k, round(v, 1)) for k, v in self.seconds.items()), key=lambda kv: -kv[1]))
        Path(path).write_text(json.dumps({"source": f"a test run of {time.strftime('%Y-%m-%d')}, seconds "
                                          "(setup + call)", "seconds": ordered}, indent=1) + "\n", encoding="utf-8")

    def line(self) -> str:
        """One line for the log: wall, per-worker test time and last finish, CPU busy %."""
        wall = time.monotonic() - self.start
        workers = "; ".join(f"{w}: {self.busy[w] / 60:.1f} min of tests, last ended at {self.last[w] / 60:.1f} min"
                            for w in sorted(self.busy))
        text = f"test-run usage: wall {wall / 60:.1f} min; {workers or 'no tests'}"
        now = self._cpu_ticks()
        if self.cpu is not None and now is not None and now[0] > self.cpu[0]:
            total, idle = now[0] - self.cpu[0], now[1] - self.cpu[1]
            text += f"; CPU busy {100 * (1 - idle / total):.0f} % of {os.cpu_count()} cores"
        return text


#: The run's :class:`RunUsage` (controller only), under "usage".
_USAGE: dict[str, RunUsage] = {}


def pytest_sessionstart(session: pytest.Session) -> None:
    """The controller (or a run without xdist) starts counting :class:`RunUsage`."""
    if not hasattr(session.config, "workerinput"):
        _USAGE["usage"] = RunUsage()


def pytest_runtest_logreport(report: pytest.TestReport) -> None:
    """Each phase report reaching the controller counts toward :class:`RunUsage`."""
    usage = _USAGE.get("usage")
    if usage is not None:
        usage.add(report)


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    """The run's :class:`RunUsage` line, after pytest's durations."""
    usage = _USAGE.get("usage")
    if usage is not None:
        terminalreporter.write_line(usage.line())
        if os.environ.get(DURATIONS_OUT):
            usage.write_durations(os.environ[DURATIONS_OUT])


def pytest_unconfigure(config: pytest.Config) -> None:
    """Remove the run's CPU lock folder (only the controller made one)."""
    folder = getattr(config, "_ros2course_lock_folder", None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)
        os.environ.pop("ROS2COURSE_TESTS_CPU_LOCK", None)


@contextlib.contextmanager
def cpu_lock():
    """Hold one lock shared by every xdist worker of this run (see :func:`cpu_exclusive`)."""
    import fcntl

    with open(os.environ["ROS2COURSE_TESTS_CPU_LOCK"], "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


@pytest.fixture
def cpu_exclusive():
    """Run the test under :func:`cpu_lock`.

    Tests that grade whole classes at once must not share the 2 cores with the tests
    that compile C++ (the underlay, rclcpp and sas packages, a whole
    workspace) or grade whole classes at once (a fork storm among them): a
    grader's timing verdicts are meant to hold under a normal load, not
    beside a compiler on every core. Tests (and module fixtures, through
    :func:`cpu_lock`) holding it never overlap.
    """
    with cpu_lock():
        yield


@pytest.fixture
def catalog():
    """The course's lesson catalog."""
    return load_catalog()


@pytest.fixture
def workspace(tmp_path: Path) -> Workspace:
    """A freshly initialised, empty workspace."""
    ws = Workspace(tmp_path / "ws")
    ws.init()
    return ws


@pytest.fixture
def solution_workspace(workspace: Workspace) -> Workspace:
    """An initialised workspace holding the reference python_package_with_a_node."""
    shutil.copytree(SOLUTIONS / "python_package_with_a_node", workspace.src / "python_package_with_a_node",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    return workspace


def run_cli(*args: str, cwd: Path | None = None, timeout: float = 300, env: dict | None = None
            ) -> subprocess.CompletedProcess:
    """Run ``python -m ros2course ARGS`` as a learner would run ``ros2course``; never hangs past ``timeout``."""
    return subprocess.run([sys.executable, "-m", "ros2course", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=timeout, env={**os.environ, **(env or {}), "COLUMNS": "320"},
                          stdin=subprocess.DEVNULL, check=False)


def run_cli_in_process(*args: str, cwd: Path | None = None, timeout: float = 300, env: dict | None = None
                       ) -> subprocess.CompletedProcess:
    """Run ``ros2course ARGS`` in this process with typer's ``CliRunner`` (issue 23), shaped as :func:`run_cli`'s result.

    For tests of messages, exit codes and files, where no process boundary is under test
    (signals, exit statuses of a real process and start-up time keep :func:`run_cli`).
    ``timeout`` is not enforced: such commands never start ROS nodes. ``env`` is set for
    the call only (CliRunner restores the environment), and the working directory is
    changed for the call only.
    """
    from ros2course.cli import app
    from ros2course.lesson import use_course
    from typer.testing import CliRunner

    use_course(None)  # the one per-process choice a new process starts without (the CLI makes it per command)
    before = Path.cwd()
    if cwd is not None:
        os.chdir(cwd)
    try:
        result = CliRunner().invoke(app, [str(a) for a in args], env={**(env or {}), "COLUMNS": "320"})
    finally:
        os.chdir(before)
        use_course(None)  # a --course or a workspace's record must not outlive the call into later tests
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception
    return subprocess.CompletedProcess(list(args), result.exit_code, result.stdout, result.stderr)


@pytest.fixture
def cli():
    """The :func:`run_cli` helper."""
    return run_cli

