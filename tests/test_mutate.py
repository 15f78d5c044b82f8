"""``ros2course dev mutate``: mutants of a lesson's reference graded through the batch engine (issue 24).

One smoke run on print-forever-node (5 of its node file's mutants, seed 3: three
killed, two survivors) in a private copy of the course, whose ``mutation.yaml``
triages one survivor and holds one stale entry; then the same command again
(everything from the cache), and a malformed ``mutation.yaml``. On the small lab course
(tests/data/lab_course): a check left out of its grader shows as a survivor, and adding the
check kills that mutant.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
import yaml

from ros2course.dev import mutants as mut
from ros2course.lesson import active_course
from ros2course.grade.results import CheckResult, LessonResult, Status

ROOT = Path(__file__).resolve().parent.parent
LESSON = "print-forever-node"
NODE_FILE = "src/python_package_with_a_node/python_package_with_a_node/print_forever_node.py"
TRIAGE = f"""\
files: ["{NODE_FILE}"]
survivors:
  - file: {NODE_FILE}
    key: 44dc05f30ba6
    original: "if __name__ == '__main__':"
    mutated: "if __name__ <= '__main__':"
    reason: "ros2 run starts the console_scripts entry point, which calls main() itself"
  - file: {NODE_FILE}
    key: 1aafc02750ae
    original: "self.print_count = 0"
    mutated: "self.print_count = 7"
    reason: "a line the reference no longer has: reported as stale"
"""

pytest.importorskip("universalmutator")


def _course(dest: Path, triage: str) -> Path:
    dest.mkdir(parents=True, exist_ok=True)
    shutil.copy(ROOT / "course.yaml", dest / "course.yaml")
    for part in ("chapters", "graders", "solutions", "tests/fixtures"):
        shutil.copytree(ROOT / part, dest / part, ignore=shutil.ignore_patterns(
            "__pycache__", "*.egg-info", "build", "install", "log"))
    (dest / "chapters" / "print-forever-node" / "mutation.yaml").write_text(triage, encoding="utf-8")
    return dest


def _result(lost: list[str], status: Status = Status.FAILED, message: str = "") -> LessonResult:
    checks = [CheckResult(c, c, 0 if c in lost else 2, 2, c not in lost, "", "", "") for c in ("build", "rate")]
    return LessonResult(LESSON, sum(c.points for c in checks), 4, status, checks if status.graded else [], message)


def test_classify() -> None:
    assert mut.classify(_result(["rate"])) == (mut.KILLED, ["rate"])
    assert mut.classify(_result([], Status.PASSED)) == (mut.SURVIVED, [])
    assert mut.classify(_result([], Status.NOT_GRADABLE, "colcon build failed for x")) == (mut.KILLED_BY_BUILD, ["build"])
    assert mut.classify(_result([], Status.NOT_GRADABLE, "timed out after 300 s"))[0] == mut.TIMED_OUT
    assert mut.classify(_result([], Status.GRADER_ERROR, "boom"))[0] == mut.GRADER_ERROR


def test_grader_errors_and_timeouts_are_graded_again(tmp_path: Path) -> None:
    """A resumed mutation batch regrades the mutants whose last outcome was a grader error or a timeout."""
    from ros2course.dev import mutate as batch_mutate
    from ros2course.report.gradebook import append_record, read_results

    results = tmp_path / "results.jsonl"
    rows = {"killed": _result(["rate"]), "error": _result([], Status.GRADER_ERROR, "boom"),
            "slow": _result([], Status.NOT_GRADABLE, "timed out after 300 s"), "survived": _result([], Status.PASSED)}
    for student, result in rows.items():
        result.student = student
        append_record(results, result)
    assert batch_mutate._forget_unfinished(results) == 2
    assert [r.student for r in read_results(results)] == ["killed", "survived"]
    assert batch_mutate._forget_unfinished(results) == 0 and len(read_results(results)) == 2
    assert batch_mutate._forget_unfinished(tmp_path / "none.jsonl") == 0


def test_sample_is_seeded_and_keys_ignore_line_numbers() -> None:
    mutants = [mut.Mutant("f.py", i, f"x = {i}", f"x = {i + 1}", f"x = {i + 1}\n") for i in range(20)]
    assert mut.sample_mutants(mutants, 5, 1) == mut.sample_mutants(mutants, 5, 1)
    assert len(mut.sample_mutants(mutants, 5, 1)) == 5 and mut.sample_mutants(mutants, None, 1) == mutants
    moved = mut.Mutant("f.py", 99, "x = 3", "x = 4", "\n\nx = 4\n")
    assert moved.key == mutants[3].key and moved.content_hash != mutants[3].content_hash


def test_the_lessons_own_files_are_mutated(tmp_path: Path) -> None:
    """By default the files the learner completes or writes, not the ones the starter gives whole."""
    from ros2course.dev.parity import case_workspace
    from ros2course.lesson.catalog import load_catalog

    lesson = load_catalog().get(LESSON)
    files = mut.lesson_files(lesson, case_workspace(lesson, "reference", tmp_path / "ref"), mut.MutationConfig())
    assert NODE_FILE in files and "src/python_package_with_a_node/package.xml" in files
    assert not any(f.endswith(("sample_python_node.py", "__init__.py", "setup.cfg")) for f in files), files
    # the finished files a starter hands out ("do not change it") are not the learner's work
    sas = load_catalog().get("sas-robot-driver")
    files = mut.lesson_files(sas, case_workspace(sas, "reference", tmp_path / "sas"), mut.MutationConfig())
    driver = "src/sas_robot_driver_myrobot/sas_robot_driver_myrobot/"
    assert f"{driver}robot_driver_myrobot.py" in files and f"{driver}sas_lite.py" not in files, files


@pytest.mark.ros
@pytest.mark.timeout(400)
def test_dev_mutate_smoke(cli, tmp_path: Path) -> None:
    course = _course(tmp_path / "course", TRIAGE)
    env = {"ROS2COURSE_CONTENT": str(course)}
    out = tmp_path / "out"
    args = ("dev", "mutate", LESSON, "--sample", "5", "--seed", "3", "--jobs", "2", "--out", str(out))
    proc = cli(*args, "--json", env=env, timeout=380)
    assert proc.returncode == 0, proc.stderr[-3000:]
    row = json.loads(proc.stdout)[0]
    assert (row["generated"], row["graded"], row["sampled"]) == (40, 5, True), row
    outcomes = {m["key"]: m for m in row["mutants"]}
    killed = [m for m in outcomes.values() if m["outcome"] == mut.KILLED]
    assert len(killed) == 3 and all(m["lost"] for m in killed), row["mutants"]
    assert {c for m in killed for c in m["lost"]} <= {"node_name", "log_format", "counts_from_zero", "rate",
                                                        "sigint_exit", "executable", "spins"}
    assert (row["survived"], row["triaged"]) == (2, 1), row
    assert row["score"] == pytest.approx(3 / 4)
    triaged = [m for m in row["mutants"] if m["triaged"]]
    assert triaged[0]["mutant"] == "if __name__ <= '__main__':"
    assert [s["original"] for s in row["stale"]] == ["self.print_count = 0"]
    survivor = next(m for m in row["mutants"] if m["outcome"] == mut.SURVIVED and not m["triaged"])
    diff = (out / "survivors" / LESSON / f"{survivor['key']}.diff").read_text(encoding="utf-8")
    assert f"--- a/{NODE_FILE}" in diff and "+if __name__ < '__main__':" in diff
    assert json.loads((out / "mutation.json").read_text())["lessons"][LESSON]["score"] == pytest.approx(0.75)
    # the score lives with the lesson, for dev validate and the course's readers
    record = json.loads((course / "chapters" / "print-forever-node" / mut.SCORE_FILE).read_text())
    assert (record["score"], record["killed"], record["triaged"]) == (pytest.approx(0.75), 3, 1), record
    assert record["survivors"] == [f"{survivor['file']}:{survivor['line']} ({survivor['key']})"]

    again = cli(*args, env=env, timeout=120)  # the table, every outcome from the cache
    assert again.returncode == 0, again.stderr[-3000:]
    assert "5 known from the cache, 0 to grade" in " ".join(again.stderr.split()), again.stderr
    assert "75%" in again.stdout and "stale" in again.stdout and "+if __name__ < '__main__':" in again.stdout


PY = "src/p/p/node.py"
NODE_SOURCE = """\
\"\"\"A node.\"\"\"

