"""Grader for ``cmake-install-prefix`` (seed ch. 33; contract in shared/LESSONS.md).

Two plain CMake projects in the workspace, no ROS, no colcon:
``cmake/greeting_library`` (a shared library ``greeting`` installed with its
header ``greeting/greeting.hpp`` and a package config in
``<prefix>/lib/cmake/Greeting/`` defining ``Greeting::greeting``) and
``cmake/greeting_app`` (``find_package(Greeting REQUIRED)``, an executable
printing ``Hello, prefix!``). The learner installs the library into
``cmake/prefix``. The grader never trusts that install: it configures, builds
and installs the library's sources into its own prefix under ``s.log_dir``
(nothing is written in the learner's folders; an install cannot be faked),
checks the installed tree, then builds a copy of the app (copied alone, so it
cannot reach into the library's sources) with ``CMAKE_PREFIX_PATH`` holding
only that prefix, checks that ``find_package`` found the package there and that
the link line uses the installed library, and runs the app. Every cmake and
program run goes through the kit (:mod:`ros2course.kit.cmake`).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from ros2course.kit import Check, Session, Unmet
from ros2course.kit import cmake as ck
from ros2course.kit.programs import run_program

LIBRARY = Path("cmake") / "greeting_library"
APP = Path("cmake") / "greeting_app"
#: The learner's own install prefix (workspace-relative), as the lesson asks.
LEARNER_PREFIX = Path("cmake") / "prefix"
HEADER = Path("greeting") / "greeting.hpp"
PACKAGE = "Greeting"
TARGET = "Greeting::greeting"
EXECUTABLE = "greeting_app"
EXPECTED_OUTPUT = "Hello, prefix!"
RUN_TIMEOUT = 10.0  # seconds for the app to print its line and exit

#: Seconds of observation the contract needs (benchmarks read it): none, everything is built and run to completion.
WINDOW = 0.0

CHECKS = [
    Check("layout", "cmake/greeting_library and cmake/greeting_app each have a CMakeLists.txt", 1,
          f"keep the two projects in {LIBRARY}/ and {APP}/ of your workspace, each with its CMakeLists.txt"),
    Check("no_hardcoded_paths", "The CMake files hard-code no absolute path or prefix", 2,
          "give the prefix on the command line (-DCMAKE_INSTALL_PREFIX=..., -DCMAKE_PREFIX_PATH=...), never in "
          "CMakeLists.txt; use ${CMAKE_CURRENT_SOURCE_DIR}, GNUInstallDirs and the imported target instead of "
          "/usr/local/... or /home/... paths"),
    Check("learner_prefix", "You installed the library into cmake/prefix inside your workspace", 1,
          "from the workspace: cmake -S cmake/greeting_library -B cmake/greeting_library/build "
          "-DCMAKE_INSTALL_PREFIX=\"$PWD/cmake/prefix\", then cmake --build ... and cmake --install ..."),
    Check("library_configures", "The library configures with cmake -DCMAKE_INSTALL_PREFIX=<prefix>", 1,
          "run cmake -S cmake/greeting_library -B /tmp/b yourself and fix the first 'CMake Error'"),
    Check("library_builds", "The library builds", 1,
          "run cmake --build on your build folder and fix the first compiler error", needs=("library_configures",)),
    Check("library_installs", "cmake --install succeeds", 1,
          "install(...) destinations must be relative (lib, include, lib/cmake/Greeting), never absolute",
          needs=("library_builds",)),
    Check("installed_headers", "The header lands in <prefix>/include/greeting/greeting.hpp", 1,
          "install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})", needs=("library_installs",)),
    Check("installed_library", "The library file lands in <prefix>/lib", 1,
          "install(TARGETS greeting EXPORT GreetingTargets LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} ...)",
          needs=("library_installs",)),
    Check("package_config", f"<prefix>/lib/cmake/{PACKAGE}/ holds {PACKAGE}Config.cmake and the target {TARGET}", 2,
          "install(EXPORT GreetingTargets NAMESPACE Greeting:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/Greeting) "
          "and install(FILES cmake/GreetingConfig.cmake DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/Greeting); "
          "GreetingConfig.cmake includes GreetingTargets.cmake", needs=("library_installs",)),
    Check("app_configures", f"The app configures and find_package({PACKAGE}) finds it through the prefix only", 2,
          "in the app: find_package(Greeting REQUIRED) and target_link_libraries(greeting_app PRIVATE "
          "Greeting::greeting); configure with -DCMAKE_PREFIX_PATH=<prefix>", needs=("library_installs",)),
    Check("app_finds_nothing_else", f"Without a prefix on the command line, find_package({PACKAGE}) finds nothing", 1,
          "no HINTS or PATHS in find_package, no path to a prefix inside the project: the prefix comes from "
          "-DCMAKE_PREFIX_PATH only", needs=("app_configures",)),
    Check("app_builds", "The app compiles and links against the installed library", 2,
          "link the imported target: target_link_libraries(greeting_app PRIVATE Greeting::greeting); it brings "
          "the include folder and the library file", needs=("app_configures",)),
    Check("app_runs", f"./greeting_app prints '{EXPECTED_OUTPUT}' and exits with 0", 2,
          "main() prints greeting::greet(\"prefix\") followed by a newline and returns 0", needs=("app_builds",)),
]


def grade(s: Session) -> None:
    """Judge the sources and the learner's prefix, then rebuild library and app under ``s.log_dir`` and run the app."""
    root = s.workspace_root
    missing = [str(f / "CMakeLists.txt") for f in (LIBRARY, APP) if not (root / f / "CMakeLists.txt").is_file()]
    if not s.record("layout", not missing, "missing: " + ", ".join(missing) if missing else "both projects are there",
                    f"{LIBRARY}/CMakeLists.txt and {APP}/CMakeLists.txt"):
        raise Unmet("the projects are missing")
    _judge_sources(s)
    _judge_learner_prefix(s)
    # CMake runs as the submission and writes the builds and the prefix: a submission folder, with the
    # app's sources copied in before it changes hands
    scratch = s.submission_folder("cmake-install-prefix", lambda folder: shutil.copytree(
        root / APP, folder / "app-src",
        ignore=shutil.ignore_patterns("build*", "CMakeCache.txt", "CMakeFiles", "prefix", "install")))
    prefix, source, build = scratch / "prefix", scratch / "app-src", scratch / "app-build"
    env = ck.prefix_only_env(s.base_env, prefix, PACKAGE)
    cmake = ck.tool(env, "cmake")
    options = dict(env=env, paths={str(scratch): "<grader>"})
    ck.build_and_install(s, ("library_configures", "library_builds", "library_installs"), root / LIBRARY,
                         scratch / "library-build", prefix, label="library", **options)
    ck.installed_file(s, "installed_headers", prefix, f"include/{HEADER}", f"<prefix>/include/{HEADER}")
    ck.installed_file(s, "installed_library", prefix, "lib*/libgreeting.[sa]*", "<prefix>/lib/libgreeting.so (or .a)")
    ck.package_config(s, "package_config", prefix, PACKAGE, TARGET)

    expected = (f"cmake configure exits with 0 with CMAKE_PREFIX_PATH=<grader prefix> only, and {PACKAGE}_DIR "
                f"is <grader prefix>/lib/cmake/{PACKAGE}")
    ck.step(s, "app_configures", [cmake, "-S", str(source), "-B", str(build), *ck.ISOLATED_OPTIONS],
            "cmake-configure-app", shown="cmake configure", expected=expected, **options)
    ck.found_package(s, "app_configures", build, PACKAGE, prefix, expected, paths=options["paths"])
    _finds_nothing_else(s, env, cmake, source, scratch)
    ck.step(s, "app_builds", [cmake, "--build", str(build), "--parallel", "2"], "cmake-build-app",
            shown="cmake --build", expected=f"the app compiles and links {TARGET}", **options)
    linked = ck.links_from(build, prefix, "greeting")
    if not s.record("app_builds", linked, "built; the link line uses <grader prefix>/lib/libgreeting" if linked
                    else "built, but no link line uses the library installed in the prefix",
                    f"the app compiles and links {TARGET} from the prefix"):
        raise Unmet("the app does not link the installed library")
    if not (build / EXECUTABLE).is_file():
        s.record("app_runs", False, f"the build made no executable named {EXECUTABLE}", f"add_executable({EXECUTABLE} ...)")
        raise Unmet(f"no {EXECUTABLE} was built")
    run = run_program(s, [str(build / EXECUTABLE)], "greeting-app", timeout=RUN_TIMEOUT, env=env, cwd=build)
    out = run.stdout.strip()
    s.record("app_runs", run.returncode == 0 and not run.timed_out and out == EXPECTED_OUTPUT,
             f"printed {out[:200]!r}, {run.describe()}", f"prints exactly {EXPECTED_OUTPUT!r}, exit code 0")


