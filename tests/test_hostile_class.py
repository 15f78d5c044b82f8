"""A class with hostile submissions, graded as root: nothing outside a submission's scratch changes.

Five print-forever-node submissions, each the reference solution plus an
attack (the node keeps doing its job afterwards, so each deserves full marks):

* ``writer``: its node *and* its ``setup.py`` (run by colcon at build time) try
  to write into the course's ``graders/``, the venv, the grading user's home,
  OUTDIR, another student's submission, ``/tmp`` and their own worker's
  result file, and to read the lesson's reference (in ``solutions/``, in a
  shared reference build in the venv, the course's ``.git``, docs and mutation
  records), and record what happened in their ROS log folder;
* ``daemon``: double-forks a ``setsid`` daemon that execs a fresh interpreter
  with an empty environment (no run marker to find it by);
* ``forker``: forks until the kernel refuses;
* ``signaller``: sends SIGKILL to its parent, to PID 1 and to every process it can see;
* ``alice``: the reference, beside them.

Runs only where every protection of :mod:`ros2course.sandbox` is in effect
(root on Linux with util-linux, iproute2, dumb-init and a pids cgroup or a
dedicated uid); elsewhere it says which one is missing.
"""

from __future__ import annotations

import sys
import uuid
from pathlib import Path

import pytest
from test_batch_ros import NODE_FILE, make_submission, tree_digest, wait_until_gone

from ros2course.batch.runner import build_trusted_interfaces, run_batch
from ros2course.lesson.catalog import content_root, load_catalog
from ros2course import sandbox
from tests.conftest import SOLUTIONS, cpu_lock

#: a fork storm and two jobs at once: never beside each other (conftest.cpu_exclusive)
pytestmark = [pytest.mark.ros, pytest.mark.usefixtures("cpu_exclusive"), pytest.mark.timeout(1200)]

SETUP_FILE = "src/python_package_with_a_node/setup.py"

#: Tries each write, then each read of a reference source, and appends one line per attempt to
#: ``$ROS_LOG_DIR/hostile-<who>.txt`` (the job's log folder, copied to OUTDIR). ``TARGETS`` and ``READS``
#: are prepended by the test.
ATTEMPTS = '''
def _hostile_attempts(who):
    import glob, os
    log_dir = os.environ.get("ROS_LOG_DIR", ".")
    here = os.path.abspath(os.getcwd())
    scratch = here
    while scratch != "/" and not os.path.basename(scratch).startswith("ros2course-grade-"):
        scratch = os.path.dirname(scratch)
    targets = dict(TARGETS)
    targets["result-file"] = os.path.join(scratch, "result.json")
    for other in glob.glob("/tmp/ros2course-batch-*/ros2course-grade-*"):
        if other != scratch:
            targets["other-scratch " + os.path.basename(other)] = os.path.join(other, "ws", "pwned")
    lines = []
    for where, path in targets.items():
        try:
            with open(path, "w") as handle:
                handle.write("pwned")
            lines.append(f"WROTE {where} {path}")
        except OSError as exc:
            lines.append(f"DENIED {where} {path} {type(exc).__name__}")
    try:
        fake = os.path.join(here, "fake-result.json")
        with open(fake, "w") as handle:
            handle.write("[]")
        os.replace(fake, targets["result-file"])
        lines.append("WROTE result-file by rename")
    except OSError as exc:
        lines.append(f"DENIED result-file by rename {type(exc).__name__}")
    for where, path in READS.items():
        try:
            with open(path, "rb") as handle:
                data = handle.read()
            lines.append(f"READ {where} {path}" if data else f"UNREAD {where} {path} empty")
        except OSError as exc:
            lines.append(f"UNREAD {where} {path} {type(exc).__name__}")
    with open(os.path.join(log_dir, f"hostile-{who}.txt"), "a") as out:
        out.write("\\n".join(lines) + "\\n")
'''

DAEMON = '''
def _hostile_daemon():
    import os, sys
    log_dir = os.environ.get("ROS_LOG_DIR", ".")
    if os.fork() == 0:
        os.setsid()
        if os.fork() == 0:
            code = ("import os, sys, time\\n"
                    "open(sys.argv[1], 'w').write(str(os.getpid()))\\n"
                    "while True: time.sleep(1)\\n")
            os.execv("/usr/bin/env", ["env", "-i", sys.executable, "-c", code,
                                      os.path.join(log_dir, "daemon-started.txt"), "TOKEN"])
        os._exit(0)
    os.wait()
'''

FORKER = '''
def _hostile_forks():
    import os, time
    children = 0
    refused = ""
    while children < 5000:
        try:
            pid = os.fork()
        except OSError as exc:
            refused = type(exc).__name__
            break
        if pid == 0:
            time.sleep(1.0)
            os._exit(0)
        children += 1
    for _ in range(children):
        os.wait()
    with open(os.path.join(os.environ.get("ROS_LOG_DIR", "."), "forks.txt"), "w") as out:
        out.write(f"{children} {refused}\\n")
'''

