"""Grader for ``cpp-demystified`` (seed ch. 28.5-28.6; contract in shared/LESSONS.md).

Pure C++, no ROS: everything lives in ``cpp/cpp_demystified/`` of the
workspace. Two independent parts:

* ``cmake``: the learner's own ``CMakeLists.txt`` is configured and built out
  of source under ``s.log_dir`` (nothing is written into their folder), and the
  demo program ``demystified_demo`` is run once.
* ``harness``: their ``src/demystified.cpp`` is compiled in one ``g++`` call
  with the course's test harness (``graders/data/cpp_demystified/harness.cpp``)
  in a scratch copy under ``s.log_dir`` where ``potato.hpp`` is replaced by a
  twin with the same interface that counts how each Potato is constructed.
  The harness is compiled with ``-D_GLIBCXX_ASSERTIONS``, so ``operator[]``
  past the end aborts deterministically instead of reading garbage. The binary
  is run once per test (an abort ends only that test) and prints one line,
  ``PASS ...`` or ``FAIL ...``.
"""

from __future__ import annotations

import os
import shutil
import signal
from pathlib import Path

from graders import kit
from graders.kit import Check, GradingSession, Unmet
from graders.kit.programs import ProgramRun, run_program

PROJECT = Path("cpp") / "cpp_demystified"
HEADER = Path("include") / "cpp_demystified" / "demystified.hpp"
POTATO = Path("include") / "cpp_demystified" / "potato.hpp"
SOURCE = Path("src") / "demystified.cpp"
FILES = (Path("CMakeLists.txt"), HEADER, POTATO, SOURCE, Path("src") / "main.cpp")
DEMO = "demystified_demo"
#: The harness sources (this grader's own data folder).
DATA = Path(__file__).resolve().parent / "data" / "cpp_demystified"

BUILD_TIMEOUT = 120.0  # seconds for each of cmake configure, cmake build and the harness's g++ call
RUN_TIMEOUT = 10.0  # seconds for the demo and for each harness test (each takes milliseconds)
#: Seconds of observation the contract needs (benchmarks read it): none, every program runs to its end.
WINDOW = 0.0

#: harness test argument -> the check it decides.
TESTS = {"at": "at_throws", "try": "catches_out_of_range", "acos": "nan_check", "potato": "potato_no_copy"}

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


def _tool(env: dict[str, str], *names: str) -> str:
    """The first of ``names`` found on ``env``'s PATH.

    Raises:
        Unmet: none is installed (the lesson's ``requires`` normally catches this before grading).
    """
    for name in names:
        found = shutil.which(name, path=env.get("PATH", os.defpath))
        if found:
            return found
    raise Unmet(f"{' or '.join(names)} is not on PATH: install it (apt-get install cmake g++)")


def _errors(run: ProgramRun, strip: Path | None = None, limit: int = 2) -> str:
    """The first error lines of a build's output (compiler 'error:' or 'CMake Error'), paths made relative."""
    text = run.stdout + "\n" + run.stderr
    if strip is not None:
        text = text.replace(str(strip) + os.sep, "")
    lines = [line.strip() for line in text.splitlines()]
    picked: list[str] = []
    for i, line in enumerate(lines):
        if "error:" in line or line.startswith("CMake Error"):
            picked.append(line)
            if line.startswith("CMake Error") and i + 2 < len(lines):  # the message is on the next lines
                detail = lines[i + 1] or lines[i + 2]
                if detail:
                    picked[-1] += " " + detail
        if len(picked) >= limit:
            break
    if picked:
        return "; ".join(picked)
    if run.timed_out:
        return run.describe()
    tail = [line for line in lines if line]
    return f"exit code {run.returncode}" + (f", last output: {tail[-1]}" if tail else "")


def grade(s: GradingSession) -> None:
    """Check the files, build and run the learner's CMake project, then run the test harness on their functions."""
    project = kit.project_files(s, "layout", PROJECT, FILES)
    with s.part("cmake"):
        _judge_cmake(s, project)
    with s.part("harness"):
        _judge_harness(s, project)


