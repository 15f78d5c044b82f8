"""Grader for ``testing-your-nodes`` (issue 20; contract in chapters/testing-your-nodes/CONTRACT.md).

The learner writes tests: pytest unit tests of the library of lesson 14
(``src/python_package_with_a_library/test/``) and a ``launch_testing`` test of the
print-forever node of lesson 13 (``src/python_package_with_a_node/test/``). They are
graded by mutation (:mod:`ros2course.kit.testing`): they must pass on the course's
reference packages and fail on each hidden mutant below, one check per mutant, so
the feedback names each bug the tests would let through.

Only the learner's ``test/`` folders are used: the code under test is always the
course's (``references:`` in lesson.yaml, ``Session.reference_package``), so a
learner's own bug cannot pass for a test's.
"""

from __future__ import annotations

from ros2course import kit
from ros2course.kit import Check, Session
from ros2course.kit.packaging import setup_py_arguments
from ros2course.kit.testing import (
    DeclaredMutant,
    TestRun,
    judge_mutant,
    judge_reference,
    prepare_cases,
    run_cases,
    run_tests,
)

LIBRARY = "python_package_with_a_library"
NODE_PACKAGE = "python_package_with_a_node"
EXECUTABLE = "print_forever_node"
FUNCTION_FILE = f"{LIBRARY}/sample_python_library/_sample_function.py"
CLASS_FILE = f"{LIBRARY}/sample_python_library/_sample_class.py"
NODE_FILE = f"{NODE_PACKAGE}/print_forever_node.py"
#: Seconds a run of the unit tests may take (they take about one), and of the launch test
#: (the reference's takes about 4 s; a test waiting for a record that never comes waits its own timeout).
LIBRARY_TIMEOUT = 30.0
LAUNCH_TIMEOUT = 60.0
#: Seconds the contract needs (benchmarks/all_lessons.py): the grader watches no node itself, but each
#: launch test must see five records, 2 s of the node (0.5 s apart), on the reference and 6 node mutants,
#: two runs at once.
WINDOW = 3.5 * 2.0
#: What each package.xml must declare as <test_depend> (the lesson: python3-pytest in both, launch_testing
#: and launch_ros for the node's package).
TEST_DEPENDENCIES = {LIBRARY: ("python3-pytest",),
                     NODE_PACKAGE: ("python3-pytest", "launch_testing", "launch_ros")}

