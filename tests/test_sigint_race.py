"""kit.nodes.sigint_exit: a Ctrl+C that hits rclpy's own shutdown race judges a fresh run, not the program.

rclpy (Jazzy 7.1) can raise ``RCLError: failed to initialize wait set: the
given context is not valid`` from inside its executor when SIGINT lands while
it builds a wait set. The reference node (which catches KeyboardInterrupt and
ExternalShutdownException) and a node that catches only KeyboardInterrupt end
the same way in that run, so that exit cannot be a verdict: in CI it once gave
sas-robot-driver's ``client-traceback-on-ctrl-c`` wrong solution full marks.
These tests drive the step with stand-in processes (no ROS): what each run
printed is given, the verdict is the step's.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from ros2course.grade.session import GradingSession
from ros2course.kit import Check
from ros2course.kit.nodes import ctrl_c_once_it_logs, sigint_exit
from ros2course.kit.programs import ProgramRun
from ros2course.run.process import ExitReport

RACE = """Traceback (most recent call last):
  File "/x/joint_interface_example.py", line 40, in main
    rclpy.spin_once(node, timeout_sec=0.0)
  File "/x/site-packages/rclpy/executors.py", line 740, in _wait_for_ready_callbacks
    wait_set = _rclpy.WaitSet(
rclpy._rclpy_pybind11.RCLError: failed to initialize wait set: the given context is not valid, at ./src/rcl/wait.c:82
"""
SHUTDOWN = """Traceback (most recent call last):
  File "/x/joint_interface_example.py", line 40, in main
    rclpy.spin_once(node, timeout_sec=0.0)
  File "/x/site-packages/rclpy/executors.py", line 712, in _wait_for_ready_callbacks
    raise ExternalShutdownException()
rclpy.executors.ExternalShutdownException
"""


class StandInProcess:
    """A process that exits on its first interrupt with ``returncode`` and ``traceback``."""

    def __init__(self, returncode: int, traceback: str = "") -> None:
        self.returncode, self.traceback = returncode, traceback
        self.running = True
        self.interrupts = 0

    def poll(self):
        return None if self.running else self.returncode

    def interrupt(self) -> bool:
        self.interrupts += 1
        self.running = False
        return True

    def wait_idle(self) -> bool:
        """Its main thread waits at once (the stand-in has none)."""
        return True

    def stop(self, sigint_timeout: float = 5.0, sigterm_timeout: float = 2.0) -> ExitReport:
        return ExitReport(self.returncode, None, 0.0, self.traceback)


@pytest.fixture
def s(tmp_path):
    return GradingSession(None, [Check("sigint_exit", "Ctrl+C", 1)], tmp_path, tmp_path / "log", {})


def test_the_race_then_a_shutdown_traceback_fails(s):
    """Only KeyboardInterrupt caught: the second run shows ExternalShutdownException, so the check fails."""
    fresh = StandInProcess(1, SHUTDOWN)
    assert not sigint_exit(s, "sigint_exit", StandInProcess(1, RACE), again=lambda: fresh)
    result = s.results["sigint_exit"]
    assert not result.passed and fresh.interrupts == 1
    assert "ExternalShutdownException" in result.observed and "a second run" in result.observed, result.observed


def test_the_race_then_a_clean_exit_passes(s):
    """The reference: its second run ends with exit code 0."""
    assert sigint_exit(s, "sigint_exit", StandInProcess(1, RACE), again=lambda: StandInProcess(0))
    result = s.results["sigint_exit"]
    assert result.passed and "exit code 0" in result.observed and "a second run" in result.observed


def test_the_race_twice_or_without_a_second_run_counts_as_clean(s):
    """No way to start it again, or the race again and then a clean run: rclpy's race is not the learner's."""
    assert sigint_exit(s, "sigint_exit", StandInProcess(1, RACE))
    assert "shutdown race" in s.results["sigint_exit"].observed
    runs = iter([StandInProcess(1, RACE), StandInProcess(0)])
    assert sigint_exit(s, "sigint_exit", StandInProcess(1, RACE), again=lambda: next(runs))
    assert sigint_exit(s, "sigint_exit", StandInProcess(1, RACE), again=lambda: None)


def test_the_race_then_a_fresh_run_that_exits_before_it_is_ready_fails(s):
    """CI of stop 68: gazebo-custom-nodes' ``thrust-ctrl-c-uncaught`` (a main that catches nothing) got full marks
    through ``check`` when its Ctrl+C hit the race and the fresh run ended before its node appeared, which
    counted the race as clean. The fresh run is judged whatever its state: it did not keep running."""
    fresh = StandInProcess(1, SHUTDOWN)
    fresh.running = False
    assert not sigint_exit(s, "sigint_exit", StandInProcess(1, RACE), again=lambda: fresh)
    result = s.results["sigint_exit"]
    assert not result.passed and fresh.interrupts == 0, result.observed
    assert "already exited (code 1) before SIGINT: rclpy.executors.ExternalShutdownException" in result.observed
    assert "a second run" in result.observed and "keep running" in result.hint


def test_the_same_race_in_every_run_is_the_programs(s):
    """main() called twice (at import, then by the entry point): the second main() spins rclpy's global executor,
    still bound to the context Ctrl+C shut down, and raises the race's very RCLError on every run (sas held-out
    seed 28 passed this way). Three runs in a row with it fail; a fourth is never started."""
    started = []

    def again():
        started.append(1)
        return StandInProcess(1, RACE)

    assert not sigint_exit(s, "sigint_exit", StandInProcess(1, RACE), again=again)
    result = s.results["sigint_exit"]
    assert len(started) == 2 and "3 runs in a row" in result.observed, result.observed
    assert "says nothing about your code" not in result.observed, result.observed
    assert "main() called twice" in result.hint, result.hint


def test_no_second_run_without_the_race(s):
    """A plain traceback is judged at once; the fresh instance is never started."""
    started = []
    assert not sigint_exit(s, "sigint_exit", StandInProcess(1, SHUTDOWN), again=lambda: started.append(1))
    assert not started and "a second run" not in s.results["sigint_exit"].observed


class RestartingProcess(StandInProcess):
    """A program whose node starts again after Ctrl+C (main() called twice): only the second press ends it."""

    def interrupt(self) -> bool:
        self.interrupts += 1
        self.running = self.interrupts < 2
        return True


def test_a_program_that_starts_again_after_ctrl_c_fails_on_its_one_press_run(s):
    """sas held-out seed 24: ``if __name__ != '__main__': main()`` ran main twice; the kit's second Ctrl+C (its
    allowance for rclpy missing the first) ended the restarted node and it passed. With a fresh run, one press."""
    fresh = RestartingProcess(0)
    assert not sigint_exit(s, "sigint_exit", RestartingProcess(0), sigint_timeout=0.2, again=lambda: fresh)
    result = s.results["sigint_exit"]
    assert fresh.interrupts == 1 and "sent once" in result.observed and "a second run" in result.observed
    assert "main() called twice" in result.hint


def test_a_missed_first_press_then_a_clean_run_passes(s):
    """rclpy missed the first Ctrl+C (about 1 %): the fresh run ends on its one press and the check passes;
    without a way to run it again the second press counts, as a user would press it."""
    assert sigint_exit(s, "sigint_exit", RestartingProcess(0), sigint_timeout=0.2, again=lambda: StandInProcess(0))
    assert "a second run" in s.results["sigint_exit"].observed
    assert sigint_exit(s, "sigint_exit", RestartingProcess(0), sigint_timeout=0.2)
    assert "second Ctrl+C" in s.results["sigint_exit"].observed


def _script_run(returncode: int, traceback: str) -> ProgramRun:
    return ProgramRun(returncode, "", traceback, False, 1.0, traceback, interrupted=True, interrupted_at=3.0)


def test_a_script_whose_node_printed_the_race_and_exited_0_passes(s):
    """A bash script (ros2 run / ros2 launch inside it) cannot be run again without its nodes' first run: a node's
    race printed while the script itself exits 0 with nothing left running counts as clean
    (kit.programs.judge_interrupted_run, which launch-and-run used to decide by itself)."""
    assert sigint_exit(s, "sigint_exit", _script_run(0, RACE))
    assert "shutdown race" in s.results["sigint_exit"].observed


def test_a_script_run_with_another_traceback_or_exit_code_fails(s):
    assert not sigint_exit(s, "sigint_exit", _script_run(0, SHUTDOWN))
    assert "ExternalShutdownException" in s.results["sigint_exit"].observed
    assert not sigint_exit(s, "sigint_exit", _script_run(1, RACE))


class StandInRosout:
    """/rosout as a list of records of one logger: each launch writes its 'waiting' record."""

    def __init__(self) -> None:
        self.count = 0

    def records(self, node=None):
        return [object()] * self.count


class LoggingSession(GradingSession):
    """A grading session whose graph is a stand-in: only ``rosout()`` is used by the step."""

    def __init__(self, tmp_path, rosout) -> None:
        super().__init__(None, [Check("sigint_exit", "Ctrl+C", 1)], tmp_path, tmp_path / "log", {})
        self._rosout = rosout

    @property
    def graph(self):
        return SimpleNamespace(rosout=lambda: self._rosout)


def test_ctrl_c_once_it_logs_judges_a_fresh_run_started_the_same_way(tmp_path):
    """kit.ctrl_c_once_it_logs (the action client's, Gazebo's and Nav2's waiting programs): the first run's
    Ctrl+C is judged as the part ends; after rclpy's race a fresh run, started by the same launch with the
    suffix '.again' and waited for until it logs, is judged instead."""
    rosout = StandInRosout()
    runs = iter([StandInProcess(1, RACE), StandInProcess(0)])
    suffixes = []

    def launch(suffix):
        suffixes.append(suffix)
        rosout.count += 1  # it says it waits
        return next(runs)

    s = LoggingSession(tmp_path, rosout)
    with s.part("interrupted"):
        first = ctrl_c_once_it_logs(s, "sigint_exit", launch, "client", patience=1.0)
        assert suffixes == [""] and first.running
    result = s.results["sigint_exit"]
    assert suffixes == ["", ".again"] and result.passed and "a second run" in result.observed, result.observed