SIGNALLER = '''
def _hostile_signals():
    import os, signal
    me = os.getpid()
    lines = []
    targets = {"parent": os.getppid(), "init": 1}
    for pid in os.listdir("/proc"):
        if pid.isdigit() and int(pid) not in (me, os.getppid(), 1):
            targets["pid " + pid] = int(pid)
    for what, pid in targets.items():
        try:
            if pid != me:
                os.kill(pid, signal.SIGKILL)
                lines.append(f"KILLED {what} {pid}")
        except OSError as exc:
            lines.append(f"DENIED {what} {pid} {type(exc).__name__}")
    with open(os.path.join(os.environ.get("ROS_LOG_DIR", "."), "signals.txt"), "w") as out:
        out.write("\\n".join(lines) + "\\n")
'''


def _insert_call(source: str, helper: str, call: str) -> str:
    """``source`` with ``helper`` defined at the top and ``call`` as the first statement of ``main``."""
    start = source.index("\ndef main(")
    end = source.index("\n", source.index(":", source.index(")", start))) + 1
    return helper + "\n" + source[:end] + f"    {call}\n" + source[end:]


@pytest.fixture(scope="module")
def hostile_class(tmp_path_factory):
    caps = sandbox.capabilities()
    if caps.missing:
        pytest.skip("not every protection is available here: "
                    + "; ".join(f"{k} ({v})" for k, v in caps.missing.items()))
    root = tmp_path_factory.mktemp("hostile")
    token = uuid.uuid4().hex[:12]
    subs, out = root / "subs", root / "out"
    home = Path("~").expanduser()
    targets = {
        "graders": str(content_root() / "graders" / f"pwned_{token}.py"),
        "venv": str(Path(sys.prefix) / f"pwned_{token}"),
        "grader-home": str(home / f"pwned_{token}"),
        "outdir": str(out / f"pwned_{token}"),
        "other-submission": str(subs / "alice" / f"pwned_{token}"),
        "tmp": f"/tmp/pwned_{token}",
    }
    # print-forever-node's reference source, where a submission could copy it from: solutions/, and a shared
    # reference build that holds it (testing-your-nodes tests the learner's tests on it: a batch of that lesson
    # leaves its trusted build in the venv, which the sandbox shows read-only)
    shared = build_trusted_interfaces([load_catalog().get("testing-your-nodes")])
    reads = {"solutions": str(SOLUTIONS / "python_package_with_a_node" / "python_package_with_a_node"
                              / "print_forever_node.py"),
             "shared-reference-build": str(shared.path / "src" / "python_package_with_a_node"
                                           / "python_package_with_a_node" / "print_forever_node.py")}
    # and what else of the course holds reference lines: its git history (a checkout), the strength table,
    # the lesson's mutation record
    root = content_root()
    for where, path in (("git", root / ".git" / "HEAD"), ("docs", root / "docs" / "grader-strength.md"),
                        ("mutation-record", root / "chapters" / "print-forever-node" / "mutation-outcomes.json")):
        if path.is_file():
            reads[where] = str(path)
    assert all(Path(path).is_file() for path in reads.values()), reads
    prelude = f"TARGETS = {targets!r}\nREADS = {reads!r}\n"
    make_submission("print-forever-node", subs / "alice")
    writer = make_submission("print-forever-node", subs / "writer")
    node = writer / NODE_FILE
    node.write_text(_insert_call(node.read_text(), prelude + ATTEMPTS, "_hostile_attempts('node')"))
    setup = writer / SETUP_FILE
    setup.write_text(prelude + ATTEMPTS + "\n_hostile_attempts('setup')\n" + setup.read_text())
    for student, helper, call in (("daemon", DAEMON.replace("TOKEN", token), "_hostile_daemon()"),
                                  ("forker", FORKER, "_hostile_forks()"),
                                  ("signaller", SIGNALLER, "_hostile_signals()")):
        ws = make_submission("print-forever-node", subs / student)
        node = ws / NODE_FILE
        node.write_text(_insert_call(node.read_text(), helper, call))
    graders_before = tree_digest(content_root() / "graders")
    subs_before = tree_digest(subs)
    with cpu_lock():  # a module fixture runs before the function-scoped cpu_exclusive
        report = run_batch(subs, ["print-forever-node"], out, jobs=2, timeout=180)
    return {"report": report, "out": out, "targets": targets, "token": token, "reads": reads,
            "graders_before": graders_before, "subs_before": subs_before, "subs": subs}


