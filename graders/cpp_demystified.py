"""Grader for ``cpp-demystified`` (seed ch. 28.5-28.6; contract in shared/LESSONS.md).

Pure C++, no ROS: everything lives in ``cpp/cpp_demystified/`` of the
workspace. Two independent parts:

They run at the same time (:func:`ros2course.kit.parts.at_once`).

* ``cmake``: the learner's own ``CMakeLists.txt`` is configured and built out
  of source under ``s.log_dir`` (nothing is written into their folder), and the
  demo program ``demystified_demo`` is run once.
* ``harness``: their ``src/demystified.cpp`` is compiled in one ``g++`` call
  with the course's test harness (``graders/data/cpp_demystified/harness.cpp``)
  in a scratch copy under ``s.log_dir`` where ``potato.hpp`` is replaced by a
  twin with the same interface that counts how each Potato is constructed.
  The harness is compiled with ``-D_GLIBCXX_ASSERTIONS``, so ``operator[]``
  past the end aborts deterministically instead of reading garbage. The binary
  is run once per test of ``tests.yaml`` (an abort ends only that test) and
  prints one line, ``PASS ...`` or ``FAIL ...``.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import yaml

from ros2course import kit
from ros2course.kit import Check, Session, Unmet
from ros2course.kit import cmake as ck
from ros2course.kit.parts import at_once
from ros2course.kit.programs import last_line, run_program, verdict_test
from ros2course.kit.topics_services import numbers_in

PROJECT = Path("cpp") / "cpp_demystified"
HEADER = Path("include") / "cpp_demystified" / "demystified.hpp"
POTATO = Path("include") / "cpp_demystified" / "potato.hpp"
SOURCE = Path("src") / "demystified.cpp"
FILES = (Path("CMakeLists.txt"), HEADER, POTATO, SOURCE, Path("src") / "main.cpp")
DEMO = "demystified_demo"
#: The harness sources (this grader's own data folder).
DATA = Path(__file__).resolve().parent / "data" / "cpp_demystified"

#: What libstdc++'s std::out_of_range from ``vector::at(22)`` says of the index (its ``_M_range_check``: the
#: text is the library's, not the learner's, so the demo's own wording stays free).
WHAT_22 = "which is 22"
#: ... and of the vector's size: the lesson's demo reads ``.at(22)`` of a four-element vector.
WHAT_SIZE = "(which is 4)"
#: The size the demo's Potato is made with, ``make_potato(20.0)``: std::cout prints the double as ``20``.
POTATO_SIZE = 20.0
RUN_TIMEOUT = 10.0  # seconds for the demo and for each harness test (each takes milliseconds)
#: Seconds of observation the contract needs (benchmarks read it): none, every program runs to its end.
WINDOW = 0.0


CHECKS = [
    Check("layout", "cpp/cpp_demystified holds CMakeLists.txt, the two headers and the two sources", 1,
          "create cpp/cpp_demystified/{CMakeLists.txt, include/cpp_demystified/demystified.hpp, "
          "include/cpp_demystified/potato.hpp, src/demystified.cpp, src/main.cpp}"),
    Check("cmake_build", f"Your CMakeLists.txt configures and builds the executable {DEMO}", 2,
          f"in cpp/cpp_demystified run: cmake -S . -B build && cmake --build build; fix the first error "
          f"it prints; the CMakeLists needs add_executable({DEMO} src/main.cpp src/demystified.cpp) and "
          "target_include_directories(" + DEMO + " PRIVATE include)", part="cmake"),
    Check("demo_runs", f"./{DEMO} runs to the end with exit code 0", 1,
          f"run ./build/{DEMO} yourself: an exception that nothing catches or a crash ends it with a non-zero code",
          needs=("cmake_build",), part="cmake"),
    Check("demo_out_of_range", f"./{DEMO} prints the what() of the std::out_of_range that .at(22) throws", 1,
          "call values.at(22) inside try, and in catch (const std::out_of_range& e) print e.what(): the "
          "exception's own text says which index was asked for and how many elements there are",
          needs=("cmake_build",), part="cmake"),
    Check("demo_potato_size", f"./{DEMO} prints the size of make_potato(20.0)", 1,
          "print potato->size() of the Potato that make_potato(20.0) returns: std::cout shows the double 20.0 as "
          "20; the words around it are yours", needs=("cmake_build",), part="cmake"),
    Check("harness_compiles", "src/demystified.cpp compiles with the course's test harness (the fixed signatures)", 1,
          "keep the four functions of demystified.hpp exactly as the lesson declares them (namespace "
          "cpp_demystified, same names, argument and return types), include \"cpp_demystified/potato.hpp\" "
          "for Potato, and do not change potato.hpp", part="harness"),
    Check("at_throws", "checked_element() uses .at(): an index past the end throws std::out_of_range", 2,
          "return values.at(index); operator[] never checks the index", needs=("harness_compiles",),
          part="harness"),
    Check("catches_out_of_range", "try_element() catches std::out_of_range and returns std::nullopt", 2,
          "wrap values.at(index) in try { ... } catch (const std::out_of_range&) { return std::nullopt; }",
          needs=("harness_compiles",), part="harness"),
    Check("nan_check", "safe_acos() detects the NaN of std::acos(1.1) with std::isnan", 2,
          "NaN compares unequal to everything, itself included, so 'a == NAN' is always false: "
          "test std::isnan(a) and return std::nullopt when it is true", needs=("harness_compiles",),
          part="harness"),
    Check("potato_no_copy", "make_potato() builds one Potato in place with std::make_shared (no temporary)", 2,
          "return std::make_shared<Potato>(size); make_shared forwards size to Potato's constructor, while "
          "std::make_shared<Potato>(Potato(size)) first builds a temporary and then copies or moves it",
          needs=("harness_compiles",), part="harness"),
]


def grade(s: Session) -> None:
    """Check the files, build and run the learner's CMake project, then run the test harness on their functions."""
    project = kit.project_files(s, "layout", PROJECT, FILES)
    # two single-threaded compiles on 2 cores: the parts run at the same time (own scratch folders each)
    at_once(s, "cmake", lambda: _judge_cmake(s, project), "harness", lambda: _judge_harness(s, project))


