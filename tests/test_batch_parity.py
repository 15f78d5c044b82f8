"""`ros2course grade` gives the verdicts `ros2course check` gives (issue 25).

The whole-course parity run is ``dev validate --batch`` (tests/test_validate.py); these
tests pin the two causes of the eight lessons that used to differ: the batch's trusted
interface build, and folders the submission's uid must write.
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import stat
import tempfile
from pathlib import Path

import pytest

from ros2course.builder.reference import trusted_interface_packages
from ros2course.errors import CourseError
from ros2course.grade.checklist import Check
from ros2course.grade.engine import load_grader
from ros2course.grade.session import GradingSession
from ros2course.lesson.catalog import load_catalog
from ros2course import sandbox


def test_an_interface_package_the_lesson_teaches_is_still_built_for_the_batch() -> None:
    """inspect-topics lists package_with_interfaces among its own packages and its grader imports its types."""
    catalog = load_catalog()
    lesson = catalog.get("inspect-topics")
    assert "package_with_interfaces" in lesson.packages
    assert trusted_interface_packages([lesson]) == ["package_with_interfaces"]
    assert trusted_interface_packages([catalog.get("print-forever-node")]) == []
    every = trusted_interface_packages(catalog.lessons)
    # and the references testing-your-nodes runs the learner's tests against
    assert every == ["package_with_interfaces", "python_package_with_a_library", "python_package_with_a_node"]


def test_a_lesson_whose_interface_the_course_cannot_build_is_refused_up_front() -> None:
    lesson = dataclasses.replace(load_catalog().get("inspect-topics"), interfaces=["no_such_interfaces"])
    with pytest.raises(CourseError) as info:
        trusted_interface_packages([lesson])
    assert "inspect-topics cannot be graded in batch" in info.value.message and "no_such_interfaces" in info.value.message


def test_lessons_of_two_courses_are_refused_as_one_batch(tmp_path: Path) -> None:
    """A batch builds one course's reference packages: a package of one name in two courses would shadow the other."""
    lesson = load_catalog().get("inspect-topics")
    other = dataclasses.replace(lesson, course=dataclasses.replace(lesson.course, root=tmp_path))
    with pytest.raises(CourseError) as info:
        trusted_interface_packages([lesson, other])
    assert "lessons of 2 courses in one batch" in info.value.message and str(tmp_path) in info.value.message


def test_the_grader_may_import_only_declared_interfaces(tmp_path: Path) -> None:
    """The same refusal under check and batch, so dev validate finds an undeclared package before a class does."""
    lesson = load_catalog().get("print-forever-node")
    session = GradingSession(lesson, [Check("a", "a", 1)], tmp_path, tmp_path / "log", dict(os.environ))
    with pytest.raises(CourseError) as info:
        session.interface_type("package_with_interfaces", "msg", "AmazingQuote")
    assert "does not declare" in info.value.message and "interfaces: [package_with_interfaces]" in info.value.hint


def test_the_grader_may_read_only_declared_reference_packages(tmp_path: Path) -> None:
    """A grader reads the course's reference sources only of the packages lesson.yaml declares in ``references:``
    (batch grading copies just those into the sandbox); a declared one is found in solutions/ under check."""
    catalog = load_catalog()
    session = GradingSession(catalog.get("print-forever-node"), [Check("a", "a", 1)], tmp_path, tmp_path / "log",
                             dict(os.environ))
    with pytest.raises(CourseError) as info:
        session.reference_package("python_package_with_a_node")
    assert "references: [python_package_with_a_node]" in info.value.hint
    testing = GradingSession(catalog.get("testing-your-nodes"), [Check("a", "a", 1)], tmp_path, tmp_path / "log",
                             dict(os.environ))
    folder = testing.reference_package("python_package_with_a_node")
    assert (folder / "python_package_with_a_node" / "print_forever_node.py").is_file()


needs_root = pytest.mark.skipif(os.geteuid() != 0 or not sandbox.capabilities().uid_drop,
                                reason="runs a program as another uid: root only")