LIBRARY_MUTANTS = [
    DeclaredMutant("catches_sum_of_squares", LIBRARY, FUNCTION_FILE, "return (a + b) ** 2", "return a ** 2 + b ** 2",
           "a library whose function returns a**2 + b**2 (the middle term 2*a*b forgotten)",
           "test a pair where neither number is zero, e.g. (1, 2) must give 9"),
    DeclaredMutant("catches_doubled_sum", LIBRARY, FUNCTION_FILE, "return (a + b) ** 2", "return (a + b) * 2",
           "a library whose function returns (a + b) * 2",
           "(1, 1) gives 4 both ways: test a pair whose sum is not 0 or 2, e.g. (1, 2) -> 9"),
    DeclaredMutant("catches_ignored_signs", LIBRARY, FUNCTION_FILE, "return (a + b) ** 2", "return (abs(a) + abs(b)) ** 2",
           "a library whose function drops the signs, (|a| + |b|)**2",
           "test negative numbers too, e.g. (-3, 1) must give 4"),
    DeclaredMutant("catches_whole_numbers", LIBRARY, FUNCTION_FILE, "return (a + b) ** 2", "return int(a + b) ** 2",
           "a library whose function rounds the sum down to a whole number",
           "test floats, e.g. (0.5, 0.25) must give 0.5625 (compare floats with pytest.approx)"),
    DeclaredMutant("catches_shared_name", LIBRARY, CLASS_FILE, "self._name = name", "SampleClass._name = name",
           "a library whose SampleClass keeps one name for all its instances (a class attribute)",
           "make two instances with different names and check each keeps its own"),
    DeclaredMutant("catches_short_names", LIBRARY, CLASS_FILE, "return self._name", "return self._name[:8]",
           "a library whose get_name() returns only the first 8 characters",
           "test a long name too, e.g. ten random letters as the next lesson's node uses"),
]
NODE_MUTANTS = [
    DeclaredMutant("catches_counting_from_one", NODE_PACKAGE, NODE_FILE, "self.print_count: int = 0",
           "self.print_count: int = 1", "a node whose count starts at 1",
           "check that the first record is 'Printed 0 times.'"),
    DeclaredMutant("catches_repeated_count", NODE_PACKAGE, NODE_FILE,
           "        self.timer = self.create_timer(timer_period, self.timer_callback)\n",
           "        self.timer = self.create_timer(timer_period, self.timer_callback)\n"
           "        self.get_logger().info(f'Printed {self.print_count} times.')\n",
           "a node that logs 'Printed 0 times.' twice (once more as it starts), then 1, 2, 3, ... every 0.5 s",
           "check the counts of the first five records, in order: 0, 1, 2, 3, 4, each once (the first and the "
           "fifth are still 2 s apart on this node: only the counts tell)"),
    DeclaredMutant("catches_slow_timer", NODE_PACKAGE, NODE_FILE, "timer_period: float = 0.5", "timer_period: float = 1.0",
           "a node that logs once a second instead of twice",
           "time the records by their stamps: each line of proc_output[node] starts '[INFO] [<seconds>] "
           "[print_forever]:'; from 'Printed 0 times.' to 'Printed 4 times.' is 2 s"),
    DeclaredMutant("catches_fast_timer", NODE_PACKAGE, NODE_FILE, "timer_period: float = 0.5",
           "timer_period: float = 0.25", "a node that logs four times a second instead of twice",
           "time the records both ways: from 'Printed 0 times.' to 'Printed 4 times.' is 2 s, neither less nor more "
           "(self.assertAlmostEqual(..., 2.0, delta=0.25), not only an upper bound)"),
    DeclaredMutant("catches_other_words", NODE_PACKAGE, NODE_FILE, "f'Printed {self.print_count} times.'",
           "f'Logged {self.print_count} times.'", "a node that logs 'Logged N times.'",
           "wait for the exact text, e.g. proc_output.assertWaitFor('Printed 0 times.', process=node, timeout=10.0)"),
    DeclaredMutant("catches_stopping", NODE_PACKAGE, NODE_FILE, "        self.print_count += 1\n",
           "        self.print_count += 1\n        if self.print_count == 3:\n            self.timer.cancel()\n",
           "a node that stops logging after 'Printed 2 times.'",
           "wait for a later record too, e.g. 'Printed 4 times.'"),
    DeclaredMutant("catches_unclean_exit", NODE_PACKAGE, NODE_FILE,
           "    except (KeyboardInterrupt, ExternalShutdownException):\n        pass\n",
           "    except (KeyboardInterrupt, ExternalShutdownException):\n        raise SystemExit(1)\n",
           "a node that exits with status 1 on Ctrl+C",
           "add a @launch_testing.post_shutdown_test() class that calls "
           "launch_testing.asserts.assertExitCodes(proc_info, process=node)"),
    # the independent review of stop 82 got full marks with assertExitCodes(..., allowable_exit_codes=[0, -2, -9,
    # -15, 130, 137, 143]): a test that lets a signal's death pass as clean; the lesson's Ctrl+C ends it with 0
    DeclaredMutant("catches_death_by_signal", NODE_PACKAGE, NODE_FILE,
           "    except (KeyboardInterrupt, ExternalShutdownException):\n        pass\n",
           "    except (KeyboardInterrupt, ExternalShutdownException):\n"
           "        import os, signal; signal.signal(signal.SIGINT, signal.SIG_DFL); os.kill(os.getpid(), signal.SIGINT)\n",
           "a node that dies of the signal on Ctrl+C (exit code -2, what a shell shows as 130) instead of exiting with 0",
           "keep assertExitCodes(proc_info, process=node) at its default, which accepts 0 only: a list of "
           "allowable_exit_codes with -2, -15 or 130 lets a node that never handles Ctrl+C pass"),
]

CHECKS = [
    Check("build", "The packages build with colcon", 1),
    Check("colcon_runs_pytest", "Both packages' setup.py ask colcon test for pytest", 1,
          "add tests_require=['pytest'] to setup() in each setup.py (what ros2 pkg create writes): without it "
          "colcon test runs unittest, which finds no pytest test functions and no launch test"),
    Check("test_depends", "Both packages' package.xml declare their test dependencies", 1,
          "<test_depend>python3-pytest</test_depend> in both package.xml, plus <test_depend>launch_testing</test_depend> "
          "and <test_depend>launch_ros</test_depend> in python_package_with_a_node's"),
    Check("executable", "ros2 run finds print_forever_node (lesson 13), which the launch test starts", 1,
          "finish lesson 13 first: the console script print_forever_node in python_package_with_a_node's setup.py"),
    Check("library_tests_pass", "Your library tests pass on the course's library", 2,
          "put test_*.py files with test_* functions in src/python_package_with_a_library/test/; run "
          "'colcon test --packages-select python_package_with_a_library' then 'colcon test-result --verbose'"),
    Check("launch_test_passes", "Your launch test passes on the course's print_forever_node", 2,
          "in src/python_package_with_a_node/test/test_*.py: a generate_test_description() marked "
          "@pytest.mark.launch_test that launches print_forever_node and ReadyToTest(), and unittest classes "
          "whose tests take proc_output; run 'colcon test' and read log/latest_test", needs=("executable",)),
    *[Check(m.check, f"Your library tests fail on {m.what}", 1, m.hint, needs=("library_tests_pass",))
      for m in LIBRARY_MUTANTS],
    *[Check(m.check, f"Your launch test fails on {m.what}", 1, m.hint, needs=("launch_test_passes",))
      for m in NODE_MUTANTS],
]