import rclpy


def main(args=None):
    \"\"\"Spin it.\"\"\"
    rclpy.init(args=args)
    node = rclpy.create_node('talker')
    node.get_logger().info('Started, publishing to /chatter.')
    rclpy.spin(node)


if __name__ == '__main__':
    main()
"""


def _mutant(source: str, rel: str, line: int, mutated: str | None, insert: bool = False) -> mut.Mutant:
    """A mutant of ``source`` replacing line ``line`` with ``mutated`` (None: deleting it), or inserting it there."""
    lines = source.splitlines()
    original = "" if insert else lines[line - 1]
    if insert:
        lines.insert(line - 1, mutated)
    elif mutated is None:
        del lines[line - 1]
    else:
        lines[line - 1] = mutated
    return mut.Mutant(rel, line, original, mutated or "", "\n".join(lines) + "\n")


DOCSTRING = mut.Rule(id="docstring-pass", reason="a docstring replaced by pass: documentation only", file="*.py",
                     original=r"""^\s*("{3}|'{3}).*("{3}|'{3})\s*$""", mutated=r"^\s*pass\s*$")
MAIN_BLOCK = mut.Rule(id="main-block", reason="ros2 run calls main() through the entry point", file=["*.py"],
                      block=r"^if __name__ == .__main__.:")
LOG_TEXT = mut.Rule(id="log-text", reason="the text of a log line the contract does not name",
                    original=r"get_logger\(\)\.(info|debug)\(", strings_only=True)
PACKAGE_TEXT = mut.Rule(id="package-metadata", reason="free text no program reads", file="*/package.xml",
                        original=r"^\s*<(description|maintainer|license|url)\b", set_aside=True)
OUTSIDE_LOOPS = mut.Rule(id="break-outside-loop", reason="bash ignores a break outside every loop", file="*.sh",
                         original=r"^\s*$", mutated=r"^\s*(break|continue);?\s*$", not_block=r"^\s*(for|while|until)\b")


def test_shell_no_ops_are_equivalent_mutants() -> None:
    """A discovery loop's counter values (never read) and a continue right before done change nothing bash
    does: dropped at generation like comment changes (inspect-topics' held-out seed 9 counted 9 such)."""
    script = ("#!/usr/bin/env bash\nros2 daemon start\nfor attempt in 1 2 3 4 5; do\n"
              "  ros2 node list | grep -q quote && break\n  sleep 1\ndone\necho over\n")
    loop = "for attempt in 1 2 3 4 5; do\n"

    def eq(old: str, new: str, source: str = script) -> bool:
        return mut.equivalent_mutant("cli/a.sh", source, source.replace(old, new, 1), old, new)

    assert eq(loop, "for attempt in 1 2 1 4 5; do\n") and eq(loop, "for attempt in 0 2 3 4 -1; do\n")
    assert not eq(loop, "for attempt in 1 2 3 4; do\n")  # one pass fewer
    assert not eq(loop, "for attempt in 1 2 (3-1) 4 5; do\n")  # a syntax error
    assert not eq(loop, "for attempt in 1 2 * 4 5; do\n")  # a glob: as many passes as files
    uses = script.replace("sleep 1", 'sleep "$attempt"')
    assert not eq(loop, "for attempt in 1 2 1 4 5; do\n", uses)  # the body reads the counter
    inserted = script.replace("  sleep 1\n", "  sleep 1\ncontinue;\n")
    assert mut.equivalent_mutant("cli/a.sh", script, inserted, "", "continue;\n")
    early = script.replace("  sleep 1\n", "continue;\n  sleep 1\n")
    assert not mut.equivalent_mutant("cli/a.sh", script, early, "", "continue;\n")  # skips the sleep
    after = script.replace("echo over\n", "continue;\necho over\n")
    assert not mut.equivalent_mutant("cli/a.sh", script, after, "", "continue;\n")  # outside every loop
    assert not mut.equivalent_mutant("cli/a.sh", script, inserted.replace("continue", "break"), "", "break;\n")


def test_the_fingerprint_is_the_same_wherever_the_course_lies(tmp_path: Path) -> None:
    """The course copied to another folder (the engine then outside its root, as for a wheel install, or a
    worktree): the same grader fingerprint, so recorded rows stay current there."""
    from ros2course.grade.fingerprint import grader_fingerprint
    from ros2course.lesson import use_course
    from ros2course.lesson.catalog import load_catalog

    here = grader_fingerprint(load_catalog().get(LESSON))
    use_course(_course(tmp_path / "elsewhere", TRIAGE))
    assert grader_fingerprint(load_catalog().get(LESSON)) == here


def test_held_out_samples_under_one_grader_are_pooled_never_the_best_shown_alone() -> None:
    """Three held-out samples, two under today's grader: the pooled figure counts both of those (23 + 29 of
    60), not the last one's 29 of 30, and leaves out the one graded under an earlier grader."""
    score = {"held_out": {"graded": 30, "killed_by_build": 0, "triaged": 0, "killed": 29, "seed": 16,
                          "fingerprint": "now", "earlier": [
                              {"seed": 2, "fingerprint": "old", "graded": 30, "counted": 30, "killed": 30},
                              {"seed": 15, "fingerprint": "now", "graded": 30, "counted": 30, "killed": 23}]}}
    pooled = mut.pooled_held_out(score, "now")
    assert (pooled.samples, pooled.killed, pooled.counted, pooled.seeds) == (2, 52, 60, (15, 16))
    assert round(pooled.score, 3) == 0.867 and mut.pooled_held_out(score, "other") is None
    assert mut.pooled_held_out({}, "now") is None


def test_a_holds_rule_covers_only_cases_that_stay_true() -> None:
    """``holds``: a parametrized case mutated into another true case (computed from its numbers as written) is
    matched; a false case, a call, a name or a tuple of another length is not, and `that` may name only the
    case's names (testing-your-nodes' library-case-still-true, decided after held-out seed 15)."""
    rule = mut.Rule(id="case-still-true", reason="another true case of (a + b)**2", file=["*/test_lib.py"],
                    original=r"^\s*\([^()]*\),\s*$", holds={"names": ["a", "b", "expected"],
                                                           "that": "(a + b) ** 2 == expected"})
    source = "import pytest\n@pytest.mark.parametrize(('a', 'b', 'expected'), [\n    (0.5, 0.25, 0.5625),\n])\n"
    rel = "src/p/test/test_lib.py"
    for true_case in ("    (0.-1, 0.25, 0.5625),", "    ( 0.25,0.5, 0.5625),", "    (0.5, -1.25, 0.5625),"):
        assert rule.matches(_mutant(source, rel, 3, true_case)), true_case
    for other in ("    (0.5, 0.25, 0.5626),", "    (0.5, 0.25),", "    (abs(-1), 0.25, 1.5625),",
                  "    (a, 0.25, 0.5625),", "    (1 / 0, 0.25, 0.5625),", "    (0.5, 0.25, 0.5625, 1),"):
        assert not rule.matches(_mutant(source, rel, 3, other)), other
    assert not rule.matches(_mutant(source, "src/p/test/test_other.py", 3, "    (0.25, 0.5, 0.5625),"))
    with pytest.raises(ValueError, match="which `names` does not list"):
        mut.Rule(id="x", reason="a reason long enough", holds={"names": ["a"], "that": "f(a) == b"})


def test_rules_match_kinds_of_mutant_mechanically() -> None:
    assert DOCSTRING.matches(_mutant(NODE_SOURCE, PY, 1, "pass"))
    assert DOCSTRING.matches(_mutant(NODE_SOURCE, PY, 7, "    pass"))
    assert not DOCSTRING.matches(_mutant(NODE_SOURCE, PY, 8, "    pass"))  # rclpy.init: not a docstring
    assert not DOCSTRING.matches(_mutant(NODE_SOURCE, "src/p/setup.cfg", 1, "pass"))  # not a .py file
    # the __main__ block: its header and the lines it opens, not main() itself
    assert MAIN_BLOCK.matches(_mutant(NODE_SOURCE, PY, 14, "if __name__ <= '__main__':"))
    assert MAIN_BLOCK.matches(_mutant(NODE_SOURCE, PY, 15, "    pass"))
    assert not MAIN_BLOCK.matches(_mutant(NODE_SOURCE, PY, 11, "    pass"))
    # a change inside a log call's text only; not its level, not the call
    assert LOG_TEXT.matches(_mutant(NODE_SOURCE, PY, 10, "    node.get_logger().info('Started, publishing to /chattr.')"))
    assert not LOG_TEXT.matches(_mutant(NODE_SOURCE, PY, 10, "    node.get_logger().debug('Started, publishing to /chatter.')"))
    assert not LOG_TEXT.matches(_mutant(NODE_SOURCE, PY, 10, "    pass"))
    assert not LOG_TEXT.matches(_mutant(NODE_SOURCE, PY, 9, "    node = rclpy.create_node('listener')"))
    # universalmutator inserts `break;` with the indentation of the line above: inside a loop it is not a no-op
    script = "#!/usr/bin/env bash\nros2 daemon start\nfor i in 1 2 3; do\n  ros2 node list && break\n  sleep 1\ndone\necho done\n"
    assert OUTSIDE_LOOPS.matches(_mutant(script, "cli/a.sh", 3, "break;", insert=True))
    assert not OUTSIDE_LOOPS.matches(_mutant(script, "cli/a.sh", 6, "  break;", insert=True))
    assert OUTSIDE_LOOPS.matches(_mutant(script, "cli/a.sh", 7, "break;", insert=True))
    # right under the loop's header it takes the header's indentation (none), yet bash runs it in the loop:
    # a shell loop is what lies between do and done (inspect-topics' 0173f16abe21 was killed, not a no-op)
    assert not OUTSIDE_LOOPS.matches(_mutant(script, "cli/a.sh", 4, "break;", insert=True))
    split = "#!/usr/bin/env bash\nwhile true\ndo\n  ros2 node list && break  # done? no\nbreak;\ndone\n"
    assert not OUTSIDE_LOOPS.matches(_mutant(split, "cli/a.sh", 5, "break;", insert=True))
    assert OUTSIDE_LOOPS.matches(_mutant(split + "echo over\n", "cli/a.sh", 7, "break;", insert=True))
    # a line inserted after a backslash joins the command above (`echo hi \\` + `break;` + `| age`): never a no-op
    piped = "#!/usr/bin/env bash\necho hi \\\n  | cat\n"
    assert not OUTSIDE_LOOPS.matches(_mutant(piped, "cli/a.sh", 3, "break;", insert=True))
    assert OUTSIDE_LOOPS.matches(_mutant(piped, "cli/a.sh", 4, "break;", insert=True))
    # a record without content is judged on the original file given
    bare = mut.Mutant(PY, 15, "    main()", "    pass", "")
    assert not MAIN_BLOCK.matches(bare) and MAIN_BLOCK.matches(bare, {PY: NODE_SOURCE})
    # set aside before sampling: never graded
    xml = "<package>\n  <description>A node</description>\n  <license>MIT</license>\n  <depend>rclpy</depend>\n</package>\n"
    mutants = [_mutant(xml, "src/p/package.xml", 2, "  <description>A nod</description>"),
               _mutant(xml, "src/p/package.xml", 3, "  <license>MI</license>"),
               _mutant(xml, "src/p/package.xml", 4, "  <depend>rclp</depend>")]
    kept, aside = mut.set_aside(mutants, mut.MutationConfig(rules=[PACKAGE_TEXT]))
    assert [m.line for m in kept] == [4] and [m.line for m in aside] == [2, 3]
    with pytest.raises(ValueError, match="matcher besides `file`"):
        mut.Rule(id="everything", reason="every mutant of the file", file="*.py")
    with pytest.raises(ValueError, match="not a regular expression"):
        mut.Rule(id="bad", reason="a broken expression", original="(")


def test_a_starter_line_rule_covers_only_the_lines_the_starter_gives_in_place() -> None:
    """``starter_line``: a line of the reference the starter gives as is, in the same place (issue 37). A line
    the learner changed (the TODO's) or wrote is not one, even when the same text sits elsewhere in the starter."""
    starter = "ros2 daemon start\nfor i in 1 2 3; do\n  sleep 1\ndone\n\n# TODO: add --verbose\nros2 topic info /t\n"
    reference = "ros2 daemon start\nfor i in 1 2 3; do\n  sleep 1\ndone\n\n# --verbose shows the QoS\nros2 topic info --verbose /t\nsleep 1\n"
    assert mut.starter_given_lines(tuple(reference.splitlines()), tuple(starter.splitlines())) == {1, 2, 3, 4, 5}
    rule = mut.Rule(id="given", reason="a line the starter gives as is", file="cli/*.sh", starter_line=True)
    rule._starters = {"cli/a.sh": starter.splitlines()}
    assert rule.matches(_mutant(reference, "cli/a.sh", 3, "  sleep 0"))
    assert rule.matches(_mutant(reference, "cli/a.sh", 5, "break;", insert=True))
    assert not rule.matches(_mutant(reference, "cli/a.sh", 7, "ros2 topic info /t"))  # the learner's line
    assert not rule.matches(_mutant(reference, "cli/a.sh", 8, "sleep 0"))  # same text, not the starter's place
    assert not rule.matches(_mutant(reference, "cli/b.sh", 3, "  sleep 0"))  # no starter copy of that file
    assert rule.covers_line("cli/a.sh", reference.splitlines(), 2)
    assert not rule.covers_line("cli/a.sh", reference.splitlines(), 8)


def test_entries_name_one_mutant_by_identity_and_rules_come_first(tmp_path: Path) -> None:
    guard = _mutant(NODE_SOURCE, PY, 14, "if __name__ <= '__main__':")
    spin = _mutant(NODE_SOURCE, PY, 11, "    pass")
    by_key = mut.TriageEntry(file=PY, key=spin.key, original="rclpy.spin(node)", mutated="pass",
                             reason="an entry by the mutant's key")
    by_line = mut.TriageEntry(file=PY, line=11, original="rclpy.spin(node)", mutated="pass",
                              reason="an entry by line number, original and mutated line")
    assert by_key.matches(spin) and by_line.matches(spin)
    moved = mut.Mutant(PY, 12, spin.original, spin.mutated, "")
    assert by_key.matches(moved) and not by_line.matches(moved)  # a key survives lines added above
    assert not by_key.matches(_mutant(NODE_SOURCE, PY, 11, "    rclpy.spin(None)"))
    # never by line text alone; a key must be that of the lines shown with it
    with pytest.raises(ValueError, match="never by line text alone"):
        mut.TriageEntry(file=PY, line="rclpy.spin(node)", mutant="pass", reason="the old text form")
    with pytest.raises(ValueError, match="a rule"):
        mut.TriageEntry(file=PY, line="<description>x</description>", every_mutant=True, reason="a whole line")
    with pytest.raises(ValueError, match="is not the key of"):
        mut.TriageEntry(file=PY, key=guard.key, original="rclpy.spin(node)", mutated="pass", reason="a wrong key")
    config = mut.MutationConfig(rules=[MAIN_BLOCK], survivors=[
        by_key, mut.TriageEntry(file=PY, key=guard.key, reason="the guard, also covered by the rule")])
    assert config.triage(guard) == (MAIN_BLOCK.reason, "rule:main-block")
    assert config.triage(spin) == (by_key.reason, "entry")
    graded = [mut.Graded(guard, mut.SURVIVED, []), mut.Graded(spin, mut.SURVIVED, []),
              mut.Graded(_mutant(NODE_SOURCE, PY, 15, "    pass"), mut.KILLED, ["spins"])]
    stale = mut.apply_triage(graded, config, [guard, spin])
    assert [g.triaged_by for g in graded] == ["rule:main-block", "entry", ""]
    assert graded[2].rule == "main-block"  # a killed mutant a rule matches is shown to the author
    assert stale == []
    found = mut.LessonMutation("demo", 3, graded, stale, False)
    assert (found.triaged, found.by_rule, found.score) == (2, 1, 1.0)
    assert found.rules_on_killed() == [f"main-block: {PY}:15 ({graded[2].mutant.key})"]
    lonely = mut.TriageEntry(file=PY, line=3, original="import rclpy", mutated="pass", reason="matches nothing now")
    assert mut.apply_triage(graded, mut.MutationConfig(survivors=[lonely]), [guard, spin]) == [lonely]


def _demo_lesson(tmp_path: Path, contract: str, triage: str):
    from types import SimpleNamespace

    folder = tmp_path / "chapters" / "13-demo"
    folder.mkdir(parents=True)
    (folder / "contract.yaml").write_text(contract, encoding="utf-8")
    (folder / "mutation.yaml").write_text(triage, encoding="utf-8")
    (folder / "lesson.yaml").write_text("id: demo\n", encoding="utf-8")
    reference = tmp_path / "reference"
    (reference / "src" / "p" / "p").mkdir(parents=True)
    (reference / PY).write_text(NODE_SOURCE, encoding="utf-8")
    lesson = SimpleNamespace(id="demo", course=active_course(), folder=folder, grader="print_forever_node", packages=["p"], folders=[],
                             workspace_paths=["src/p"])
    return lesson, reference


CONTRACT = """\
lesson: demo
requirements:
  - id: logs-start
    says: "it logs 'Started' with node.get_logger().info when it starts"
    from: contract
    checks: [log]
  - id: main-spins
    says: "main() calls rclpy.init() and spins the node (rclpy.spin)"
    from: instructions
    checks: [spins]
"""


def test_a_rule_may_never_cover_a_line_that_implements_a_contract_requirement(tmp_path: Path) -> None:
    triage = """\
rules:
  - id: docstring-pass
    reason: "a docstring replaced by pass: documentation only"
    original: '^\\s*("{3}|''{3}).*("{3}|''{3})\\s*$'
    mutated: '^\\s*pass\\s*$'
  - id: log-text
    reason: "the text of a log line the contract does not name"
    original: 'get_logger\\(\\)\\.info\\('
    strings_only: true
  - id: main-block
    reason: "ros2 run calls main() through the console_scripts entry point"
    block: "^if __name__ == .__main__.:"
"""
    lesson, reference = _demo_lesson(tmp_path, CONTRACT, triage)
    problems = mut.rule_conflicts(lesson, reference=reference)
    triage_file = lesson.folder / "mutation.yaml"
    contract_file = lesson.folder / "contract.yaml"
    # the log line implements logs-start (it names get_logger().info); main() under the guard contains `main()`
    assert problems == [
        f"{triage_file}:6: rule log-text covers {PY}:10 `node.get_logger().info('Started, publishing to /chatter.')`, "
        f"which implements requirement logs-start ({contract_file}:3: names `Started`)",
        f"{triage_file}:10: rule main-block covers {PY}:15 `main()`, which implements requirement main-spins "
        f"({contract_file}:7: names `main()`)"], problems
    # the contract names main-spins' lines itself: main()'s own lines, not the call under the guard
    named = CONTRACT + """\
    code:
      - file: "src/*/node.py"
        line: '^def main\\(|rclpy\\.(init|spin)\\('
"""
    (lesson.folder / "contract.yaml").write_text(named, encoding="utf-8")
    assert [p.split(": rule ")[1].split()[0] for p in mut.rule_conflicts(lesson, reference=reference)] == ["log-text"]
    assert any("rule log-text covers" in p for p in mut.triage_problems(lesson, reference=reference))
    # a starter that gives the log line as is: the learner never writes it, so naming `Started` does not make it
    # logs-start's (a given line the lesson makes a requirement is marked with `code:`, as main-spins' lines are)
    lesson.starter_dir = tmp_path / "starter"
    (lesson.starter_dir / "src" / "p" / "p").mkdir(parents=True)
    (lesson.starter_dir / PY).write_text(NODE_SOURCE, encoding="utf-8")
    assert mut.rule_conflicts(lesson, reference=reference) == []
    # a contract that does not load vouches for no rule: one problem naming its error, never a silent []
    (lesson.folder / "contract.yaml").write_text("lesson: demo\nrequirements: [\n", encoding="utf-8")
    problems = mut.rule_conflicts(lesson, reference=reference)
    assert len(problems) == 1 and "rules not checked against the contract" in problems[0], problems
    assert f"{contract_file}:" in problems[0] and "not valid YAML" in problems[0], problems


def test_the_held_out_sample_is_disjoint_from_the_first_and_seeded() -> None:
    mutants = [mut.Mutant("f.py", i, f"x = {i}", f"x = {i + 1}", f"x = {i + 1}\\n") for i in range(80)]
    first = mut.sample_mutants(mutants, 30, 1)
    held = mut.held_out_sample(mutants, first, 30, 2)
    assert len(held) == 30 and not {m.key for m in held} & {m.key for m in first}
    assert held == mut.held_out_sample(mutants, first, 30, 2) and held != mut.held_out_sample(mutants, first, 30, 3)
    # the first sample as its run recorded it is left out too (the mutants may have changed since)
    recorded = {m.key for m in held[:5]}
    again = mut.held_out_sample(mutants, first, 30, 2, recorded)
    assert not {m.key for m in again} & (recorded | {m.key for m in first})
    # fewer left than asked: every one of them
    assert len(mut.held_out_sample(mutants[:40], mut.sample_mutants(mutants[:40], 30, 1), 30, 2)) == 10


def test_a_held_out_run_is_recorded_beside_the_first_and_shown(tmp_path: Path) -> None:
    """write_score then write_held_out: both figures in mutation-score.json, outcomes by key, the doc's cell and
    dev validate's line say the held-out score; a new first sample drops the held-out one."""
    import importlib.util
    from types import SimpleNamespace

    lesson = SimpleNamespace(id="demo-lesson", course=active_course(), folder=tmp_path, grader="print_forever_node",
                             packages=["python_package_with_a_node"], folders=[])
    (tmp_path / "lesson.yaml").write_text("id: demo-lesson\\n")
    mutants = [mut.Mutant("f.py", i, f"x = {i}", f"x = {i + 1}", "") for i in range(60)]

    def run(part: list[mut.Mutant], survived: int, held_out: bool) -> mut.LessonMutation:
        graded = [mut.Graded(m, mut.SURVIVED if i < survived else mut.KILLED, [] if i < survived else ["rate"])
                  for i, m in enumerate(part)]
        return mut.LessonMutation("demo-lesson", 60, graded, [], True, sample=30, seed=2 if held_out else 1,
                                  held_out=held_out, pool=30)

    assert mut.write_held_out(lesson, run(mutants[30:], 3, True)) is None  # no first sample recorded yet
    mut.write_score(lesson, run(mutants[:30], 0, False))
    assert mut.recorded_first_sample(lesson) == {m.key for m in mutants[:30]}
    mut.write_score(lesson, run(mutants[30:], 3, True))
    row = mut.recorded_score(lesson)
    assert (row.tuned, row.counted) == (1.0, 30) and (row.held_out.tuned, row.held_out.counted) == (0.9, 30)
    assert len(row.held_out.data["survivors"]) == 3 and row.held_out.data["seed"] == 2
    outcomes = json.loads((tmp_path / mut.OUTCOMES_FILE).read_text())
    assert {m["key"] for m in outcomes["held_out"]["mutants"]} == {m.key for m in mutants[30:]}
    assert "; held-out 90 % of 30" in mut.score_text(lesson)
    assert "held-out sample 90 % (27 of 30 counted, 90 % raw, 3 survivor(s) no rule covers)" in mut.describe_score(lesson)
    spec = importlib.util.spec_from_file_location("grader_strength", ROOT / "benchmarks" / "grader_strength.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module._held_out_cell(row) == ("90 % of 30 counted (raw 90 %; 30 graded of the 30 no earlier sample took, "
                                          "seed 2; 3 uncovered)")
    small = mut.RecordedScore({"graded": 12, "pool": 12, "seed": 2, "survivors": [], "date": "2026-11-20"}, 12,
                              1.0, 1.0, "stale: graded on 2026-11-20 under grader fingerprint 0, now 1")
    assert module._held_out_cell(SimpleNamespace(held_out=small, stale="", data={})) == (
        "100 % of 12 counted (raw 100 %; 12 graded of the 12 no earlier sample took, seed 2; 0 uncovered) "
        "(too small to judge: 12 < 20; only 12 were left to draw) **stale** (2026-11-20)")
    # the row says why the lesson cannot reach 20 (issue 37): what the sample's graded mutants became
    assert module._too_small(2, {"graded": 30, "pool": 798, "sample": 30, "killed_by_build": 28}) == (
        " (too small to judge: 2 < 20; 28 of 30 broke the build (caught before any check))")
    assert module._too_small(4, {"graded": 30, "pool": 46, "sample": 30, "killed_by_build": 11, "triaged": 15}) == (
        " (too small to judge: 4 < 20; 11 of 30 broke the build (caught before any check); 15 triaged as equivalent)")
    assert module._held_out_cell(SimpleNamespace(held_out=None, stale="", data={})) == "not drawn"
    # a first sample measured again drops its held-out one; what the earlier held-out samples scored still shows
    again = SimpleNamespace(held_out=None, stale="", data={"fingerprint": "f2", mut.EARLIER_KEY: [
        {"seed": 2, "date": "2026-11-26", "fingerprint": "f1", "counted": 28, "score": 0.82}]})
    assert module._held_out_cell(again) == ("not drawn since the first sample was measured again; earlier held-out "
                                            "samples: seed 2 (2026-11-26): 82 % of 28 under an earlier grader")
    # a re-triage keeps the held-out sample as graded; a new first sample drops it
    mut.write_score(lesson, run(mutants[:30], 0, False), keep_held_out=True)
    assert mut.recorded_score(lesson).held_out is not None
    mut.write_score(lesson, run(mutants[:30], 0, False))
    assert mut.recorded_score(lesson).held_out is None
    assert "held_out" not in json.loads((tmp_path / mut.OUTCOMES_FILE).read_text())
    # ... but what the dropped held-out sample scored stays on record, and is shown beside the next one's
    earlier = json.loads((tmp_path / mut.SCORE_FILE).read_text())[mut.EARLIER_KEY]
    assert [(e["seed"], e["counted"], e["killed"]) for e in earlier] == [(2, 30, 27)]
    # a re-triage of that first sample keeps what the dropped held-out sample showed and scored (it dropped
    # both once, and the next held-out sample could have drawn mutants whose survival had been seen)
    shown = mut.recorded_held_out(lesson)
    assert shown == {m.key for m in mutants[30:]}
    mut.write_score(lesson, run(mutants[:30], 0, False), keep_held_out=True)
    assert mut.recorded_held_out(lesson) == shown
    assert json.loads((tmp_path / mut.SCORE_FILE).read_text())[mut.EARLIER_KEY] == earlier
    later = run(mutants[30:], 6, True)
    later.seed = 3
    mut.write_score(lesson, later)
    row = mut.recorded_score(lesson)
    assert row.held_out.tuned == 0.8 and [e["seed"] for e in row.held_out.data["earlier"]] == [2]
    assert mut.EARLIER_KEY not in json.loads((tmp_path / mut.SCORE_FILE).read_text())
    cell = module._held_out_cell(row)
    assert cell.endswith("; earlier held-out samples: seed 2 (%s): 90 %% of 30; **all 2 held-out samples under this "
                         "grader together: 85 %% of 60 counted** (seeds 2, 3)" % earlier[0]["date"]), cell
    assert mut.score_text(lesson).endswith("; held-out 80 % of 30 (all 2 under this grader: 85 % of 60)")
    # a draw that finds no mutant left (every one shown by the first sample or a held-out one) says so,
    # never "n/a of 0": the README's cell, dev validate's line and the doc's cell
    spent = mut.LessonMutation("demo-lesson", 60, [], [], True, sample=30, seed=4, held_out=True, pool=0)
    mut.write_score(lesson, spent)
    assert mut.score_text(lesson).endswith("; held-out: none left to draw (all 2 under this grader: 85 % of 60)")
    assert "no held-out mutant left to draw" in mut.describe_score(lesson)
    assert module._held_out_cell(mut.recorded_score(lesson)).startswith("none left to draw: ")


@pytest.mark.parametrize("triage,words", [
    ("survivors:\n  - file: x.py\n    reason: too short\n", "survivors.0"),
    ("survivors: [\n", "not valid YAML"),
    ("- just a list\n", "expected a mapping"),
    ("rules:\n  - use: no-such-rule\n", "use: 'no-such-rule' is not a rule of"),
    ("rules:\n  - use: docstring-pass\n    reason: mine\n", "'use' takes a shared rule as it is"),
])
def test_a_bad_mutation_yaml_is_a_one_line_error(cli, tmp_path: Path, triage: str, words: str) -> None:
    course = _course(tmp_path / "course", triage)
    proc = cli("dev", "mutate", LESSON, "--sample", "1", "--out", str(tmp_path / "out"),
               env={"ROS2COURSE_CONTENT": str(course)})
    assert proc.returncode == 5, proc.stderr
    error = [line for line in proc.stderr.splitlines() if line.startswith("error:")]
    assert len(error) == 1 and "mutation.yaml" in error[0] and words in error[0], proc.stderr
    assert "hint:" in proc.stderr and "Traceback" not in proc.stderr


def test_dev_validate_shows_the_lessons_last_mutation_score(tmp_path: Path) -> None:
    """The raw kill rate beside the score after triage, a denominator too small to judge by, and a row
    measured under another grader fingerprint (or before fingerprints) marked stale with its date."""
    from types import SimpleNamespace

    from ros2course.grade.fingerprint import grader_fingerprint

    lesson = SimpleNamespace(id="demo-lesson", course=active_course(), folder=tmp_path, grader="print_forever_node",
                             packages=["python_package_with_a_node"], folders=[])
    (tmp_path / "lesson.yaml").write_text("id: demo-lesson\n")
    assert mut.describe_score(lesson) == \
        "demo-lesson: grader strength not measured (ros2course dev mutate demo-lesson --sample 30)"
    record = {"generated": 57, "graded": 20, "sampled": True, "killed": 11, "killed_by_build": 4, "survived": 5,
              "triaged": 4, "timed_out": 0, "grader_error": 0, "score": 11 / 12, "seconds": 80.0,
              "date": "2026-11-23", "course_version": mut.course_version(), "survivors": ["a.py:3 (abc)"],
              "fingerprint": grader_fingerprint(lesson)}
    (tmp_path / mut.SCORE_FILE).write_text(json.dumps(record))
    line = mut.describe_score(lesson)
    assert line.startswith("demo-lesson: grader strength 92 % after triage, 69 % raw (11 of 12 counted mutants killed; "
                           "20 of 57 mutants")
    assert "1 survivor(s) not triaged" in line and "12 counted mutants are too few to judge by" in line
    assert "stale" not in line and "no held-out sample" in line
    assert mut.score_text(lesson) == "raw 69 %, triaged 92 % of 12 counted (too small)"
    record["fingerprint"] = "0123456789abcdef"
    (tmp_path / mut.SCORE_FILE).write_text(json.dumps(record))
    assert "stale: graded on 2026-11-23 under grader fingerprint 0123456789abcdef, now " in mut.describe_score(lesson)
    assert mut.score_text(lesson).endswith("; stale")
    del record["fingerprint"]
    (tmp_path / mut.SCORE_FILE).write_text(json.dumps(record))
    assert "stale: graded on 2026-11-23, before grader fingerprints were recorded" in mut.describe_score(lesson)


def test_the_grader_fingerprint_follows_the_grader_its_helpers_and_the_lesson(tmp_path: Path) -> None:
    from types import SimpleNamespace

    from ros2course.grade.fingerprint import grader_files, grader_fingerprint

    lesson = SimpleNamespace(id="demo", course=active_course(), folder=tmp_path, grader="cpp_node", packages=["cpp_package_with_a_node"],
                             folders=[])
    (tmp_path / "lesson.yaml").write_text("id: demo\n")
    names = {p.name for p in grader_files(lesson)}
    # cpp_node imports print_forever_node's steps: a change there changes what cpp-node's figure was measured on
    assert {"cpp_node.py", "print_forever_node.py", "lesson.yaml", "session.py", "nodes.py", "CMakeLists.txt"} <= names
    before = grader_fingerprint(lesson)
    assert before == grader_fingerprint(lesson) and len(before) == 16
    (tmp_path / "lesson.yaml").write_text("id: demo\ntitle: changed\n")
    assert grader_fingerprint(lesson) != before


def test_the_course_fingerprint_changes_with_the_lesson_and_not_with_the_engine(tmp_path: Path, monkeypatch) -> None:
    """Recorded beside the grader fingerprint, it tells an engine-only change from a change of the lesson."""
    from types import SimpleNamespace

    from ros2course.grade import fingerprint

    lesson = SimpleNamespace(id="demo", course=active_course(), folder=tmp_path, grader="cpp_node", packages=["cpp_package_with_a_node"],
                             folders=[])
    (tmp_path / "lesson.yaml").write_text("id: demo\n")
    grader, course = fingerprint.grader_fingerprint(lesson), fingerprint.course_fingerprint(lesson)
    assert grader != course and set(fingerprint.measurement(lesson)) == {"date", "fingerprint", "course_fingerprint"}
    real = fingerprint._file_digest
    monkeypatch.setattr(fingerprint, "_file_digest",  # every engine module "edited"
                        lambda path: real(path) + (b"x" if "/kit/" in str(path) or "/run/" in str(path) else b""))
    assert fingerprint.grader_fingerprint(lesson) != grader and fingerprint.course_fingerprint(lesson) == course
    (tmp_path / "lesson.yaml").write_text("id: demo\ntitle: changed\n")
    assert fingerprint.course_fingerprint(lesson) != course


def test_the_fingerprint_covers_the_engine_modules_the_grader_reaches_and_no_others(tmp_path: Path) -> None:
    """The engine part of the fingerprint is the import closure of the grader and of the grading engine (read from
    the code, function-level imports included): the script lessons' kit step is in inspect-services' fingerprint and
    not in lifecycle-node's, so adding a step for one lesson leaves the other's figures current."""
    from ros2course.grade.fingerprint import engine_modules, grader_files
    from ros2course.lesson.catalog import load_catalog

    catalog = load_catalog()
    def engine_names(lesson_id: str) -> set[str]:
        return {"/".join(p.parts[-2:]) for p in grader_files(catalog.get(lesson_id)) if "graders" not in p.parts
                and p.suffix == ".py"}

    services, lifecycle = engine_names("inspect-services"), engine_names("lifecycle-node")
    assert {"kit/scripts.py", "kit/mystery.py", "grade/session.py", "grade/engine.py", "run/process.py",
            "kit/__init__.py"} <= services
    assert "kit/scripts.py" not in lifecycle and "kit/mystery.py" not in lifecycle
    assert {"grade/session.py", "run/probes.py", "kit/__init__.py"} <= lifecycle
    # a module reached only through a function-level import of a reached module is found too
    module = tmp_path / "grader.py"
    module.write_text("def grade(s):\n    from ros2course.kit import scripts  # noqa\n    return scripts\n")
    assert "scripts.py" in {p.name for p in engine_modules([module])}


def test_the_committed_grader_strength_doc_is_made_from_the_recorded_runs(tmp_path: Path) -> None:
    """docs/grader-strength.md is regenerated from each lesson's mutation-score.json (and steadiness.json) and
    compared: the figure can only say what the records say (`python benchmarks/grader_strength.py --doc-only`)."""
    import importlib.util

    from ros2course.lesson.catalog import load_catalog

    spec = importlib.util.spec_from_file_location("grader_strength", ROOT / "benchmarks" / "grader_strength.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    doc = tmp_path / "grader-strength.md"
    module.write_doc(doc, [], load_catalog().ids(), 30, 1, 2,
                     speedup=next((line for line in (ROOT / "docs" / "grader-strength.md").read_text(
                         encoding="utf-8").splitlines() if line.startswith("Parallel speed-up")), ""))
    assert doc.read_text(encoding="utf-8") == (ROOT / "docs" / "grader-strength.md").read_text(encoding="utf-8"), \
        "run `python benchmarks/grader_strength.py --doc-only`"


@pytest.mark.ros
@pytest.mark.timeout(600)
def test_a_check_left_out_of_a_grader_shows_its_survivor_and_adding_it_kills_it(cli, tmp_path: Path) -> None:
    """issue 24, on issue 18's small course: the lab course's grader has no Ctrl+C check, so the mutant
    deleting the ExternalShutdownException import (Ctrl+C then ends in a NameError traceback) gets full
    marks; with the check added to the grader, the same mutant is killed by it."""
    course = tmp_path / "lab_course"
    shutil.copytree(ROOT / "tests" / "data" / "lab_course", course,
                    ignore=shutil.ignore_patterns("__pycache__", "build", "install", "log"))
    node_file = "src/hello_node_pkg/hello_node_pkg/hello_node.py"
    (course / "chapters" / "10-hello-node" / "mutation.yaml").write_text(
        f'files: ["{node_file}"]\n', encoding="utf-8")
    args = ("dev", "mutate", "hello-node", "--course", str(course), "--jobs", "2", "--out", str(tmp_path / "out"),
            "--json")
    import_line = "from rclpy.executors import ExternalShutdownException"

    def the_import_mutant() -> dict:
        proc = cli(*args, env={"ROS2COURSE_CONTENT": ""}, timeout=280)
        assert proc.returncode == 0, proc.stderr[-3000:]
        mutants = json.loads(proc.stdout)[0]["mutants"]
        return next(m for m in mutants if m["original"] == import_line)

    before = the_import_mutant()
    assert before["outcome"] == mut.SURVIVED, before

    grader = course / "graders" / "hello_node.py"
    text = grader.read_text(encoding="utf-8")
    text = text.replace(']\n\n\ndef grade', '    Check("sigint_exit", "Ctrl+C ends it with exit code 0 and no traceback", 1,\n'
                                             '          needs=("executable",)),\n]\n\n\ndef grade', 1)
    text = text.replace('kit.start_node(s, "node_name", path, NODE)',
                        'kit.start_node(s, "node_name", path, NODE, sigint_check="sigint_exit")')
    assert text.count("sigint_exit") == 2
    grader.write_text(text, encoding="utf-8")

    after = the_import_mutant()  # the grader changed: its cache entries do not apply
    assert after["outcome"] == mut.KILLED and after["lost"] == ["sigint_exit"], after


def test_comment_and_same_element_mutants_are_dropped_as_equivalent() -> None:
    script = "#!/usr/bin/env bash\n# 2. A geometry message\nros2 interface show geometry_msgs/msg/Point\n"
    assert mut.equivalent_mutant("cli/a.sh", script, script.replace("# 2.", "# 1."), "# 2. A geometry message",
                                 "# 1. A geometry message")
    # the #! line is read by the kernel, a command line by bash, and in a here-document '#' is data
    assert not mut.equivalent_mutant("cli/a.sh", script, script.replace("#!/usr", "#!+usr"),
                                     "#!/usr/bin/env bash", "#!+usr/bin/env bash")
    assert not mut.equivalent_mutant("cli/a.sh", script, script.replace("Point", "Pose"),
                                     "ros2 interface show geometry_msgs/msg/Point",
                                     "ros2 interface show geometry_msgs/msg/Pose")
    heredoc = "cat <<EOF\n# a line of data\nEOF\n"
    assert not mut.equivalent_mutant("cli/b.sh", heredoc, heredoc.replace("# a", "# b"), "# a line of data",
                                     "# b line of data")
    assert mut.equivalent_mutant("src/p/action/Move.action", "# metres\nfloat64 x\n", "# metrs\nfloat64 x\n",
                                 "# metres", "# metrs")
    toml = '# installable with pip (ch. 2.6)\n[project]\nname = "p"\n'
    assert mut.equivalent_mutant("python/p/pyproject.toml", toml, toml.replace("2.6", "1.6"),
                                 "# installable with pip (ch. 2.6)", "# installable with pip (ch. 1.6)")
    assert not mut.equivalent_mutant("python/p/pyproject.toml", toml, toml.replace('"p"', '""'),
                                     'name = "p"', 'name = ""')
    xml = '<?xml version="1.0"?>\n<package format="3">\n  <name>p</name>\n  <!-- built first -->\n</package>\n'
    same = xml.replace("<!-- built first -->", "<!-- built (1-1) -->").replace("</name>\n", "</name>\nbreak;\n")
    assert mut.equivalent_mutant("src/p/package.xml", xml, same, "", "break;")
    assert not mut.equivalent_mutant("src/p/package.xml", xml, xml.replace(">p<", ">q<"), "", "")
    # text inside an element that has children is read by neither catkin_pkg nor Fast DDS
    assert mut.equivalent_mutant("src/p/package.xml", xml, xml.replace('format="3">', 'format="3">='), "", "")
    assert not mut.equivalent_mutant("src/p/package.xml", xml, xml.replace("<name>", "<=name>"), "", "")
    # a package.xml that no longer parses is not a program (colcon rejects it before any check): invalid
    assert mut.invalid_mutant("src/p/package.xml", xml.replace("<name>", "<=name>"))
    assert not mut.invalid_mutant("src/p/package.xml", xml.replace(">p<", ">q<"))
    assert not mut.invalid_mutant("src/p/setup.py", "def (")  # universalmutator's Python handler judges .py


def test_every_lessons_mutation_yaml_is_valid() -> None:
    """Each lesson's triage parses (TriageEntry's rules) and names files of the reference: a broken one would
    only show when someone runs dev mutate on that lesson."""
    from ros2course.lesson.catalog import load_catalog

    catalog = load_catalog()
    checked = 0
    for lesson_id in catalog.ids():
        lesson = catalog.get(lesson_id)
        if not mut.triage_path(lesson).is_file():
            continue
        config = mut.load_config(lesson)
        for entry in config.survivors:
            assert (ROOT / "solutions" / entry.file).is_file(), f"{lesson_id}: {entry.file}"
        # a rule never covers a line that implements a requirement of the lesson's contract (issue 37)
        assert not mut.rule_conflicts(lesson, config), "\n".join(mut.rule_conflicts(lesson, config))
        checked += 1
    assert checked >= 20
    # the course's shared rules (chapters/mutation-rules.yaml): each one used by a lesson, none left behind
    library = mut.rule_library(ROOT / "chapters")
    used = {item["use"] for lesson_id in catalog.ids() if mut.triage_path(catalog.get(lesson_id)).is_file()
            for item in (yaml.safe_load(mut.triage_path(catalog.get(lesson_id)).read_text()) or {}).get("rules") or []
            if isinstance(item, dict) and "use" in item}
    assert library and set(library) == used, sorted(set(library) ^ used)


def test_a_second_held_out_sample_leaves_out_every_mutant_an_earlier_one_showed(tmp_path: Path) -> None:
    """Once its survivors were looked at (and rules written from them), a held-out sample is tuned: the next
    held-out sample is drawn from the mutants neither the first sample nor any earlier held-out one took."""
    from types import SimpleNamespace

    lesson = SimpleNamespace(id="demo-lesson", course=active_course(), folder=tmp_path, grader="print_forever_node",
                             packages=["python_package_with_a_node"], folders=[])
    (tmp_path / "lesson.yaml").write_text("id: demo-lesson\n")
    mutants = [mut.Mutant("f.py", i, f"x = {i}", f"x = {i + 1}", "") for i in range(100)]

    def run(part: list[mut.Mutant], seed: int, held_out: bool) -> mut.LessonMutation:
        graded = [mut.Graded(m, mut.KILLED, ["rate"]) for m in part]
        return mut.LessonMutation("demo-lesson", 100, graded, [], True, sample=30, seed=seed, held_out=held_out,
                                  pool=70)

    first = mut.sample_mutants(mutants, 30, 1)
    mut.write_score(lesson, run(first, 1, False))
    second = mut.held_out_sample(mutants, first, 30, 2, mut.recorded_first_sample(lesson) | mut.recorded_held_out(lesson))
    mut.write_score(lesson, run(second, 2, True))
    assert mut.recorded_held_out(lesson) == {m.key for m in second}
    taken = mut.recorded_first_sample(lesson) | mut.recorded_held_out(lesson)
    third = mut.held_out_sample(mutants, first, 30, 3, taken)
    assert not {m.key for m in third} & taken and len(third) == 30
    mut.write_score(lesson, run(third, 3, True))
    # the third records the second as earlier, so a fourth leaves out both
    assert mut.recorded_held_out(lesson) == {m.key for m in second} | {m.key for m in third}
    fourth = mut.held_out_sample(mutants, first, 30, 4, mut.recorded_first_sample(lesson) | mut.recorded_held_out(lesson))
    assert len(fourth) == 10 and not {m.key for m in fourth} & ({m.key for m in second} | {m.key for m in third})
    mut.write_score(lesson, run(fourth, 4, True))
    # the first sample graded again (a new grader fingerprint) drops the held-out figures, never what they showed
    mut.write_score(lesson, run(first, 1, False))
    assert "held_out" not in mut.read_json_object(tmp_path / mut.SCORE_FILE)
    assert mut.recorded_held_out(lesson) == {m.key for m in second} | {m.key for m in third} | {m.key for m in fourth}
    fifth = mut.held_out_sample(mutants, first, 30, 5, mut.recorded_first_sample(lesson) | mut.recorded_held_out(lesson))
    assert not fifth


def _family_mutants(generate, folder: Path, text: str, lines: tuple[int, ...]) -> tuple[list, set]:
    """A family's mutants of ``text`` (written to ``folder/node.py``), checked as every family's must be: the same
    list on a second call, no two alike, each compiling, changing the file, on one of ``lines``; with the
    ``(line, original, mutated)`` edits (stripped) they make."""
    (folder / "node.py").write_text(text)
    made = generate(folder, "node.py")
    assert made == generate(folder, "node.py")
    assert len({m.content for m in made}) == len(made)
    for m in made:
        compile(m.content, "node.py", "exec")
        assert m.content != text and m.file == "node.py" and m.line in lines
    return made, {(m.line, m.original.strip(), m.mutated.strip()) for m in made}


def test_cosmic_ray_mutants_are_another_tools_edits_compiled_and_fixed_in_order(tmp_path: Path) -> None:
    """The second family (issue 37: fresh held-out pools): cosmic-ray's core operators on a Python file, in a
    fixed order; none that fails to compile or compiles to the original's bytecode; an edit universalmutator
    also makes has the same key, so no sample draws it twice."""
    pytest.importorskip("cosmic_ray")
    made, edits = _family_mutants(mut.generate_cosmic_ray_mutants, tmp_path,
                                  "def ready(count):\n    if count == 2:\n        return True\n    return count * 3 > 4\n",
                                  (2, 3, 4))
    assert len(made) > 10
    assert (2, "if count == 2:", "if count != 2:") in edits  # ReplaceComparisonOperator_Eq_NotEq
    assert (3, "return True", "return False") in edits  # ReplaceTrueWithFalse
    same = mut.Mutant("node.py", 2, "    if count == 2:", "    if count != 2:", "")
    assert same.key in {m.key for m in made}


def test_mutmut_mutants_are_a_third_tools_edits_compiled_and_fixed_in_order(tmp_path: Path) -> None:
    """The third family (fresh held-out pools once cosmic-ray's are spent too): mutmut 2's mutations of a
    Python file, one edit each, in mutmut's order; none that fails to compile or compiles to the original's
    bytecode; an edit another tool also makes has the same key."""
    pytest.importorskip("mutmut")
    text = "TOPIC = '/initialpose'\n\n\ndef ready(count):\n    if count < 2:\n        return False\n    return count * 3 > 4\n"
    made, edits = _family_mutants(mut.generate_mutmut_mutants, tmp_path, text, (1, 5, 6, 7))
    assert len(made) >= 6
    for m in made:
        assert sum(a != b for a, b in zip(m.content.splitlines(), text.splitlines())) == 1
    assert (1, "TOPIC = '/initialpose'", "TOPIC = 'XX/initialposeXX'") in edits  # mutmut's own string mutation
    assert (6, "return False", "return True") in edits
    same = mut.Mutant("node.py", 6, "        return False", "        return True", "")
    assert same.key in {m.key for m in made}
    assert mut.MUTMUT in mut.FAMILIES


def test_poodle_mutants_are_a_fourth_tools_edits_compiled_and_fixed_in_order(tmp_path: Path) -> None:
    """The fourth family (fresh held-out pools once mutmut's are spent too): poodle's built-in mutators on a
    Python file, one edit each, in poodle's order; operators the other three lack (a call or a subscript
    replaced by None, a return of None); none that fails to compile; an edit another tool makes has its key."""
    pytest.importorskip("poodle")
    made, edits = _family_mutants(mut.generate_poodle_mutants, tmp_path,
                                  "TOPIC = '/initialpose'\n\n\ndef ready(node, counts):\n    if counts[0] < 2:\n"
                                  "        node.get_logger().info('waiting')\n        return False\n"
                                  "    return counts[0] * 3 > 4\n", (1, 5, 6, 7, 8))
    assert len(made) >= 8
    assert (6, "node.get_logger().info('waiting')", "None") in edits  # FuncCall: the call replaced by None
    assert (5, "if counts[0] < 2:", "if None < 2:") in edits  # DictArray: the subscript replaced by None
    assert (7, "return False", "return None") in edits  # Return
    assert (7, "return False", "return True") in edits  # Keyword
    same = mut.Mutant("node.py", 7, "        return False", "        return True", "")
    assert same.key in {m.key for m in made}
    assert mut.POODLE in mut.FAMILIES


def test_mutpy_mutants_are_a_fifth_tools_edits_spliced_into_the_original_text(tmp_path: Path) -> None:
    """The fifth family (fresh held-out pools once poodle's are spent too): MutPy's operators on a node's file,
    each mutation spliced into the original text (the rest of the file, its comments and quotes, unchanged);
    operators the other four lack (self.x made x, an except body swallowed, a super() call removed, a loop run
    reversed or zero times); a mutant another family makes in other words is dropped by its syntax tree."""
    pytest.importorskip("mutpy")
    text = ("class Node(Base):\n    def __init__(self, names):\n        super().__init__(\"talker\")  # the node\n"
            "        self.count = 0\n        for name in names:\n            self.count += 1\n\n"
            "    def stop(self):\n        try:\n            self.close()\n        except KeyError:\n"
            "            print('gone')\n")
    made, edits = _family_mutants(mut.generate_mutpy_mutants, tmp_path, text, tuple(range(1, 13)))
    assert (6, "self.count += 1", "count += 1") in edits  # SVD: self variable deletion
    assert (12, "print('gone')", "pass") in edits  # EXS: the handler's body swallowed
    assert (3, 'super().__init__("talker")  # the node', "pass  # the node") in edits  # SCD, the comment kept
    assert (5, "for name in names:", "for name in reversed(names):") in edits  # RIL: the loop reversed
    assert (6, "self.count += 1", "break") in edits  # ZIL: the loop's body left at once
    for m in made:  # one place changed: every line outside the edit is the original's
        assert m.content.splitlines()[:m.line - 1] == text.splitlines()[:m.line - 1]
    # another family's mutant: the same edit in other words (spacing), so the same syntax tree
    other = mut.Mutant("node.py", 6, "            self.count += 1", "            self.count  +=  2",
                       text.replace("self.count += 1", "self.count  +=  2"))
    kept = mut.drop_made_by_others(made, [other])
    assert len(kept) == len(made) - 1 and all("self.count += 2" not in m.content for m in kept)
    assert mut.MUTPY in mut.FAMILIES


def test_a_family_other_than_universalmutator_draws_only_held_out_samples(tmp_path: Path) -> None:
    """--family: a bad name and a first sample from cosmic-ray are one-line errors before anything is graded."""
    from ros2course.dev.mutate import mutate_lessons
    from ros2course.errors import CourseError

    with pytest.raises(CourseError, match="unknown mutant family 'pitmutator'"):
        mutate_lessons([LESSON], tmp_path, sample=5, family="pitmutator")
    pytest.importorskip("cosmic_ray")
    with pytest.raises(CourseError, match="draws a held-out sample"):
        mutate_lessons([LESSON], tmp_path, sample=5, family="cosmic-ray")
    assert not any(tmp_path.iterdir())


def test_the_mutant_cache_is_never_wider_than_the_grader_fingerprint(monkeypatch, tmp_path) -> None:
    """Stop 66: grade/machine.py was in the fingerprint but not in the cache key, so outcomes graded before a fix
    to it were reused after it. The key is made from the fingerprint's own list of files: a change to any of
    them (an engine module among them) changes the key."""
    from ros2course.grade import fingerprint
    from ros2course.lesson.catalog import load_catalog

    lesson = load_catalog().get(LESSON)
    files = fingerprint.grader_files(lesson)
    assert any(p.parts[-2:] == ("grade", "machine.py") for p in files)
    before = mut.grader_hash(lesson)
    assert before == mut.grader_hash(lesson)
    extra = tmp_path / "engine_module.py"
    extra.write_text("A = 1\n", encoding="utf-8")
    monkeypatch.setattr(fingerprint, "grader_files", lambda lesson: [*files, extra])
    with_extra = mut.grader_hash(lesson)
    assert with_extra != before
    extra.write_text("A = 2\n", encoding="utf-8")
    assert mut.grader_hash(lesson) != with_extra