@needs_root
def test_submission_programs_write_only_into_submission_folders() -> None:
    """What a submission's program writes (a build folder, a probe's trace, a venv) lands in a folder its uid
    owns; the check's log folder stays the grader's, and a program writing there is refused. (The lessons'
    own builds, traces and venvs as that uid: ``dev validate --batch`` in tests/test_validate.py.)"""
    from ros2course.kit.programs import run_program  # noqa: PLC0415 - the course's kit, on the content root

    uid = sandbox.UID_BASE + sandbox.UID_SPAN + 1
    lesson = load_catalog().get("python-installable-package")
    root = Path(tempfile.mkdtemp(prefix="ros2course-parity-test-"))  # pytest's tmp_path is 0700: the uid must pass
    root.chmod(0o755)
    log_dir = root / "log"
    log_dir.mkdir()
    env = {"PATH": "/usr/bin:/bin"}
    session = GradingSession(lesson, [Check("a", "a", 1)], root, log_dir, env)
    write = ["/bin/sh", "-c", 'echo t > "$1"', "sh"]
    sandbox.configure(sandbox.SubmissionIdentity(uid, uid, 64))
    try:
        filled = session.submission_folder("probe", lambda folder: (folder / "given" / "a.txt").parent.mkdir())
        assert filled == log_dir / "probe"
        assert {p.lstat().st_uid for p in [filled, filled / "given"]} == {uid}
        wrote = run_program(session, [*write, str(filled / "given" / "trace.json")], "writer", env=env, cwd=filled)
        assert wrote.returncode == 0 and (filled / "given" / "trace.json").stat().st_uid == uid
        refused = run_program(session, [*write, str(log_dir / "planted.txt")], "planter", env=env, cwd=filled)
        assert refused.returncode != 0 and not (log_dir / "planted.txt").exists()
        assert log_dir.stat().st_uid == os.geteuid() and not log_dir.stat().st_mode & stat.S_IWOTH
        again = session.submission_folder("probe")  # fresh: what the submission left there is gone
        assert list(again.iterdir()) == []
    finally:
        sandbox.configure(None)
        session.close()
        shutil.rmtree(root, ignore_errors=True)


def test_a_learner_programs_temporary_files_stay_in_the_checks_log_folder(tmp_path: Path) -> None:
    """Every learner process gets TMPDIR = log_dir/tmp: ros2 launch's launch_params_* files (launch_ros never
    removes them) stay with the check's logs, not in the machine's /tmp (found cleaning up after stop 65)."""
    from ros2course.kit.programs import run_program  # noqa: PLC0415 - the course's kit, on the content root

    log_dir = tmp_path / "log"
    session = GradingSession(load_catalog().get("launch-files"), [Check("a", "a", 1)], tmp_path, log_dir,
                             {"PATH": "/usr/bin:/bin", "TMPDIR": "/tmp"})
    try:
        made = run_program(session, ["/bin/sh", "-c", 'mktemp launch_params_XXXX --tmpdir'], "probe",
                           env={"PATH": "/usr/bin:/bin", "TMPDIR": "/tmp"})
        path = Path(made.stdout.strip())
        assert made.returncode == 0 and path.parent == log_dir / "tmp" and path.is_file()
    finally:
        session.close()


@pytest.mark.ros
@pytest.mark.timeout(600)
def test_a_forgotten_depend_on_an_earlier_lessons_package_loses_the_same_points_in_grade(tmp_path: Path) -> None:
    """A fresh hand-in whose package.xml forgets the library (use-python-library's missing-library-depend) builds the
    library all the same, as a learner's workspace has it from lesson 14: `grade` loses only depends_library, as
    `check` does, although the worker cannot read solutions/ to learn what the lesson depends on."""
    from ros2course.dev.parity import case_workspace  # noqa: PLC0415
    from ros2course.batch.runner import run_batch  # noqa: PLC0415

    lesson = load_catalog().get("use-python-library")
    case_workspace(lesson, "missing-library-depend", tmp_path / "class" / "forgetful")
    report = run_batch(tmp_path / "class", [lesson.id], tmp_path / "out", jobs=1, timeout=300)
    [record] = report.records
    assert [c.id for c in record.checks if not c.passed] == ["depends_library"], record.message


