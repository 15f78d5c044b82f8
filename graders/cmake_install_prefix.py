"""Grader for ``cmake-install-prefix`` (seed ch. 33; contract in shared/LESSONS.md).

Two plain CMake projects in the workspace, no ROS, no colcon:

* ``cmake/greeting_library``: a shared library ``greeting`` (header
  ``include/greeting/greeting.hpp``, ``greeting::greet(name)`` returning
  ``"Hello, <name>!"``) installed with its headers and a CMake package config
  (``install(EXPORT ...)`` + ``GreetingConfig.cmake`` in
  ``<prefix>/lib/cmake/Greeting/``) defining the imported target
  ``Greeting::greeting``;
* ``cmake/greeting_app``: ``find_package(Greeting REQUIRED)``, an executable
  ``greeting_app`` linked to ``Greeting::greeting`` that prints ``Hello, prefix!``.

The learner installs the library into ``cmake/prefix`` (workspace-relative).
The grader never trusts that install: it configures, builds and installs the
learner's library sources into its own prefix under ``s.log_dir`` (so nothing
is written in the learner's folders and an install cannot be faked), checks
the installed tree, then builds a copy of the app (copied alone, so it cannot
reach into the library's sources) with ``CMAKE_PREFIX_PATH`` holding only that
prefix, checks that ``find_package`` found the package there and that the link
line uses the installed library, and runs the app. Every cmake and program run
goes through :func:`graders.kit.programs.run_program` (own process group,
deadline, capped output).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from graders.kit import Check, GradingSession, Unmet
from graders.kit.programs import ProgramRun, run_program

LIBRARY = Path("cmake") / "greeting_library"
APP = Path("cmake") / "greeting_app"
#: The learner's own install prefix (workspace-relative), as the lesson asks.
LEARNER_PREFIX = Path("cmake") / "prefix"
HEADER = Path("greeting") / "greeting.hpp"
PACKAGE = "Greeting"
TARGET = "Greeting::greeting"
EXECUTABLE = "greeting_app"
EXPECTED_OUTPUT = "Hello, prefix!"

BUILD_TIMEOUT = 120.0  # seconds for each cmake configure / build / install step
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
    Check("app_builds", "The app compiles and links against the installed library", 2,
          "link the imported target: target_link_libraries(greeting_app PRIVATE Greeting::greeting); it brings "
          "the include folder and the library file", needs=("app_configures",)),
    Check("app_runs", f"./greeting_app prints '{EXPECTED_OUTPUT}' and exits with 0", 2,
          "main() prints greeting::greet(\"prefix\") followed by a newline and returns 0", needs=("app_builds",)),
]

#: Environment variables that would let a compiler or CMake find the library without the prefix.
_LEAKY_VARIABLES = ("CPATH", "C_INCLUDE_PATH", "CPLUS_INCLUDE_PATH", "LIBRARY_PATH", "LD_LIBRARY_PATH",
                    f"{PACKAGE}_DIR", f"{PACKAGE}_ROOT", "CMAKE_INCLUDE_PATH", "CMAKE_LIBRARY_PATH")
#: Options every grader configure gets: no package registries (only the prefix may find the package),
#: and an absolute install destination is an error instead of a write outside the grader's prefix.
_CONFIGURE_OPTIONS = ["-DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF", "-DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF",
                      "-DCMAKE_ERROR_ON_ABSOLUTE_INSTALL_DESTINATION=ON"]
#: A path written literally: starts with / or ~/ right after a separator (not after ${VAR}).
_ABSOLUTE = re.compile(r"""(?:^|(?<=[\s("'=;:]))((?:~|/)(?:/|[A-Za-z_.])[^\s)"';]*)""", re.MULTILINE)
#: Setting a prefix variable in a CMake file instead of on the command line.
_PREFIX_SET = re.compile(r"\b(?:set|list)\s*\(\s*(?:APPEND\s+|PREPEND\s+)?"
                         rf"(CMAKE_INSTALL_PREFIX|CMAKE_PREFIX_PATH|{PACKAGE}_DIR)\b", re.IGNORECASE)


def _strip_comments(text: str) -> str:
    """CMake text without ``#`` comments (bracket comments included, approximately)."""
    text = re.sub(r"#\[(=*)\[.*?\]\1\]", "", text, flags=re.DOTALL)
    return "\n".join(re.sub(r"#.*", "", line) for line in text.splitlines())


def hardcoded_paths(text: str) -> list[str]:
    """What in one CMake file's text hard-codes a location: absolute paths and prefix variables it sets."""
    code = _strip_comments(text)
    found = [m.group(1) for m in _ABSOLUTE.finditer(code)]
    found += [re.sub(r"\s+", " ", m.group(0)) + " ...)" for m in _PREFIX_SET.finditer(code)]
    return list(dict.fromkeys(found))


def _cmake_files(folder: Path) -> list[Path]:
    """The CMake files a project owns: CMakeLists.txt anywhere in it and *.cmake, skipping build folders."""
    out = []
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder)
        if any(part.startswith("build") or part in ("CMakeFiles", "install", "prefix") for part in rel.parts[:-1]):
            continue
        if path.is_file() and (path.name == "CMakeLists.txt" or path.suffix == ".cmake"):
            out.append(path)
    return out


def _excerpt(run: ProgramRun, scratch: Path, limit: int = 6) -> str:
    """The lines of a cmake/compiler run that say what went wrong (grader folders shortened).

    A ``CMake Error`` line comes with its indented explanation; make's own
    "Error 1/2" lines are left out when anything better was printed.
    """
    if run.timed_out:
        return run.describe()
    lines = [line.rstrip() for line in (run.stderr + "\n" + run.stdout).splitlines() if line.strip()]
    keys = ("error", "Error", "undefined reference", "not found", "No such file", "Could not find")
    picked: list[str] = []
    for i, line in enumerate(lines):
        if re.match(r"g?make(\[\d+\])?: ", line) or not any(k in line for k in keys):
            continue
        picked.append(line.strip())
        if line.startswith("CMake Error"):
            picked += [more.strip() for more in lines[i + 1:i + 4] if more.startswith(" ")]
    text = "\n".join((picked or lines[-limit:])[:limit]).replace(str(scratch), "<grader>")
    return text or run.describe()


def _clean_env(base: dict[str, str], prefix: Path) -> dict[str, str]:
    """The ROS environment with CMAKE_PREFIX_PATH holding only ``prefix`` and no include/library shortcuts."""
    env = {k: v for k, v in base.items() if k not in _LEAKY_VARIABLES}
    env["CMAKE_PREFIX_PATH"] = str(prefix)
    return env


def _cache_value(cache: Path, name: str) -> str | None:
    """``name``'s value in a CMakeCache.txt, None when absent."""
    try:
        text = cache.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    match = re.search(rf"^{re.escape(name)}:[A-Z]+=(.*)$", text, re.MULTILINE)
    return match.group(1).strip() if match else None


def _inside(path: Path, folder: Path) -> bool:
    try:
        return path.resolve().is_relative_to(folder.resolve())
    except OSError:
        return False


def _same(a: Path, b: Path) -> bool:
    try:
        return a.resolve() == b.resolve()
    except OSError:
        return False


def judge_sources(s: GradingSession) -> None:
    """``no_hardcoded_paths``: scan the two projects' CMake files."""
    root = s.workspace_root
    problems = []
    for folder in (LIBRARY, APP):
        for path in _cmake_files(root / folder):
            for found in hardcoded_paths(path.read_text(encoding="utf-8", errors="replace")):
                problems.append(f"{path.relative_to(root)}: {found}")
    app_text = "\n".join(_strip_comments(p.read_text(encoding="utf-8", errors="replace"))
                         for p in _cmake_files(root / APP))
    if "greeting_library" in app_text:
        problems.append(f"{APP}/CMakeLists.txt reaches into the library's source folder (greeting_library)")
    s.record("no_hardcoded_paths", not problems,
             "; ".join(problems[:5]) if problems else "no absolute path and no prefix set inside the CMake files",
             "locations only from the command line (CMAKE_INSTALL_PREFIX, CMAKE_PREFIX_PATH) and from "
             "${CMAKE_CURRENT_SOURCE_DIR} / GNUInstallDirs")


def judge_learner_prefix(s: GradingSession) -> None:
    """``learner_prefix``: the learner's own install is in cmake/prefix, and every build of the library they
    configured installs inside the workspace."""
    root = s.workspace_root
    problems = []
    for cache in sorted((root / "cmake").rglob("CMakeCache.txt")):
        home = _cache_value(cache, "CMAKE_HOME_DIRECTORY")
        value = _cache_value(cache, "CMAKE_INSTALL_PREFIX")
        if value is None or home is None or not _same(Path(home), root / LIBRARY):
            continue  # only builds of the library install anything (the app's default prefix is never used)
        where = cache.parent.relative_to(root)
        if not _inside(Path(value), root):
            problems.append(f"{where} installs into {value}, outside your workspace")
    configs = sorted((root / LEARNER_PREFIX).glob(f"lib*/cmake/{PACKAGE}/{PACKAGE}Config.cmake"))
    if not configs:
        problems.append(f"there is no {LEARNER_PREFIX}/lib/cmake/{PACKAGE}/{PACKAGE}Config.cmake: the library "
                        f"is not installed into {LEARNER_PREFIX}")
    s.record("learner_prefix", not problems,
             "; ".join(problems) if problems else f"installed in {configs[0].parent.relative_to(root)}",
             f"the library installed with CMAKE_INSTALL_PREFIX=<workspace>/{LEARNER_PREFIX}")


def build_library(s: GradingSession, scratch: Path, prefix: Path, env: dict[str, str]) -> None:
    """Configure, build and install the learner's library into the grader's ``prefix``."""
    build = scratch / "library-build"
    configure = run_program(s, ["cmake", "-S", str(s.workspace_root / LIBRARY), "-B", str(build),
                                f"-DCMAKE_INSTALL_PREFIX={prefix}", *_CONFIGURE_OPTIONS],
                            "cmake-configure-library", timeout=BUILD_TIMEOUT, env=env)
    if not s.record("library_configures", configure.returncode == 0 and not configure.timed_out,
                    f"cmake configure: {configure.describe()}"
                    + ("" if configure.returncode == 0 else "\n" + _excerpt(configure, scratch)),
                    "cmake -S cmake/greeting_library -B <build> -DCMAKE_INSTALL_PREFIX=<prefix> exits with 0"):
        raise Unmet("the library does not configure")
    built = run_program(s, ["cmake", "--build", str(build), "--parallel", "2"], "cmake-build-library",
                        timeout=BUILD_TIMEOUT, env=env)
    if not s.record("library_builds", built.returncode == 0 and not built.timed_out,
                    f"cmake --build: {built.describe()}" + ("" if built.returncode == 0 else "\n" + _excerpt(built, scratch)),
                    "the library compiles and links"):
        raise Unmet("the library does not build")
    # --prefix repeats the prefix at install time: a set(CMAKE_INSTALL_PREFIX ...) in the file cannot redirect it.
    installed = run_program(s, ["cmake", "--install", str(build), "--prefix", str(prefix)], "cmake-install-library",
                            timeout=BUILD_TIMEOUT, env=env)
    if not s.record("library_installs", installed.returncode == 0 and not installed.timed_out,
                    f"cmake --install: {installed.describe()}"
                    + ("" if installed.returncode == 0 else "\n" + _excerpt(installed, scratch)),
                    "cmake --install <build> succeeds with relative install destinations"):
        raise Unmet("the library does not install")


def judge_installed_tree(s: GradingSession, prefix: Path) -> None:
    """``installed_headers``, ``installed_library``, ``package_config``: what the install put in ``prefix``."""
    files = sorted(str(p.relative_to(prefix)) for p in prefix.rglob("*") if p.is_file() or p.is_symlink())
    listing = ", ".join(files[:12]) + (" ..." if len(files) > 12 else "") if files else "nothing"
    header = prefix / "include" / HEADER
    s.record("installed_headers", header.is_file(),
             f"found include/{HEADER}" if header.is_file() else f"no include/{HEADER}; the prefix holds: {listing}",
             f"<prefix>/include/{HEADER}")
    libraries = [p for p in prefix.glob("lib*/libgreeting*") if ".so" in p.name or p.suffix == ".a"]
    s.record("installed_library", bool(libraries),
             f"found {libraries[0].relative_to(prefix)}" if libraries else f"no lib/libgreeting.so; the prefix holds: "
             f"{listing}", "<prefix>/lib/libgreeting.so (or libgreeting.a)")
    configs = sorted(prefix.glob(f"lib*/cmake/{PACKAGE}/{PACKAGE}Config.cmake"))
    if not configs:
        s.record("package_config", False, f"no lib/cmake/{PACKAGE}/{PACKAGE}Config.cmake; the prefix holds: {listing}",
                 f"<prefix>/lib/cmake/{PACKAGE}/{PACKAGE}Config.cmake (install(EXPORT ...) and install(FILES ...))")
        return
    folder = configs[0].parent
    texts = {p.name: p.read_text(encoding="utf-8", errors="replace") for p in sorted(folder.glob("*.cmake"))}
    defines = [name for name, text in texts.items() if re.search(rf"add_library\(\s*{re.escape(TARGET)}\s", text)]
    targets = sorted({m for text in texts.values() for m in re.findall(r"add_library\(\s*(\S+)\s", text)})
    s.record("package_config", bool(defines),
             f"{folder.relative_to(prefix)} holds {', '.join(texts)}; "
             + (f"{defines[0]} defines {TARGET}" if defines
                else f"no file there defines {TARGET} (imported targets found: {', '.join(targets) or 'none'})"),
             f"{PACKAGE}Config.cmake and the exported targets file defining {TARGET} "
             f"(install(EXPORT ... NAMESPACE {PACKAGE}:: ...))")


def build_app(s: GradingSession, scratch: Path, prefix: Path, env: dict[str, str]) -> Path:
    """Configure and build a copy of the app against ``prefix`` only; returns the build folder."""
    source = scratch / "app-src"
    shutil.copytree(s.workspace_root / APP, source,
                    ignore=shutil.ignore_patterns("build*", "CMakeCache.txt", "CMakeFiles", "prefix", "install"))
    build = scratch / "app-build"
    configure = run_program(s, ["cmake", "-S", str(source), "-B", str(build), *_CONFIGURE_OPTIONS],
                            "cmake-configure-app", timeout=BUILD_TIMEOUT, env=env)
    found = _cache_value(build / "CMakeCache.txt", f"{PACKAGE}_DIR")
    expected = f"cmake configure exits with 0 with CMAKE_PREFIX_PATH=<grader prefix> only, and {PACKAGE}_DIR " \
               f"is <grader prefix>/lib/cmake/{PACKAGE}"
    if configure.returncode != 0 or configure.timed_out:
        s.record("app_configures", False, f"cmake configure: {configure.describe()}\n{_excerpt(configure, scratch)}",
                 expected)
        raise Unmet("the app does not configure")
    if not found or found.endswith("-NOTFOUND") or not _inside(Path(found), prefix):
        s.record("app_configures", False,
                 f"configured, but {PACKAGE}_DIR is {found or 'not set'}: " + (
                     f"the app never calls find_package({PACKAGE})" if not found
                     else f"find_package({PACKAGE}) did not find the package in the prefix"), expected)
        raise Unmet("the app does not find the package through the prefix")
    s.record("app_configures", True, f"configured; {PACKAGE}_DIR = {found.replace(str(scratch), '<grader>')}", expected)
    built = run_program(s, ["cmake", "--build", str(build), "--parallel", "2"], "cmake-build-app",
                        timeout=BUILD_TIMEOUT, env=env)
    if built.returncode != 0 or built.timed_out:
        s.record("app_builds", False, f"cmake --build: {built.describe()}\n{_excerpt(built, scratch)}",
                 f"the app compiles and links {TARGET}")
        raise Unmet("the app does not build")
    link_lines = [p.read_text(encoding="utf-8", errors="replace") for p in build.glob("CMakeFiles/*.dir/link.txt")]
    linked = any(re.search(re.escape(str(prefix)) + r"/lib[^/\s]*/libgreeting", text) for text in link_lines)
    s.record("app_builds", linked,
             "built; the link line uses <grader prefix>/lib/libgreeting" if linked
             else "built, but no link line uses the library installed in the prefix",
             f"the app compiles and links {TARGET} from the prefix")
    if not linked:
        raise Unmet("the app does not link the installed library")
    return build


def grade(s: GradingSession) -> None:
    """Judge the sources and the learner's prefix, then rebuild library and app under ``s.log_dir`` and run the app."""
    root = s.workspace_root
    missing = [str(folder / "CMakeLists.txt") for folder in (LIBRARY, APP) if not (root / folder / "CMakeLists.txt").is_file()]
    if not s.record("layout", not missing, "missing: " + ", ".join(missing) if missing else "both projects are there",
                    f"{LIBRARY}/CMakeLists.txt and {APP}/CMakeLists.txt"):
        raise Unmet("the projects are missing")
    judge_sources(s)
    judge_learner_prefix(s)
    scratch = s.log_dir / "cmake-install-prefix"
    shutil.rmtree(scratch, ignore_errors=True)
    scratch.mkdir(parents=True)
    prefix = scratch / "prefix"
    env = _clean_env(s.base_env, prefix)
    build_library(s, scratch, prefix, env)
    judge_installed_tree(s, prefix)
    build = build_app(s, scratch, prefix, env)
    executable = build / EXECUTABLE
    if not executable.is_file():
        s.record("app_runs", False, f"the build made no executable named {EXECUTABLE}",
                 f"add_executable({EXECUTABLE} ...)")
        return
    run = run_program(s, [str(executable)], "greeting-app", timeout=RUN_TIMEOUT, env=env, cwd=build)
    out = run.stdout.strip()
    s.record("app_runs", run.returncode == 0 and not run.timed_out and out == EXPECTED_OUTPUT,
             f"printed {out[:200]!r}, {run.describe()}", f"prints exactly {EXPECTED_OUTPUT!r}, exit code 0")
