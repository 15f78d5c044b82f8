#!/usr/bin/env python3
"""How long ``ros2course check print-forever-node`` takes, and how far above the floor.

Run from the repository root with the project's venv::

    python benchmarks/check_speed.py [--runs N] [--json]

1. A fresh temporary workspace gets the lesson's reference solution and is ``init``-ed (a learner's
   workspace: the CLI check records its attempt in progress.json).
2. Cold: build/ install/ log/ are removed, then ``grade_lesson`` is timed end
   to end (colcon build included) and split into build / start / observe /
   stop+teardown / other (``other`` = wall time minus the engine's timed phases).
3. Warm: N more ``grade_lesson`` calls on the unchanged workspace (the
   fingerprint cache should skip colcon); median and min/max per phase.
4. Floor, measured in the same run: a bare rclpy node (0.5 s timer logging
   like the lesson's node) started the way the grader starts learner nodes
   (``LearnerProcess`` in a ``RosSession``'s private domain); the median time
   from Popen to its first record arriving on /rosout, plus the grader's
   observation window ((SAMPLES - 1) * PERIOD), is the least a check can take.
5. ``python -m ros2course check ... --json`` once, warm, through the real CLI
   (interpreter start, imports, overlay sourcing included).
6. Diagnostics: interpreter start, rclpy and CLI imports, RosSession set-up in
   a fresh process, uncached overlay sourcing, console-script entry-point lookup.

Exits non-zero only when a graded result is not full marks (or the CLI run is
not); timings are reported, never asserted. The temporary workspace is removed
and every process this script started is gone when it exits, error or not.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import selectors
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from ros2course.builder import colcon as build_mod
from ros2course.errors import CourseError
from ros2course.grade.engine import grade_lesson, load_grader
from ros2course.grade.results import LessonResult, Status
from ros2course.dev.validate import reference_workspace
from ros2course.lesson.catalog import Lesson, load_catalog
from ros2course.lesson.workspace import Workspace
from ros2course.ros import env as env_mod
from ros2course.run.process import kill_marked

LESSON_ID = "print-forever-node"
#: What "warm overhead above floor" should stay under, seconds.
GOAL_SECONDS = 1.0
#: Issue 36: the check a learner types within this many seconds of the floor.
CLI_GOAL_ABOVE_FLOOR = 0.5
#: Every process this script starts inherits this variable (value: a per-run id), so
#: leftovers are found by their environment and killed by PID at the end.
BENCH_MARKER_VAR = "ROS2COURSE_BENCH_MARKER"
#: The guard of the wheels' bootstrapper (.pth re-exec); a learner's shell does not have it.
BOOTSTRAP_GUARD = "_ROS_WHEELS_BOOTSTRAP_COMPLETE"
PHASES = ("build", "start", "observe", "stop+teardown", "other", "total")
SUB_PHASES = {"stop+teardown": ("stop", "teardown")}
FLOOR_NODE_NAME = "print_forever"
FLOOR_TIMEOUT = 15.0
CLI_TIMEOUT = 300.0

FLOOR_NODE = '''\
"""Benchmark floor: the lesson's node reduced to its essentials."""
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node


class Floor(Node):
    def __init__(self):
        super().__init__({name!r})
        self.count = 0
        self.timer = self.create_timer({period!r}, self.tick)

    def tick(self):
        self.get_logger().info(f"Printed {{self.count}} times.")
        self.count += 1


def main():
    try:
        rclpy.init()
        rclpy.spin(Floor())
    except (KeyboardInterrupt, ExternalShutdownException):
        pass


if __name__ == "__main__":
    main()