@pytest.mark.ros
@pytest.mark.usefixtures("cpu_exclusive")
@pytest.mark.timeout(900)
def test_gradescope_autograder_gives_the_references_full_marks(tmp_path: Path) -> None:
    """The Gradescope path (one upload graded for several lessons, as root with full isolation) on three of the
    lessons that used to differ: an interface the lesson teaches, a probe's trace, a CMake build and g++."""
    from ros2course.batch.gradescope import run_gradescope  # noqa: PLC0415
    from ros2course.builder.reference import reference_workspace  # noqa: PLC0415
    from ros2course.dev.validate import run_commands  # noqa: PLC0415

    lessons = ["python-asyncio", "inspect-services", "cpp-demystified"]
    upload = tmp_path / "autograder" / "submission"
    catalog = load_catalog()
    for lesson_id in lessons:  # one workspace holding the three references (no package in common)
        lesson = catalog.get(lesson_id)
        reference_workspace(lesson, upload)
        run_commands(upload, lesson.reference.commands)
    results = tmp_path / "autograder" / "results" / "results.json"
    score = run_gradescope(lessons, upload, results, timeout=600)
    data = json.loads(results.read_text(encoding="utf-8"))
    lost = [t["name"] for t in data["tests"] if t.get("score") != t.get("max_score")]
    assert not lost, lost
    total = sum(float(sum(c.points for c in load_grader(catalog.get(i).grader).CHECKS)) for i in lessons)
    assert score == total


def test_a_reference_cache_folder_others_can_write_is_never_used(tmp_path: Path, monkeypatch) -> None:
    """Trusted interface builds are code the grader imports: never from a folder another user could swap."""
    from ros2course.builder import reference  # noqa: PLC0415

    monkeypatch.setattr(reference.sys, "prefix", str(tmp_path))
    root = reference.reference_cache_root()
    assert root == tmp_path / "var" / "cache" / "ros2course" / "reference" and root.is_dir()
    root.chmod(0o777)
    assert reference.reference_cache_root() is None


@pytest.mark.ros
def test_reference_interfaces_are_built_once_and_shared(tmp_path: Path, monkeypatch) -> None:
    """dev validate's underlay and the batch's trusted interfaces: one build while the sources stay the same."""
    from ros2course.builder import reference  # noqa: PLC0415

    lesson = load_catalog().get("publisher-subscriber")
    first = reference.shared_reference_build(lesson, ["package_with_interfaces"])
    installed = first.path / "install" / "package_with_interfaces" / "share" / "package_with_interfaces" / "package.xml"
    stamp = installed.stat().st_mtime_ns
    again = reference.shared_reference_build(lesson, ["package_with_interfaces"])
    assert again == first and not first.temporary
    assert installed.stat().st_mtime_ns == stamp, "the shared build was built a second time"
    assert (first.path / "install" / "package_with_interfaces").is_dir()
    assert first.path.stat().st_mode & 0o005 == 0o005, "the submission's uid must be able to source it"
    first.discard()
    assert first.path.is_dir(), "discard() removed a shared build"
    monkeypatch.setattr(reference, "reference_cache_root", lambda: None)
    own = reference.shared_reference_build(lesson, ["package_with_interfaces"])
    assert own.temporary and own.path != first.path and (own.path / "install" / "setup.bash").is_file()
    own.discard()
    assert not own.path.exists()


