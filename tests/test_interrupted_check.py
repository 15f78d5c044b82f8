"""A check killed half-way loses nothing and leaves no learner process behind."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import psutil
import pytest

from ros2course.run.process import sweep_stale_fastdds_shm


def _wait_for(predicate, timeout: float) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.05)
    return predicate()


def _node_children(pid: int) -> list[psutil.Process]:
    try:
        kids = psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []
    out = []
    for kid in kids:
        try:
            if any("print_forever_node" in part for part in kid.cmdline()):
                out.append(kid)
        except psutil.Error:
            continue
    return out


@pytest.mark.ros
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_check_killed_mid_way(solution_workspace, sig):
    ws = solution_workspace
    before = ws.progress_path.read_bytes()
    cli = subprocess.Popen([sys.executable, "-m", "ros2course", "check", "print-forever-node", "--workspace", str(ws.root)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, stdin=subprocess.DEVNULL,
                           start_new_session=True)
    try:
        assert _wait_for(lambda: _node_children(cli.pid), 120), "the learner node never started"
        nodes = _node_children(cli.pid)
        time.sleep(0.5)
        os.kill(cli.pid, sig)  # only ros2course itself, not its process group
        cli.wait(timeout=30)
        gone, alive = psutil.wait_procs(nodes, timeout=15)
        assert not alive, f"learner node(s) survived ros2course: {[p.pid for p in alive]}"
    finally:
        if cli.poll() is None:
            os.killpg(cli.pid, signal.SIGKILL)
            cli.wait()
    # the progress file is intact: the interrupted check was simply not recorded
    assert ws.progress_path.read_bytes() == before
    json.loads(ws.progress_path.read_text())
    assert not list(ws.state_dir.glob(".progress.json.*.tmp"))
    if sig == signal.SIGKILL:
        sweep_stale_fastdds_shm()  # what the next check does first thing after a crash