'''


class BenchmarkFailed(Exception):
    """A graded result was not full marks (or a measurement could not be made)."""


# --- small helpers -------------------------------------------------------------


def _round(value: Any) -> Any:
    if isinstance(value, float):
        return round(value, 3)
    if isinstance(value, dict):
        return {k: _round(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_round(v) for v in value]
    return value


def summary(values: list[float]) -> dict[str, float]:
    """Median, min and max of ``values`` (seconds)."""
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def split(result: LessonResult, wall: float) -> dict[str, float]:
    """A check's wall time split into the engine's phases plus ``other`` (the rest)."""
    t = result.timings
    parts = {name: float(t.get(name, 0.0)) for name in ("build", "start", "observe", "stop", "teardown")}
    parts["stop+teardown"] = parts["stop"] + parts["teardown"]
    parts["other"] = wall - (parts["build"] + parts["start"] + parts["observe"] + parts["stop+teardown"])
    parts["total"] = wall
    return parts


def require_full_marks(result: LessonResult, what: str) -> None:
    if result.status != Status.PASSED or result.score < result.max_score:
        failed = "; ".join(f"{c.id}: {c.observed}" for c in result.checks if not c.passed) or "none"
        detail = f"; {result.message.splitlines()[0]}" if result.message else ""
        raise BenchmarkFailed(f"{what}: {result.status} {result.score:g}/{result.max_score:g} "
                              f"(failed: {failed}{detail})")


def learner_shell_env() -> dict[str, str]:
    """This process's environment as a learner's terminal would have it (wheels' re-exec not done yet)."""
    return learner_shell_env_from(dict(os.environ))


@dataclasses.dataclass
class Run:
    """A finished subprocess: wall seconds, and when its stdout last carried data (seconds after start)."""

    seconds: float
    returncode: int
    stdout: bytes
    stderr: bytes
    last_output: float | None


def timed_run(argv: list[str], env: dict[str, str], cwd: Path, timeout: float) -> Run:
    """Run ``argv`` in its own session, reading both pipes; its whole group is killed on timeout or error."""
    begin = time.monotonic()
    proc = subprocess.Popen(argv, env=env, cwd=cwd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True)
    out_fd, err_fd = proc.stdout.fileno(), proc.stderr.fileno()
    chunks: dict[int, bytearray] = {out_fd: bytearray(), err_fd: bytearray()}
    last_output = None
    try:
        with selectors.DefaultSelector() as selector:
            for pipe in (proc.stdout, proc.stderr):
                selector.register(pipe, selectors.EVENT_READ)
            while selector.get_map():
                remaining = begin + timeout - time.monotonic()
                if remaining <= 0:
                    raise BenchmarkFailed(f"{' '.join(argv)} still running after {timeout:.0f} s")
                for key, _ in selector.select(timeout=remaining):
                    chunk = os.read(key.fd, 65536)
                    if not chunk:
                        selector.unregister(key.fileobj)
                        continue
                    chunks[key.fd] += chunk
                    if key.fd == out_fd:
                        last_output = time.monotonic() - begin
        proc.wait(timeout=max(begin + timeout - time.monotonic(), 1.0))
    except BaseException:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise
    finally:
        proc.stdout.close()
        proc.stderr.close()
    return Run(time.monotonic() - begin, proc.returncode, bytes(chunks[out_fd]), bytes(chunks[err_fd]), last_output)


def kill_leftovers(marker: str) -> list[int]:
    """SIGKILL every process (other than this one) whose environment carries this run's marker."""
    return kill_marked(marker, BENCH_MARKER_VAR)


# --- the measurements ------------------------------------------------------------


def grade_timed(lesson: Lesson, workspace: Path) -> tuple[LessonResult, dict[str, float]]:
    begin = time.monotonic()
    result = grade_lesson(lesson, workspace)
    return result, split(result, time.monotonic() - begin)


def measure_floor(runs: int, folder: Path, period: float, progress: Console) -> dict[str, Any]:
    """Popen -> first /rosout record of a bare rclpy node, launched exactly as the grader launches nodes.

    Also records, per run, Popen -> node in the graph, SIGINT -> exit, and the
    RosSession's open/close times (what a check pays around its node).
    """
    from ros2course.run.probes import RosSession, wait_until  # noqa: PLC0415 - rclpy only when measuring
    from ros2course.run.process import LearnerProcess, rclpy_shutdown_race, sweep_stale_fastdds_shm  # noqa: PLC0415 - rclpy only when measuring

    folder.mkdir(parents=True, exist_ok=True)
    script = folder / "floor_node.py"
    script.write_text(FLOOR_NODE.format(name=FLOOR_NODE_NAME, period=period), encoding="utf-8")
    base_env = env_mod.activate()
    wanted = f"/{FLOOR_NODE_NAME}"
    rows: dict[str, list[float]] = {"first_record": [], "node_in_graph": [], "sigint_exit": [], "rclpy_shutdown_races": [],
                                    "session_open": [], "session_close": []}
    for index in range(runs):
        progress.print(f"  floor run {index + 1}/{runs}")
        opening = time.monotonic()
        session = RosSession().__enter__()
        session.node  # noqa: B018 - opens the grader's participant (RosSession opens it on first use)
        rows["session_open"].append(time.monotonic() - opening)
        try:
            probe = session.rosout()
            proc = LearnerProcess([sys.executable, str(script)], session.learner_env(base_env), folder,
                                  f"floor-{index}", cwd=folder, ros_sigint=True)
            seen: dict[str, float] = {}
            try:
                proc.start()

                def ready() -> bool:
                    if "node" not in seen and wanted in session.node_names():
                        seen["node"] = time.monotonic()
                    return "node" in seen and any(m.name == FLOOR_NODE_NAME for m in probe.messages())

                if not wait_until(ready, FLOOR_TIMEOUT, interval=0.01, abort=lambda: proc.poll() is not None):
                    raise BenchmarkFailed(f"floor node: no node and /rosout record within {FLOOR_TIMEOUT:.0f} s "
                                          f"(exit code {proc.poll()}); stderr: {proc.stderr()[-800:]}")
                arrival = next(t for t, m in probe.samples() if m.name == FLOOR_NODE_NAME)
                rows["first_record"].append(arrival - proc.started_at)
                rows["node_in_graph"].append(min(seen["node"], arrival) - proc.started_at)
            finally:
                report = proc.stop(sigint_timeout=3.0, sigterm_timeout=2.0)
            if report.signal_used == "SIGINT" and report.traceback and rclpy_shutdown_race(report.traceback):
                rows["rclpy_shutdown_races"].append(index)  # rclpy's own Ctrl+C race (ros2course.run.process.rclpy_shutdown_race): not the node's fault
            elif report.signal_used != "SIGINT" or report.returncode != 0 or report.traceback:
                raise BenchmarkFailed(f"floor node did not stop cleanly on SIGINT: {report}")
            rows["sigint_exit"].append(report.seconds)
        finally:
            closing = time.monotonic()
            session.__exit__(None, None, None)
            rows["session_close"].append(time.monotonic() - closing)
            sweep_stale_fastdds_shm()
    return rows


def measure_diagnostics(runs: int, workspace: Path, folder: Path) -> dict[str, float]:
    """Costs a warm check pays outside the node's own life, each timed on its own (medians, seconds)."""
    shell = learner_shell_env()
    python = sys.executable
    out: dict[str, float] = {}

    def median_of(argv: list[str], env: dict[str, str]) -> float:
        times = []
        for _ in range(runs):
            done = timed_run(argv, env, folder, timeout=120)
            if done.returncode != 0:
                raise BenchmarkFailed(f"{' '.join(argv)} failed ({done.returncode}): {done.stderr.decode()[-500:]}")
            times.append(done.seconds)
        return statistics.median(times)

    out["python_start_reexec"] = median_of([python, "-c", "pass"], shell)
    out["python_start_bootstrapped"] = median_of([python, "-c", "pass"], dict(os.environ))
    out["rclpy_import_bootstrapped"] = median_of(
        [python, "-c", "import rclpy, rclpy.node, rclpy.executors"], dict(os.environ)) - out["python_start_bootstrapped"]
    out["cli_help"] = median_of([python, "-m", "ros2course", "--help"], shell)

    base_env = env_mod.activate()
    times = []
    for _ in range(runs):
        # what a fresh CLI process pays when neither cache (in memory, build/.ros2course-overlay.json) holds it
        begin = time.monotonic()
        overlay = build_mod._source_overlay(workspace / "install" / "setup.bash", workspace, base_env)  # noqa: SLF001
        times.append(time.monotonic() - begin)
    out["overlay_sourcing"] = statistics.median(times)

    def self_timed(what: str, code: str, env: dict[str, str]) -> list[float]:
        """Medians of the numbers ``code`` (a fresh interpreter) prints on its last line, plus its exit lag.

        The exit lag is the time from its last output to its exit (interpreter shutdown).
        """
        rows = []
        for _ in range(runs):
            done = timed_run([python, "-c", "import time; t = time.perf_counter()\n" + code], env, folder,
                             timeout=60)
            if done.returncode != 0 or done.last_output is None:
                raise BenchmarkFailed(f"{what} failed: {done.stderr.decode()[-500:]}")
            rows.append([*map(float, done.stdout.decode().splitlines()[-1].split()), done.seconds - done.last_output])
        return [statistics.median(column) for column in zip(*rows)]

    out["cli_import"] = self_timed("import ros2course.cli", "import ros2course.cli\nprint(time.perf_counter() - t)",
                                   dict(os.environ))[0]
    # What the grader's ROS graph costs in a fresh process (``ros2course check``): imports, rclpy init,
    # node (with its type description service), executor thread; then closing it, then exiting.
    out["ros_session_open_fresh"], out["ros_session_close_fresh"], out["exit_after_ros_session"] = self_timed(
        "RosSession", "from ros2course.run.probes import RosSession\ns = RosSession().__enter__()\ns.node\n"
        "opened = time.perf_counter()\ns.__exit__(None, None, None)\n"
        "print(opened - t, time.perf_counter() - opened, flush=True)", dict(os.environ))
    out["exit_plain_python"] = self_timed("print", "print(0, flush=True)", dict(os.environ))[-1]
    # The console-script wrapper colcon installs looks the entry point up with importlib.metadata.
    out["entry_point_lookup"] = self_timed(
        "entry point lookup", "from importlib.metadata import distribution\n"
        "[e for e in distribution('python-package-with-a-node').entry_points]\n"
        "print(time.perf_counter() - t)", overlay)[0]
    from ros2course.run.process import sweep_stale_fastdds_shm  # noqa: PLC0415

    sweep_stale_fastdds_shm()
    return out


LAUNCH_TEST = '''\
"""The plainest launch_testing test a teacher would write for the lesson: the fifth print, then exit codes."""
import unittest