def _judge_cmake(s: Session, project: Path) -> None:
    """Configure and build the learner's CMakeLists.txt under log_dir, then run the demo once."""
    cmake, build = ck.tool(s.base_env, "cmake"), s.submission_folder("cmake-build")
    expected = f"cmake configures the project and builds {DEMO}"
    ck.step(s, "cmake_build", [cmake, "-S", str(project), "-B", str(build)], "cmake_configure",
            shown="cmake -S . -B build", expected=expected, cwd=s.log_dir, paths={str(project) + os.sep: ""})
    ck.step(s, "cmake_build", [cmake, "--build", str(build), "--parallel", "2"], "cmake_build",
            shown="cmake --build build", expected=expected, cwd=s.log_dir, paths={str(project) + os.sep: ""})
    found = sorted(p for p in build.rglob(DEMO) if p.is_file() and os.access(p, os.X_OK))
    if not s.record("cmake_build", bool(found), f"configured and built {found[0].relative_to(build)}" if found
                    else f"the build succeeded but made no executable named {DEMO} (add_executable({DEMO} ...))",
                    expected):
        raise Unmet(f"no {DEMO} was built")
    run = run_program(s, [str(found[0])], DEMO, timeout=RUN_TIMEOUT, cwd=build)
    out = [line for line in run.stdout.splitlines() if line.strip()]
    problem = last_line(run.stderr)[:160]
    s.record("demo_runs", run.returncode == 0 and not run.timed_out, f"./{DEMO}: {run.ending()}"
             + (f"; it printed {len(out)} line(s), the last: {out[-1].strip()[:120]!r}" if out else "")
             + (f"; stderr: {problem!r}" if run.returncode != 0 and problem else ""),
             f"exit code 0 within {RUN_TIMEOUT:.0f} s")
    said = [line.strip() for line in (run.stdout + "\n" + run.stderr).splitlines() if WHAT_22 in line]
    sized_4 = [line for line in said if WHAT_SIZE in line]  # the closing bracket: "(which is 40)" is not it
    s.record("demo_out_of_range", bool(sized_4),
             f"it printed {said[0][:160]!r}" + ("" if sized_4 else ": the vector does not hold four elements")
             if said else
             f"none of its {len(out)} line(s) holds the exception's text" + (f"; the first: {out[0].strip()[:120]!r}"
                                                                             if out else ""),
             f"a line with e.what() of .at(22)'s std::out_of_range (libstdc++: 'vector::_M_range_check: __n "
             f"({WHAT_22}) >= this->size() {WHAT_SIZE}')")
    sized = [line.strip() for line in out if POTATO_SIZE in numbers_in(line)]
    s.record("demo_potato_size", bool(sized), f"it printed {sized[0][:160]!r}" if sized else
             f"none of its {len(out)} line(s) holds the number {POTATO_SIZE:g}",
             f"a line with the size of make_potato({POTATO_SIZE}), {POTATO_SIZE:g} (the wording is yours)")


def _scratch_copy(s: Session, project: Path) -> Path:
    """A submission folder ``<log_dir>/harness`` with the learner's include/ and src/demystified.cpp, the
    course's potato.hpp in place of theirs, and harness.cpp (the compile runs as the submission)."""

    def fill(scratch: Path) -> None:
        if (project / "include").is_dir():
            shutil.copytree(project / "include", scratch / "include", symlinks=True)
        (scratch / POTATO).parent.mkdir(parents=True, exist_ok=True)
        (scratch / POTATO).unlink(missing_ok=True)
        shutil.copyfile(DATA / "potato.hpp", scratch / POTATO)
        (scratch / "src").mkdir(parents=True, exist_ok=True)
        shutil.copyfile(project / SOURCE, scratch / SOURCE)
        shutil.copyfile(DATA / "harness.cpp", scratch / "harness.cpp")

    return s.submission_folder("harness", fill)


def _judge_harness(s: Session, project: Path) -> None:
    """Compile src/demystified.cpp with the harness (one g++ call, -O0), then run each test in its own process."""
    if not (project / SOURCE).is_file():
        s.record("harness_compiles", False, f"there is no {PROJECT}/{SOURCE}", f"{SOURCE} with the four functions")
        raise Unmet(f"there is no {SOURCE}")
    gxx = ck.tool(s.base_env, "g++", "c++")
    scratch = _scratch_copy(s, project)
    argv = [gxx, "-std=c++17", "-O0", "-D_GLIBCXX_ASSERTIONS", "-I", "include", "harness.cpp", str(SOURCE),
            "-o", "harness"]
    ck.step(s, "harness_compiles", argv, "harness_compile", shown=f"g++ -std=c++17 harness.cpp {SOURCE}",
            passed="compiled with the harness", cwd=scratch, paths={str(scratch) + os.sep: ""},
            expected="your functions compile against the signatures of the lesson's demystified.hpp "
                     "(with the course's copy of potato.hpp)")

    for test in yaml.safe_load((DATA / "tests.yaml").read_text(encoding="utf-8")):
        verdict_test(s, test["check"], [str(scratch / "harness"), test["test"]], f"harness_{test['test']}",
                     expected=test["expected"], explain=test.get("explain", []), cwd=scratch, timeout=RUN_TIMEOUT)