def _judge_cmake(s: GradingSession, project: Path) -> None:
    """Configure and build the learner's CMakeLists.txt under log_dir, then run the demo once."""
    if not (project / "CMakeLists.txt").is_file():
        s.record("cmake_build", False, f"there is no {PROJECT}/CMakeLists.txt", "a CMakeLists.txt that builds " + DEMO)
        raise Unmet("there is no CMakeLists.txt")
    cmake = _tool(s.base_env, "cmake")
    build = s.log_dir / "cmake-build"
    configure = run_program(s, [cmake, "-S", str(project), "-B", str(build)], "cmake_configure",
                            timeout=BUILD_TIMEOUT, cwd=s.log_dir)
    if configure.returncode != 0 or configure.timed_out:
        s.record("cmake_build", False, f"cmake -S . -B build failed: {_errors(configure, project)}",
                 f"cmake configures the project and builds {DEMO}")
        raise Unmet("the CMake project does not configure")
    compiled = run_program(s, [cmake, "--build", str(build), "--parallel", "2"], "cmake_build",
                           timeout=BUILD_TIMEOUT, cwd=s.log_dir)
    if compiled.returncode != 0 or compiled.timed_out:
        s.record("cmake_build", False, f"cmake --build build failed: {_errors(compiled, project)}",
                 f"it compiles and links {DEMO}")
        raise Unmet("the CMake project does not build")
    found = sorted(p for p in build.rglob(DEMO) if p.is_file() and os.access(p, os.X_OK))
    if not found:
        s.record("cmake_build", False, f"the build succeeded but made no executable named {DEMO}",
                 f"add_executable({DEMO} ...) in CMakeLists.txt")
        raise Unmet(f"no {DEMO} was built")
    s.record("cmake_build", True, f"configured and built {found[0].relative_to(build)}", f"{DEMO} is built")

    run = run_program(s, [str(found[0])], DEMO, timeout=RUN_TIMEOUT, cwd=build)
    out = [line for line in run.stdout.splitlines() if line.strip()]
    observed = f"./{DEMO}: {_ending(run)}"
    if out:
        observed += f"; it printed {len(out)} line(s), the last: {out[-1].strip()[:120]!r}"
    problem = [line for line in run.stderr.splitlines() if line.strip()]
    if run.returncode != 0 and problem:
        observed += f"; stderr: {problem[-1].strip()[:160]!r}"
    s.record("demo_runs", run.returncode == 0 and not run.timed_out, observed,
             f"exit code 0 within {RUN_TIMEOUT:.0f} s")


def _ending(run: ProgramRun) -> str:
    """How a compiled program ended, in words (a signal named, not only its number)."""
    if run.timed_out:
        return f"still running after {run.seconds:.1f} s (stopped)"
    if run.returncode is not None and run.returncode < 0:
        try:
            name = signal.Signals(-run.returncode).name
        except ValueError:
            name = f"signal {-run.returncode}"
        meaning = {"SIGABRT": " (abort: an assertion failed or an exception nothing caught)",
                   "SIGSEGV": " (segmentation fault: memory that is not yours was touched)"}.get(name, "")
        return f"killed by {name}{meaning}"
    return f"exit code {run.returncode}"


def _scratch_copy(s: GradingSession, project: Path) -> Path:
    """A folder under log_dir with the learner's include/ and src/demystified.cpp, the course's
    potato.hpp in place of theirs, and harness.cpp."""
    scratch = s.log_dir / "harness"
    if (project / "include").is_dir():
        shutil.copytree(project / "include", scratch / "include", symlinks=True)
    (scratch / POTATO).parent.mkdir(parents=True, exist_ok=True)
    (scratch / POTATO).unlink(missing_ok=True)
    shutil.copyfile(DATA / "potato.hpp", scratch / POTATO)
    (scratch / "src").mkdir(parents=True, exist_ok=True)
    shutil.copyfile(project / SOURCE, scratch / SOURCE)
    shutil.copyfile(DATA / "harness.cpp", scratch / "harness.cpp")
    return scratch


