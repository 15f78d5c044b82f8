"""A check of a ``ros2`` CLI lesson leaves nothing behind (issue 12).

The learner's script is real bash running the real ``ros2`` CLI: its first
command, a plain ``ros2 topic list``, spawns a ``ros2`` daemon for the check's
domain (ros2cli's ``spawn_daemon`` detaches it with ``setsid``, out of the
script's process group), and this script also leaves a ``sleep`` running in
the background. After the check: no process of the script, no daemon of that
domain (none in the process list, nothing listening on its port 11511 + domain
id) and no unused Fast DDS shared-memory file from the check (its /dev/shm is its own). Real ROS nodes;
nothing here depends on timing.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import re
import shutil
import socket
import subprocess
import sys
from pathlib import Path

import psutil
import pytest

from ros2course.dev.validate import reference_workspace
from ros2course.lesson.catalog import load_catalog
from ros2course.run.process import MARKER_VAR
from ros2course.kit.scripts import daemon_port

#: Put before the reference script: a daemon, the domain and a background process to find afterwards.
PREAMBLE = """ros2 topic list
ros2 daemon status
echo "DOMAIN=${ROS_DOMAIN_ID}"
echo "SHM=$(ls /dev/shm | grep -c fastrtps)"
sleep 300 &
echo "BACKGROUND=$!"
"""


def daemons_of(domain: int) -> list[psutil.Process]:
    """Running ``ros2`` daemons of ``domain`` (ros2cli tags them ``--name ros2-daemon --ros-domain-id N``)."""
    found = []
    for proc in psutil.process_iter(["cmdline"]):
        words = proc.info["cmdline"] or []
        joined = " ".join(words)
        if ("ros2-daemon" in joined or "_ros2_daemon" in joined) and re.search(rf"--ros-domain-id[ =]{domain}\b",
                                                                               joined):
            found.append(proc)
    return found


def marked_in(workspace: Path) -> list[psutil.Process]:
    """Processes carrying a learner-run marker whose working directory is ``workspace``."""
    found = []
    for proc in psutil.process_iter(["cwd"]):
        with contextlib.suppress(psutil.Error):
            if proc.info["cwd"] == str(workspace) and MARKER_VAR in proc.environ():
                found.append(proc)
    return found


def listening(port: int) -> bool:
    """Whether something accepts TCP connections on localhost ``port``."""
    with socket.socket() as sock:
        sock.settimeout(1.0)
        return sock.connect_ex(("127.0.0.1", port)) == 0


def unused_shm(folder: Path) -> list[str]:
    """The Fast DDS files in ``folder`` (the check's private /dev/shm) no live participant holds: what a sweep
    would remove. A segment is held while its ``<name>_el`` lock file is locked; a file with no lock file of its
    own (a port's semaphore) is held by nothing once every process of the check has ended."""
    stale = []
    for path in sorted(folder.iterdir()):
        name = path.name
        if "fastrtps_" not in name:  # not Fast DDS's: e.g. LTTng's lttng-ust-wait-<n>, which rcl's tracing makes
            continue
        if name.endswith("_el"):
            with open(path, "rb") as lock:
                try:
                    fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError:
                    continue  # a live participant holds it
                stale.append(name)
        elif not (folder / f"{name}_el").exists():
            stale.append(name)
    return stale


#: Grades inspect-topics in the process ``unshare`` starts (argv: workspace, log folder); prints its check count.
CHILD = """import json, sys
from pathlib import Path
from ros2course.grade.engine import grade_lesson
from ros2course.lesson.catalog import load_catalog
result = grade_lesson(load_catalog().get("inspect-topics"), Path(sys.argv[1]), log_dir=Path(sys.argv[2]))
print(json.dumps({"checks": len(result.checks), "message": result.message}))
"""


@pytest.mark.ros
@pytest.mark.timeout(300)
def test_a_cli_check_leaves_no_process_daemon_or_shared_memory(tmp_path):
    """The check runs in a mount namespace of its own whose /dev/shm is a fresh folder (root: ``unshare``), so
    every Fast DDS file found there afterwards is the check's: the other xdist worker's participants write to
    the real /dev/shm (CI of stop 72: their segment files, unused for an instant, were counted as this check's)."""
    if os.geteuid() != 0 or not shutil.which("unshare"):
        pytest.skip("a private /dev/shm needs root and unshare(1)")
    lesson = load_catalog().get("inspect-topics")
    workspace = reference_workspace(lesson, tmp_path / "ws")
    script = workspace / "cli" / "inspect_topics.sh"
    script.write_text(PREAMBLE + script.read_text(encoding="utf-8"), encoding="utf-8")
    shm = tmp_path / "shm"
    shm.mkdir()
    shm.chmod(0o1777)
    child = subprocess.run(["unshare", "--mount", "--propagation", "private", "sh", "-c",
                            'mount --bind "$0" /dev/shm && exec "$@"', str(shm), sys.executable, "-c", CHILD,
                            str(workspace), str(tmp_path / "log")], capture_output=True, text=True, timeout=280)
    assert child.returncode == 0, child.stderr[-3000:]
    result = json.loads(child.stdout.strip().splitlines()[-1])
    assert result["checks"], result["message"]
    output = (tmp_path / "log" / "inspect_topics.stdout.log").read_text(encoding="utf-8")
    assert "The daemon is running" in output, f"the script's first command started no daemon: {output[:500]}"
    domain = int(re.search(r"DOMAIN=(\d+)", output).group(1))
    background = int(re.search(r"BACKGROUND=(\d+)", output).group(1))
    assert not psutil.pid_exists(background) or psutil.Process(background).status() == psutil.STATUS_ZOMBIE, (
        "the script's background sleep outlived the check")
    assert marked_in(workspace) == [], "a process of the learner's script outlived the check"
    assert daemons_of(domain) == [], f"a ros2 daemon of domain {domain} outlived the check"
    assert not listening(daemon_port(domain)), f"something still listens on the daemon port of domain {domain}"
    assert int(re.search(r"SHM=(\d+)", output).group(1)) > 0, "the daemon wrote no Fast DDS file to the private /dev/shm"
    assert unused_shm(shm) == [], "the check left unused Fast DDS shared-memory files"