def test_the_batch_sample_is_the_wrong_solutions_check_graded_fastest() -> None:
    """``dev validate --batch --sample K`` hands in the K graded fixtures ``check`` took least time on;
    a not-gradable one (no checks to compare) is not picked; without timings the names are spread."""
    from ros2course.dev.parity import sample_fixtures
    from ros2course.grade.results import LessonResult
    from ros2course.dev.validate import Outcome, load_fixtures

    lesson = load_catalog().get("inspect-topics")

    def outcome(case: str, seconds: float, status: str = "failed") -> Outcome:
        return Outcome(lesson.id, case, True, "", "", seconds, LessonResult(lesson.id, 1.0, 11.0, status, []))

    checked = [outcome("reference", 1.0, "passed"), outcome("echo_without_once", 29.0),
               outcome("grep_keeps_the_inbox", 7.9), outcome("message_type_typo", 3.0, "not gradable"),
               outcome("pub_without_once", 26.7), outcome("wrong_topic_name", 10.3)]
    assert sample_fixtures(lesson, 1, checked) == ["grep_keeps_the_inbox"]
    assert sample_fixtures(lesson, 2, checked) == ["grep_keeps_the_inbox", "wrong_topic_name"]
    assert sample_fixtures(lesson, 1) == ["echo_without_once"]
    every = sorted(f.name for f in load_fixtures(lesson.id))
    assert len(every) < 9 and sorted(sample_fixtures(lesson, 9, checked)) == every  # more than it has: all
    # one whose program died on its own (a `process` diagnosis) comes last: what was seen of it is a race
    from ros2course.grade.results import CheckResult
    from ros2course.run.diagnose import Diagnosis

    died = CheckResult("echo", "echo", 0, 1, False, "", "", "",
                       diagnosis=[Diagnosis("process", "the learner's process x exited with code 1", {})])
    checked[2] = Outcome(lesson.id, "grep_keeps_the_inbox", True, "", "", 7.9,
                         LessonResult(lesson.id, 1.0, 11.0, "failed", [died]))
    assert sample_fixtures(lesson, 1, checked) == ["wrong_topic_name"]
    # ... even when it was graded whole and the others were stopped once their checks were judged (which, like
    # the ones graded whole, are taken fastest first)
    from ros2course.grade.checklist import STOPPED_SETTLED

    from ros2course.dev.mutants import NOT_CHECKED

    settled = CheckResult("echo", "echo", 0, 1, False, NOT_CHECKED + STOPPED_SETTLED, "", "", skipped=True)
    for index in (1, 4, 5):
        old = checked[index]
        checked[index] = Outcome(lesson.id, old.case, True, "", "", old.seconds,
                                 LessonResult(lesson.id, 1.0, 11.0, "failed", [settled]))
    assert sample_fixtures(lesson, 1, checked) == ["wrong_topic_name"], "stopped or whole: the fastest"
    assert sample_fixtures(lesson, 2, checked) == ["wrong_topic_name", "pub_without_once"]


def test_the_graders_random_draws_follow_the_files_not_their_times_or_modes(tmp_path: Path) -> None:
    """``GradingSession.random``: the same files get the same probes through ``check`` and ``grade`` (a hand-in
    is a copy: other times, other permission bits); other content, or another lesson, gets other draws."""
    lesson = load_catalog().get("actions-server")

    def draws(root: Path, which=lesson) -> list[float]:
        session = GradingSession(which, [Check("a", "a", 1)], root, root / "log", dict(os.environ))
        return [session.random.uniform(0.0, 6.28) for _ in range(3)]

    mine = tmp_path / "mine"
    (mine / "src" / "pkg").mkdir(parents=True)
    node = mine / "src" / "pkg" / "node.py"
    node.write_text("print('goal')\n", encoding="utf-8")
    first = draws(mine)
    assert draws(mine) == first, "two checks of unchanged files draw alike"
    copy = tmp_path / "handed-in"
    shutil.copytree(mine, copy)
    (copy / "src" / "pkg" / "node.py").chmod(0o600)
    os.utime(copy / "src" / "pkg" / "node.py", (1_000_000, 1_000_000))
    assert draws(copy) == first, "a copy with other times and modes is the same submission"
    node.write_text("print('goal!')\n", encoding="utf-8")
    assert draws(mine) != first, "other content, other probes"
    assert draws(copy, load_catalog().get("actions-client")) != first, "another lesson, other probes"
    assert draws(tmp_path / "no-src") == draws(tmp_path / "no-src-either"), "no src/: the lesson alone seeds"
    (mine / "src" / "dangling").symlink_to(tmp_path / "nowhere")
    assert draws(mine) == draws(tmp_path / "no-src"), "a src/ that cannot be read whole: the lesson alone seeds"