def _judge_harness(s: GradingSession, project: Path) -> None:
    """Compile src/demystified.cpp with the harness (one g++ call, -O0), then run each test in its own process."""
    if not (project / SOURCE).is_file():
        s.record("harness_compiles", False, f"there is no {PROJECT}/{SOURCE}", f"{SOURCE} with the four functions")
        raise Unmet(f"there is no {SOURCE}")
    gxx = _tool(s.base_env, "g++", "c++")
    scratch = _scratch_copy(s, project)
    argv = [gxx, "-std=c++17", "-O0", "-D_GLIBCXX_ASSERTIONS", "-I", "include", "harness.cpp", str(SOURCE),
            "-o", "harness"]
    compiled = run_program(s, argv, "harness_compile", timeout=BUILD_TIMEOUT, cwd=scratch)
    if compiled.returncode != 0 or compiled.timed_out or not (scratch / "harness").is_file():
        s.record("harness_compiles", False,
                 f"g++ -std=c++17 harness.cpp {SOURCE} failed: {_errors(compiled, scratch)}",
                 "your functions compile against the signatures of the lesson's demystified.hpp "
                 "(with the course's copy of potato.hpp)")
        raise Unmet("your code does not compile with the test harness")
    s.record("harness_compiles", True, "compiled with the harness", "it compiles")

    expected = {
        "at_throws": "checked_element({1, 2, 3, 4}, 1) == 2, and indices 4 and 22 throw std::out_of_range",
        "catches_out_of_range": "try_element({1, 2, 3, 4}, 2) == 3, and std::nullopt for indices 4 and 22, "
                                "with no exception escaping",
        "nan_check": "safe_acos(0.5) == acos(0.5), safe_acos(1.0) == 0, std::nullopt for 1.1 and -1.1",
        "potato_no_copy": "make_potato(20.0): 1 Potato built from a double, 0 copies, 0 moves, "
                          "1 heap allocation (std::make_shared), size() 20",
    }
    for test, check_id in TESTS.items():
        run = run_program(s, [str(scratch / "harness"), test], f"harness_{test}", timeout=RUN_TIMEOUT, cwd=scratch)
        verdicts = [line for line in run.stdout.splitlines() if line.startswith(("PASS ", "FAIL "))]
        hint = None
        if verdicts:
            passed, observed = verdicts[-1].startswith("PASS "), verdicts[-1][5:]
            if check_id == "nan_check" and "the NaN was not detected" in observed:
                hint = ("comparing with NAN (a == NAN, a != NAN) never tells: NaN is unequal to everything, "
                        "itself included; use std::isnan(a) from <cmath>")
            elif (check_id == "potato_no_copy" and "0 copy(ies), 0 move(s)" in observed
                  and "1 heap allocation" not in observed):
                hint = ("std::shared_ptr<Potato>(new Potato(size)) allocates the Potato and the reference count "
                        "separately; std::make_shared<Potato>(size) does both in one allocation")
        else:
            passed = False
            observed = f"the test program ended before giving a verdict: {_ending(run)}"
            stderr = [line.strip() for line in run.stderr.splitlines() if line.strip()]
            if "__n < this->size()" in run.stderr:
                observed += ("; libstdc++'s bounds assertion fired inside std::vector::operator[] "
                             "(the check compiles with -D_GLIBCXX_ASSERTIONS; without it the index past "
                             "the end would have been read silently)")
                hint = "operator[] does not check the index: use values.at(index), which throws std::out_of_range"
            elif stderr:
                observed += f"; stderr: {stderr[-1][:200]!r}"
        s.record(check_id, passed, observed, expected[check_id], hint=hint)