def _record(hostile_class, student: str) -> dict:
    return next(r for r in hostile_class["report"].records if r.student == student)


def _log(hostile_class, student: str, name: str) -> str:
    path = hostile_class["out"] / student / "logs" / "ros" / name
    assert path.is_file(), f"{student} left no {name}: its attack did not run"
    return path.read_text()


def test_every_submission_gets_the_verdict_it_deserves(hostile_class) -> None:
    """Each attack is beside a correct node: full marks for all five, none a grader error."""
    for student in ("alice", "writer", "daemon", "forker", "signaller"):
        record = _record(hostile_class, student)
        lost = [c.id for c in record.checks if c.points < c.max_points]
        assert record.status == "passed" and not lost, (student, record.status, record.message, lost)
        iso = record.isolation
        assert not iso["missing"] and iso["uid"] and iso["pids_limit"] == sandbox.DEFAULT_PIDS_LIMIT, iso


def test_nothing_outside_the_scratch_copy_changed(hostile_class) -> None:
    """The node's and setup.py's writes into the course, venv, home, OUTDIR, other submissions, /tmp all fail."""
    for who in ("node", "setup"):
        lines = _log(hostile_class, "writer", f"hostile-{who}.txt").splitlines()
        assert any("result-file" in line for line in lines), lines
        wrote = [line for line in lines if line.startswith("WROTE") and " tmp " not in line]
        assert not wrote, f"the {who} of a submission wrote outside its scratch copy: {wrote}"
    for where, path in hostile_class["targets"].items():
        assert not Path(path).exists(), f"{where}: {path} was written by a submission"
    assert tree_digest(content_root() / "graders") == hostile_class["graders_before"]
    assert tree_digest(hostile_class["subs"]) == hostile_class["subs_before"], "the submissions folder changed"
    assert not list((hostile_class["out"]).glob("pwned*"))


def test_no_reference_source_can_be_read(hostile_class) -> None:
    """Neither the node nor setup.py can read the lesson's reference: solutions/, the shared reference
    builds in the venv (only the job's own trusted build is bound back), the course's git history and docs are
    hidden, its mutation records masked."""
    for who in ("node", "setup"):
        lines = _log(hostile_class, "writer", f"hostile-{who}.txt").splitlines()
        read = [line for line in lines if line.startswith("READ ")]
        assert not read, f"the {who} of a submission read a reference source: {read}"
        assert {line.split()[1] for line in lines if line.startswith("UNREAD ")} == set(hostile_class["reads"]), lines


def test_a_trusted_build_holds_no_reference_tests() -> None:
    """testing-your-nodes' answer is the reference packages' test/ folders; a batch of that lesson shows its
    trusted build (those packages' sources) to each submission, so the build leaves them out."""
    trusted = build_trusted_interfaces([load_catalog().get("testing-your-nodes")])
    packages = sorted(p.name for p in (trusted.path / "src").iterdir() if (p / "package.xml").is_file())
    assert packages == ["python_package_with_a_library", "python_package_with_a_node"], packages
    assert (SOLUTIONS / "python_package_with_a_node" / "test").is_dir()
    assert not list((trusted.path / "src").glob("*/test")), list((trusted.path / "src").glob("*/test"))


def test_a_clean_environment_daemon_does_not_outlive_its_job(hostile_class) -> None:
    """A double-forked setsid daemon with an empty environment ends with the job (PID namespace)."""
    assert _log(hostile_class, "daemon", "daemon-started.txt").strip().isdigit()
    alive = wait_until_gone(hostile_class["token"])
    assert not alive, f"the daemon survived the batch: {alive}"


def test_forking_is_refused_at_the_process_limit(hostile_class) -> None:
    """The fork loop is refused near the limit; the result says the limit and how often it refused."""
    children, _, refused = _log(hostile_class, "forker", "forks.txt").strip().partition(" ")
    assert refused and int(children) < sandbox.DEFAULT_PIDS_LIMIT, (children, refused)
    iso = _record(hostile_class, "forker").isolation
    assert iso["pids_limit"] == sandbox.DEFAULT_PIDS_LIMIT
    if "cgroup pids" in iso["pids_via"]:
        assert iso.get("pids_refused", 0) > 0 and iso.get("pids_peak", 0) <= sandbox.DEFAULT_PIDS_LIMIT, iso


def test_signals_reach_no_process_of_the_grader(hostile_class) -> None:
    """SIGKILL to its parent, PID 1 and every visible process is refused for all but its own."""
    lines = _log(hostile_class, "signaller", "signals.txt").splitlines()
    assert any(line.startswith("DENIED parent") for line in lines), lines
    assert any(line.startswith("DENIED init") for line in lines), lines
    killed = [line for line in lines if line.startswith("KILLED")]
    assert not killed, f"the submission signalled processes that are not its own: {killed}"