import launch
import launch_ros.actions
import launch_testing
import launch_testing.actions
import launch_testing.asserts
import pytest


@pytest.mark.launch_test
def generate_test_description():
    node = launch_ros.actions.Node(package="python_package_with_a_node", executable="print_forever_node",
                                   output="screen")
    return launch.LaunchDescription([node, launch_testing.actions.ReadyToTest()]), {{"node": node}}


class TestPrints(unittest.TestCase):
    def test_fifth_print(self, proc_output, node):
        proc_output.assertWaitFor("Printed {last} times.", process=node, timeout=15)


@launch_testing.post_shutdown_test()
class TestExit(unittest.TestCase):
    def test_exit_codes(self, proc_info):
        launch_testing.asserts.assertExitCodes(proc_info)
'''


def run_launch_test(runs: int, workspace: Path, folder: Path, samples: int) -> list[float]:
    """``launch_test`` of :data:`LAUNCH_TEST` (waits for the ``samples``-th print, index ``samples - 1``),
    ``runs`` times, in the workspace's overlay as a learner's sourced terminal has it; wall seconds each.

    Raises:
        BenchmarkFailed: ``launch_test`` is not installed, or a run fails.
    """
    base_env = env_mod.activate()
    overlay = build_mod.overlay_env(workspace, base_env)
    launch_test = shutil.which("launch_test", path=overlay.get("PATH"))
    if launch_test is None:
        raise BenchmarkFailed("launch_test is not on the overlay's PATH (the underlay's launch_testing)")
    test = folder / "test_print_forever.py"
    test.write_text(LAUNCH_TEST.format(last=samples - 1), encoding="utf-8")
    env = learner_shell_env_from(overlay)
    times = []
    for _ in range(runs):
        done = timed_run([launch_test, str(test)], env, folder, timeout=CLI_TIMEOUT)
        if done.returncode != 0:
            raise BenchmarkFailed(f"launch_test failed ({done.returncode}): {(done.stdout + done.stderr).decode()[-800:]}")
        times.append(done.seconds)
    return times


def learner_shell_env_from(env: dict[str, str]) -> dict[str, str]:
    """``env`` as a learner's terminal has it (the wheels' bootstrap guard removed: the interpreter re-execs)."""
    env = dict(env)
    env.pop(BOOTSTRAP_GUARD, None)
    return env


def measure_source_digest(runs: int) -> dict[str, Any]:
    """The build record's content digest of every package of the course's reference (``solutions/src``, the
    largest package set a check reads), as a warm check computes it; milliseconds, median of ``runs``."""
    from ros2course.builder.sources import scan_package  # noqa: PLC0415
    from ros2course.lesson import content_root  # noqa: PLC0415
    from ros2course.ros.manifests import find_packages  # noqa: PLC0415

    src = content_root() / "solutions" / "src"
    found = find_packages(src)
    times, files = [], 0
    for _ in range(runs):
        begin = time.perf_counter()
        files = sum(len(scan_package(src.parent, folder).files) for folder, _ in found.values())
        times.append((time.perf_counter() - begin) * 1000)
    return {"packages": len(found), "files": files, "ms": summary(times)}


def run_cli_check(workspace: Path, folder: Path) -> dict[str, Any]:
    """``python -m ros2course check LESSON --workspace WS --json`` once, as a learner's terminal would run it."""
    argv = [sys.executable, "-m", "ros2course", "check", LESSON_ID, "--workspace", str(workspace), "--json"]
    done = timed_run(argv, learner_shell_env(), folder, timeout=CLI_TIMEOUT)
    try:
        data = json.loads(done.stdout.decode())
    except ValueError:
        data = {}
    # The JSON is written and flushed once everything is judged and cleaned up; what follows is
    # interpreter shutdown (native destructors of rclpy / Fast DDS included).
    exit_after_output = done.seconds - done.last_output if done.last_output is not None else 0.0
    info = {"wall": done.seconds, "exit_after_output": exit_after_output, "exit_code": done.returncode,
            "status": data.get("status"), "score": data.get("score"), "max_score": data.get("max_score")}
    if done.returncode != 0 or data.get("status") != Status.PASSED:
        raise BenchmarkFailed(f"CLI check was not full marks: exit {done.returncode}, {info}; "
                              f"stderr: {done.stderr.decode()[-800:]}")
    return info


def benchmark(runs: int, root: Path, progress: Console) -> dict[str, Any]:
    lesson = load_catalog().get(LESSON_ID)
    grader = load_grader(lesson.grader)  # graders.print_forever_node
    samples, period = grader.SAMPLES, grader.PERIOD
    window = (samples - 1) * period
    workspace = root / "ws"
    progress.print(f"workspace: {workspace}")
    reference_workspace(lesson, workspace)
    # a learner's workspace: `ros2course init` ran (progress.json), so the CLI check records its attempt
    Workspace(workspace).init()

    progress.print("cold run (colcon build included) ...")
    for name in ("build", "install", "log"):
        shutil.rmtree(workspace / name, ignore_errors=True)
    cold_result, cold = grade_timed(lesson, workspace)
    require_full_marks(cold_result, "cold run")
    if cold_result.build.get("cached"):
        raise BenchmarkFailed("cold run: the build was reported cached after build/ install/ log/ were removed")

    warm_runs: list[dict[str, float]] = []
    uncached = 0
    for index in range(runs):
        progress.print(f"warm run {index + 1}/{runs} ...")
        result, parts = grade_timed(lesson, workspace)
        require_full_marks(result, f"warm run {index + 1}")
        uncached += not result.build.get("cached")
        warm_runs.append(parts)
    warm = {name: summary([r[name] for r in warm_runs]) for name in (*PHASES, "stop", "teardown")}

    progress.print("floor: bare rclpy node, Popen -> first /rosout record ...")
    floor_rows = measure_floor(runs, root / "floor", period, progress)
    first_record = statistics.median(floor_rows["first_record"])
    floor = first_record + window

    progress.print("ros2course check through the CLI (warm) and the plainest launch_test, in turn ...")
    cli_runs, launch_runs = [], []
    for _ in range(runs):
        cli_runs.append(run_cli_check(workspace, root / "floor"))
        launch_runs.extend(run_launch_test(1, workspace, root / "floor", samples))
    cli = dict(cli_runs[len(cli_runs) // 2])
    cli["wall"] = statistics.median(run["wall"] for run in cli_runs)
    cli["exit_after_output"] = statistics.median(run["exit_after_output"] for run in cli_runs)
    cli["runs"] = [run["wall"] for run in cli_runs]

    progress.print("diagnostics (interpreter start, imports, overlay sourcing) ...")
    diagnostics = measure_diagnostics(runs, workspace, root / "floor")
    diagnostics.update({f"floor_{k}": statistics.median(v) for k, v in floor_rows.items()
                        if k not in ("first_record", "rclpy_shutdown_races")})

    return {
        "lesson": LESSON_ID,
        "runs": runs,
        "cold": {**cold, "status": cold_result.status, "score": cold_result.score,
                 "max_score": cold_result.max_score, "build_cached": bool(cold_result.build.get("cached"))},
        "warm": warm,
        "warm_runs": warm_runs,
        "warm_builds_not_cached": uncached,
        "floor": {"first_record_median": first_record, "first_record_runs": floor_rows["first_record"],
                  "rclpy_shutdown_races": len(floor_rows["rclpy_shutdown_races"]),
                  "samples": samples, "period": period, "observation_window": window, "floor": floor},
        "warm_overhead_above_floor": warm["total"]["median"] - floor,
        "goal_overhead_below": GOAL_SECONDS,
        "cli": {**cli, "above_floor": cli["wall"] - floor,
                "above_in_process_warm": cli["wall"] - warm["total"]["median"]},
        "launch_test": {"runs": launch_runs, "median": statistics.median(launch_runs),
                        "cli_ratio": cli["wall"] / statistics.median(launch_runs)},
        "goal_cli_above_floor": CLI_GOAL_ABOVE_FLOOR,
        "source_digest": measure_source_digest(max(runs, 5)),
        "diagnostics": diagnostics,
    }


# --- output --------------------------------------------------------------------------


def render(data: dict[str, Any], console: Console) -> None:
    table = Table(title=f"ros2course check {data['lesson']}: seconds (warm: {data['runs']} runs)",
                  title_justify="left")
    table.add_column("phase")
    for column in ("cold", "warm median", "warm min", "warm max"):
        table.add_column(column, justify="right")
    for name in PHASES:
        warm = data["warm"][name]
        style = "bold" if name == "total" else None
        table.add_row(name, f"{data['cold'][name]:.2f}", f"{warm['median']:.2f}", f"{warm['min']:.2f}",
                      f"{warm['max']:.2f}", style=style)
        for sub in SUB_PHASES.get(name, ()):
            warm = data["warm"][sub]
            table.add_row(f"  {sub}", f"{data['cold'][sub]:.2f}", f"{warm['median']:.2f}", f"{warm['min']:.2f}",
                          f"{warm['max']:.2f}", style="dim")
    console.print(table)

    floor = data["floor"]
    lines = [
        f"floor: first /rosout record {floor['first_record_median']:.2f} s after Popen "
        f"(median of {len(floor['first_record_runs'])})",
        f"       + observation window {floor['observation_window']:.2f} s "
        f"({floor['samples'] - 1} x {floor['period']:.1f} s) = {floor['floor']:.2f} s",
    ]
    for line in lines:
        console.print(line, soft_wrap=True)
    overhead = data["warm_overhead_above_floor"]
    colour = "green" if overhead < data["goal_overhead_below"] else "red"
    console.print(f"[{colour}]warm overhead above floor: {overhead:.2f} s "
                  f"(goal < {data['goal_overhead_below']:.0f} s)[/]", soft_wrap=True)
    cli = data["cli"]
    console.print(f"CLI check, warm, median of {len(cli['runs'])}: {cli['wall']:.2f} s wall "
                  f"({cli['above_in_process_warm']:+.2f} s vs in-process warm median, "
                  f"{cli['above_floor']:.2f} s above floor; "
                  f"{cli['exit_after_output']:.2f} s from its JSON to its exit)", soft_wrap=True)
    lt = data["launch_test"]
    within = cli["above_floor"] <= data["goal_cli_above_floor"]
    faster = cli["wall"] < lt["median"]
    console.print(f"side by side, same run: floor {floor['floor']:.2f} s | ros2course check (CLI, 14 checks) "
                  f"{cli['wall']:.2f} s | plainest launch_test (2 checks) {lt['median']:.2f} s "
                  f"(median of {len(lt['runs'])}); check / launch_test = {lt['cli_ratio']:.2f}", soft_wrap=True)
    console.print(f"[{'green' if within else 'red'}]CLI within {data['goal_cli_above_floor']:.1f} s of the floor: "
                  f"{'yes' if within else 'no'}[/]; [{'green' if faster else 'red'}]faster than launch_test: "
                  f"{'yes' if faster else 'no'}[/]", soft_wrap=True)
    digest = data["source_digest"]
    console.print(f"build record: content digest of the course's {digest['packages']} packages "
                  f"({digest['files']} files): {digest['ms']['median']:.1f} ms median "
                  f"(min {digest['ms']['min']:.1f}, max {digest['ms']['max']:.1f})", soft_wrap=True)
    if data["warm_builds_not_cached"]:
        console.print(f"[yellow]note:[/] {data['warm_builds_not_cached']} warm run(s) ran colcon "
                      "(fingerprint cache missed)", soft_wrap=True)
    if data["leftover_processes_killed"]:
        console.print(f"[yellow]note:[/] {data['leftover_processes_killed']} leftover process(es) killed",
                      soft_wrap=True)

    diag = data["diagnostics"]
    notes = Table(title="where the time outside the node goes (medians, seconds)", title_justify="left")
    notes.add_column("measurement")
    notes.add_column("s", justify="right")
    for label, key in (
        ("python start, with the wheels' re-exec (learner's shell)", "python_start_reexec"),
        ("python start, already bootstrapped (how nodes are started)", "python_start_bootstrapped"),
        ("import rclpy (+node, executors), beyond python start", "rclpy_import_bootstrapped"),
        ("python -m ros2course --help (CLI start-up, wall)", "cli_help"),
        ("import ros2course.cli, fresh process", "cli_import"),
        ("RosSession open, fresh process (imports, init, node)", "ros_session_open_fresh"),
        ("RosSession close, fresh process", "ros_session_close_fresh"),
        ("RosSession open / close, warm process", None),
        ("interpreter exit after a RosSession was closed", "exit_after_ros_session"),
        ("interpreter exit, plain python", "exit_plain_python"),
        ("source install/setup.bash (overlay, uncached)", "overlay_sourcing"),
        ("console-script entry-point lookup (importlib.metadata)", "entry_point_lookup"),
        ("floor node: Popen -> node in the graph", "floor_node_in_graph"),
        ("floor node: SIGINT -> exit", "floor_sigint_exit"),
    ):
        value = (f"{diag['floor_session_open']:.3f} / {diag['floor_session_close']:.3f}" if key is None
                 else f"{diag[key]:.3f}")
        notes.add_row(label, value)
    console.print(notes)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5, help="warm runs, floor runs and diagnostic repeats (default 5)")
    parser.add_argument("--json", action="store_true", help="print the numbers as JSON on stdout instead of tables")
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error("--runs must be at least 1")

    def terminate(signum: int, _frame: Any) -> None:
        raise SystemExit(128 + signum)  # so the finally blocks below clean up

    signal.signal(signal.SIGTERM, terminate)
    os.environ.setdefault("RCUTILS_COLORIZED_OUTPUT", "0")
    marker = uuid.uuid4().hex
    os.environ[BENCH_MARKER_VAR] = marker
    env_mod.activate_process()
    progress = Console(file=sys.stderr, highlight=False, quiet=args.json)
    root = Path(tempfile.mkdtemp(prefix="ros2course-bench-"))
    code = 0
    try:
        data = benchmark(args.runs, root, progress)
    except BenchmarkFailed as exc:
        Console(file=sys.stderr, highlight=False).print(f"[bold red]benchmark failed:[/] {exc}")
        code = 1
    except CourseError as exc:
        Console(file=sys.stderr, highlight=False).print(f"[bold red]error:[/] {exc.message}\n[cyan]hint:[/] {exc.hint}")
        code = int(exc.exit_status) or 1
    finally:
        leftovers = kill_leftovers(marker)
        shutil.rmtree(root, ignore_errors=True)
        if leftovers:
            Console(file=sys.stderr, highlight=False).print(
                f"[yellow]warning:[/] killed {len(leftovers)} leftover process(es): {leftovers}")
    if code:
        return code
    data["leftover_processes_killed"] = len(leftovers)
    if args.json:
        sys.stdout.write(json.dumps(_round(data), indent=2) + "\n")
    else:
        render(data, Console(file=sys.stdout, highlight=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