#: find_package(...) with HINTS or PATHS, or $ENV{HOME} anywhere: a search path the project names itself.
_OWN_SEARCH_PATH = re.compile(r"find_package\s*\([^)]*\b(?:HINTS|PATHS)\b[^)]*\)|\$ENV\{HOME\}", re.IGNORECASE)


def _finds_nothing_else(s: Session, env: dict[str, str], cmake: str, source: Path, scratch: Path) -> None:
    """``app_finds_nothing_else``: the app configured with no CMAKE_PREFIX_PATH at all (and an empty HOME) must not
    find the package: the lesson's "find_package(Greeting) must find it there, and nothing else may". A project
    that points find_package at a prefix itself (``PATHS ${CMAKE_CURRENT_SOURCE_DIR}/../prefix``, ``HINTS
    $ENV{HOME}/...``) found the grader's prefix or the learner's and passed (helper audit of issue 37)."""
    home = s.submission_folder("cmake-empty-home")  # made by the grader, then the submission's (never written here)
    bare = {k: v for k, v in env.items() if k != "CMAKE_PREFIX_PATH"} | {"HOME": str(home)}
    build = scratch / "app-build-without-prefix"
    run = run_program(s, [cmake, "-S", str(source), "-B", str(build), *ck.ISOLATED_OPTIONS], "cmake-configure-bare",
                      timeout=RUN_TIMEOUT * 4, env=bare, cwd=scratch)
    found = ck.cache_value(build / "CMakeCache.txt", f"{PACKAGE}_DIR") or ""
    located = found and not found.endswith("-NOTFOUND")
    s.record("app_finds_nothing_else", not located,
             f"configured with no CMAKE_PREFIX_PATH, it found {PACKAGE} at "
             f"{found.replace(str(scratch), '<grader>')}: the project names a prefix itself" if located else
             f"configured with no CMAKE_PREFIX_PATH, find_package({PACKAGE}) found nothing ({run.describe()})",
             f"cmake configure with no CMAKE_PREFIX_PATH (and an empty HOME) does not find {PACKAGE}")