def test_a_built_lessons_draws_follow_its_packages_contents_as_the_build_read_them(tmp_path: Path) -> None:
    """With packages, the seed is the build's content digest (no second scan): a copy with other modes keeps it."""
    from ros2course.builder.sources import scan_package  # noqa: PLC0415

    lesson = load_catalog().get("actions-server")
    pkg = tmp_path / "src" / "pkg"
    pkg.mkdir(parents=True)
    (pkg / "node.py").write_text("print('goal')\n", encoding="utf-8")
    before = scan_package(tmp_path, pkg)
    (pkg / "node.py").chmod(0o700)
    after = scan_package(tmp_path, pkg)
    assert before.digest != after.digest, "the build's own record keeps modes (an executable bit matters to it)"
    assert before.content_digest == after.content_digest, "the seed does not"

    def draws(digest: str) -> list[float]:
        session = GradingSession(lesson, [Check("a", "a", 1)], tmp_path, tmp_path / "log", dict(os.environ),
                                 sources_digest=digest)
        return [session.random.random() for _ in range(3)]

    assert draws(before.content_digest) == draws(after.content_digest)
    assert draws(before.content_digest) != draws("0" * 64)


def test_processes_started_from_parts_at_once_share_one_temporary_folder(tmp_path: Path) -> None:
    """Parts run in threads of their own (kit.parts.at_once): the folder is made once, never emptied under a
    running process (stop 66's measurement: a FileExistsError, 'the grader failed', in 13 of 30 gradings)."""
    import threading

    log_dir = tmp_path / "log"
    session = GradingSession(load_catalog().get("launch-files"), [Check("a", "a", 1)], tmp_path, log_dir,
                             {"PATH": "/usr/bin:/bin"})
    folders, failures, start = [], [], threading.Barrier(8)

    def make() -> None:
        start.wait()
        try:
            folders.append(session.machine.process(["/bin/true"], {"PATH": "/usr/bin:/bin"}, "p").env["TMPDIR"])
        except Exception as error:  # noqa: BLE001 - the race shows as any exception
            failures.append(error)

    threads = [threading.Thread(target=make) for _ in range(8)]
    try:
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        assert not failures and set(folders) == {str(log_dir / "tmp")} and (log_dir / "tmp").is_dir()
    finally:
        session.close()


@pytest.mark.ros
@pytest.mark.timeout(600)
def test_a_wrong_solutions_own_race_is_told_apart_from_parity_by_a_second_check_run(tmp_path: Path) -> None:
    """dev validate --batch, given a check result that lost a check grade then passes (as a wrong program racing
    itself does: CI of 893e21c), grades the case once more with check: a check its fixture does not name that
    check's second run passes too is the race, and the case passes saying so; the same on the check the fixture
    names still fails."""
    from ros2course.dev.child import grade_in_child  # noqa: PLC0415
    from ros2course.dev.parity import batch_parity, case_workspace  # noqa: PLC0415
    from ros2course.dev.validate import Outcome  # noqa: PLC0415

    lesson = load_catalog().get("python-node-template")
    fixture = "greeting-without-period"  # fails [greeting]; exit_code passes
    checked = grade_in_child(lesson.id, case_workspace(lesson, fixture, tmp_path / "ws"), (), tmp_path / "logs")
    assert "greeting" in checked.failed_checks() and "exit_code" not in checked.failed_checks(), checked.checks

    def lost(check_id: str) -> Outcome:
        checks = [dataclasses.replace(c, passed=False, points=0.0) if c.id == check_id else c for c in checked.checks]
        result = dataclasses.replace(checked, checks=checks, score=sum(c.points for c in checks))
        return Outcome(lesson.id, fixture, True, "", "", 0.0, result)

    raced = lost("exit_code")
    passed_too = dataclasses.replace(checked, checks=[dataclasses.replace(c, passed=True, points=c.max_points)
                                                      if c.id == "greeting" else c for c in checked.checks])
    named = Outcome(lesson.id, fixture, True, "", "", 0.0, dataclasses.replace(passed_too, score=checked.max_score))
    [told] = batch_parity([lesson], [raced])
    [parity] = batch_parity([lesson], [named])
    assert told.ok and "exit_code changed between check's two runs" in told.got, told.got
    assert not parity.ok and "races itself" not in parity.got, parity.got