def _asks_for_pytest(s: Session) -> None:
    """``colcon_runs_pytest``: colcon-core runs pytest for a package whose setup() lists it in
    ``tests_require`` or ``extras_require['test']`` (``task/python/test/pytest.py``), else unittest."""
    lacking = []
    for package in (LIBRARY, NODE_PACKAGE):
        arguments, problem = setup_py_arguments(s, s.workspace_root / "src" / package)
        wanted = list(arguments.get("tests_require") or []) + list((arguments.get("extras_require") or {}).get("test", []))
        if problem or not any(str(w).split("=")[0].split("<")[0].split(">")[0].strip() == "pytest" for w in wanted):
            lacking.append(f"{package} ({problem or 'no pytest in tests_require'})")
    s.record("colcon_runs_pytest", not lacking, "both ask for pytest" if not lacking else "missing in " + "; ".join(lacking),
             "tests_require=['pytest'] in the setup() of both packages")


def _test_depends(s: Session) -> None:
    """``test_depends``: each package.xml lists TEST_DEPENDENCIES as <test_depend> (or <depend>, which includes it)."""
    seen, missing = [], []
    for package, needed in TEST_DEPENDENCIES.items():
        found = kit.source_package(s, package)
        if found is None:
            missing.append(f"{package}: no such package in src/")
            continue
        # <test_depend>, or <depend> (build, build_export and exec at once): an <exec_depend> or <build_depend>
        # alone is not the test dependency the lesson asks for (helper audit of issue 37)
        package_xml = found[1]
        both = ({d.name for d in package_xml.build_depends} & {d.name for d in package_xml.exec_depends}
                & {d.name for d in package_xml.build_export_depends})
        declared = {d.name for d in package_xml.test_depends} | both
        lacking = [name for name in needed if name not in declared]
        missing += [f"{package}: {name}" for name in lacking]
        seen.append(f"{package}: {', '.join(sorted(d.name for d in found[1].test_depends)) or 'no test_depend'}"
                    + (f" (missing {', '.join(lacking)})" if lacking else ""))
    total = sum(len(needed) for needed in TEST_DEPENDENCIES.values())
    s.record("test_depends", not missing, "; ".join(seen + [m for m in missing if "no such package" in m]),
             "; ".join(f"{package}: " + ", ".join(f"<test_depend>{n}</test_depend>" for n in needed)
                       for package, needed in TEST_DEPENDENCIES.items()),
             fraction=max(0, total - len(missing)) / total)


def grade(s: Session) -> None:
    """Static setup checks, then the learner's tests on the reference, then on each mutant (two runs at once)."""
    _asks_for_pytest(s)
    _test_depends(s)
    kit.executable(s, "executable", NODE_PACKAGE, EXECUTABLE)
    # every mutant when a learner is graded; under dev validate --until-settled only those a named check needs
    library_mutants = [m for m in LIBRARY_MUTANTS if s.wanted(m.check)]
    node_mutants = [m for m in NODE_MUTANTS if s.wanted(m.check)]
    cases = prepare_cases(s, (LIBRARY, NODE_PACKAGE), library_mutants + node_mutants)
    overlay = s.overlay()
    # each launch run in a private ROS domain: a learner's test that listens to a topic must hear only its node
    graphs = {case: s.new_graph() for case in ["reference", *(m.check for m in node_mutants)]}
    runs: dict[str, TestRun] = {}

    def library(case: str) -> None:
        runs[f"{case}/library"] = run_tests(s, cases[case] / LIBRARY, f"tests-{case}-library", env=overlay,
                                            timeout=LIBRARY_TIMEOUT)

    def launch(case: str) -> None:
        runs[f"{case}/node"] = run_tests(s, cases[case] / NODE_PACKAGE, f"tests-{case}-node",
                                         env=graphs[case].learner_env(overlay), timeout=LAUNCH_TIMEOUT)

    run_cases(s, [lambda: library("reference"), lambda: launch("reference")])
    where = "src/{}/test"
    library_ok = judge_reference(s, "library_tests_pass", runs["reference/library"], where.format(LIBRARY),
                                 "every test passes (pytest exit status 0) on the correct library")
    node_ok = judge_reference(s, "launch_test_passes", runs["reference/node"], where.format(NODE_PACKAGE),
                              "every test passes (pytest exit status 0) on the correct node")
    library_jobs = [(lambda m=m: library(m.check)) for m in library_mutants] if library_ok else []
    launch_jobs = [(lambda m=m: launch(m.check)) for m in node_mutants] if node_ok else []
    run_cases(s, launch_jobs + library_jobs)  # the slow launch runs first: the quick library runs fill the gaps
    for mutant in library_mutants if library_ok else []:
        judge_mutant(s, mutant, runs[f"{mutant.check}/library"])
    for mutant in node_mutants if node_ok else []:
        judge_mutant(s, mutant, runs[f"{mutant.check}/node"])