def _judge_sources(s: Session) -> None:
    """``no_hardcoded_paths``: scan the two projects' CMake files (and the app must not reach into the library)."""
    root = s.workspace_root
    problems = [f"{path.relative_to(root)}: {found}" for folder in (LIBRARY, APP) for path in ck.cmake_files(root / folder)
                for found in ck.hardcoded_paths(path.read_text(encoding="utf-8", errors="replace"),
                                                ("CMAKE_INSTALL_PREFIX", "CMAKE_PREFIX_PATH", f"{PACKAGE}_DIR"))]
    # a search path of its own in find_package, or the user's home: locations that only hold on one machine
    problems += [f"{path.relative_to(root)}: {m.group(0)[:80]}" for path in ck.cmake_files(root / APP)
                 for m in _OWN_SEARCH_PATH.finditer(ck.strip_comments(path.read_text(encoding="utf-8",
                                                                                    errors="replace")))]
    if any("greeting_library" in ck.strip_comments(p.read_text(encoding="utf-8", errors="replace"))
           for p in ck.cmake_files(root / APP)):
        problems.append(f"{APP}/CMakeLists.txt reaches into the library's source folder (greeting_library)")
    s.record("no_hardcoded_paths", not problems,
             "; ".join(problems[:5]) if problems else "no absolute path and no prefix set inside the CMake files",
             "locations only from the command line (CMAKE_INSTALL_PREFIX, CMAKE_PREFIX_PATH) and from "
             "${CMAKE_CURRENT_SOURCE_DIR} / GNUInstallDirs")


def _judge_learner_prefix(s: Session) -> None:
    """``learner_prefix``: the library is installed in cmake/prefix, and every build of it installs in the workspace.

    Only builds of the library count (their CMAKE_HOME_DIRECTORY is the library's folder): the app's default
    install prefix is never used.
    """
    root = s.workspace_root
    problems = [f"{build.relative_to(root)} installs into {value}, outside your workspace"
                for build, value in ck.configured_prefixes(root / "cmake", root / LIBRARY).items()
                if not ck.inside(Path(value), root)]
    configs = sorted((root / LEARNER_PREFIX).glob(f"lib*/cmake/{PACKAGE}/{PACKAGE}Config.cmake"))
    if not configs:
        problems.append(f"there is no {LEARNER_PREFIX}/lib/cmake/{PACKAGE}/{PACKAGE}Config.cmake: the library "
                        f"is not installed into {LEARNER_PREFIX}")
    s.record("learner_prefix", not problems,
             "; ".join(problems) if problems else f"installed in {configs[0].parent.relative_to(root)}",
             f"the library installed with CMAKE_INSTALL_PREFIX=<workspace>/{LEARNER_PREFIX}")