@pytest.mark.ros
@pytest.mark.parametrize("misses", [1, 2])
def test_a_wrong_solutions_bug_grade_missed_once_is_told_apart_from_parity_by_a_second_grade_run(
        tmp_path: Path, monkeypatch, misses: int) -> None:
    """A batch that passed the check a wrong solution's fixture names, where check lost it twice, grades the case
    once more through grade: a miss that does not repeat was one run's race (CI of stop 72: gazebo-custom-nodes'
    thrust-ctrl-c-uncaught passed its Ctrl+C check once under grade), and the case passes saying so; a miss grade
    repeats is a parity difference and fails. The miss is doctored into grade's result (``misses`` runs)."""
    from ros2course.dev import parity as parity_mod  # noqa: PLC0415
    from ros2course.dev.child import grade_in_child  # noqa: PLC0415
    from ros2course.dev.validate import Outcome  # noqa: PLC0415

    lesson = load_catalog().get("python-node-template")
    fixture = "greeting-without-period"  # fails [greeting]
    checked = grade_in_child(lesson.id, parity_mod.case_workspace(lesson, fixture, tmp_path / "ws"), (),
                             tmp_path / "logs")
    assert "greeting" in checked.failed_checks(), checked.checks
    real_batch, runs = parity_mod.run_batch, []

    def batch_that_misses(*args, **kwargs):
        report = real_batch(*args, **kwargs)
        runs.append(1)
        if len(runs) <= misses:  # greeting passed: the bug missed in this run
            report.records = [dataclasses.replace(r, checks=[dataclasses.replace(c, passed=True, points=c.max_points)
                                                             if c.id == "greeting" else c for c in r.checks])
                              for r in report.records]
        return report

    monkeypatch.setattr(parity_mod, "run_batch", batch_that_misses)
    [outcome] = parity_mod.batch_parity([lesson], [Outcome(lesson.id, fixture, True, "", "", 0.0, checked)])
    assert len(runs) == 2, runs
    if misses == 1:
        assert outcome.ok and "grade's second run gave check's verdict (greeting differed" in outcome.got, outcome.got
    else:
        assert not outcome.ok and "second run" not in outcome.got, outcome.got

def _program_session(tmp_path: Path) -> GradingSession:
    return GradingSession(load_catalog().get("inspect-topics"), [Check("a", "a", 1)], tmp_path, tmp_path / "log",
                          {"PATH": "/usr/bin:/bin"})


def test_a_program_that_leaves_a_command_running_is_told_from_one_that_stopped_it(tmp_path: Path) -> None:
    """run_program names what a script left running when it ended (``cmd &``, never stopped: kit.scripts.ended
    fails on it), shown as typed; a child it killed as it ended (``kill $!``) is still exiting then, and gets
    LEFT_GRACE to be gone, so it does not count (audits of stops 69-71: ``ros2 topic hz ... &``)."""
    from ros2course.kit.programs import run_program  # noqa: PLC0415 - the course's kit, on the content root

    session = _program_session(tmp_path)
    env = {"PATH": "/usr/bin:/bin"}
    try:
        left = run_program(session, ["/bin/sh", "-c", "sleep 30 & echo started"], "leaves", env=env)
        assert left.returncode == 0 and len(left.left_running) == 1
        assert left.left_running_text() == "sleep 30"
        # a child that needs a moment to die after the script ended (a trap that sleeps, as a node shutting down)
        stopped = run_program(session, ["/bin/sh", "-c", "sh -c 'trap \"sleep 0.3; exit\" TERM; "
                                        "while :; do sleep 0.05; done' & sleep 0.2; kill $!"], "stops", env=env)
        assert stopped.returncode == 0 and stopped.left_running == ()
    finally:
        session.close()


def test_stdin_open_makes_a_question_wait_as_in_a_terminal(tmp_path: Path) -> None:
    """With ``stdin_open`` a program that asks something (``read``; ssh-keygen's passphrase prompt) waits for an
    answer nobody types, until its timeout; with /dev/null (the default) it reads end of file at once."""
    from ros2course.kit.programs import run_program  # noqa: PLC0415 - the course's kit, on the content root

    session = _program_session(tmp_path)
    env = {"PATH": "/usr/bin:/bin"}
    ask = ["/bin/sh", "-c", "read answer; echo done"]
    try:
        waited = run_program(session, ask, "asks-open", env=env, timeout=1.0, stdin_open=True)
        assert waited.timed_out and "done" not in waited.stdout
        at_once = run_program(session, ask, "asks-null", env=env, timeout=10.0)
        assert not at_once.timed_out and at_once.stdout.strip() == "done" and at_once.seconds < 10.0
    finally:
        session.close()
