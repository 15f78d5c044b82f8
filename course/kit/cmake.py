"""Kit steps for plain CMake projects (no colcon): configure, build, install, read the cache and the CMake text.

Every command runs through :func:`ros2course.kit.programs.run_program` (own
process group, deadline, capped output), out of source, in a build folder the
grader chooses under ``s.log_dir``: nothing is written into the learner's
folders. A step that fails records its check with the compiler's or CMake's
own error lines (:func:`ros2course.kit.programs.compile_errors`) and raises
:class:`Unmet`, so the checks that need the build become "not checked".

Typical use::

    cmake = kit.cmake.tool(s.base_env, "cmake")
    kit.cmake.step(s, "builds", [cmake, "-S", src, "-B", build], "cmake_configure", shown="cmake -S . -B build",
                   expected="it configures", paths={str(src): "."})
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Mapping
from pathlib import Path

from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course.kit.programs import ProgramRun, compile_errors, run_program

#: Seconds for each configure, build, install or compiler call.
BUILD_TIMEOUT = 120.0

#: A path written literally: starts with / or ~/ right after a separator (not after ${VAR}).
_ABSOLUTE = re.compile(r"""(?:^|(?<=[\s("'=;:]))((?:~|/)(?:/|[A-Za-z_.])[^\s)"';]*)""", re.MULTILINE)


def tool(env: Mapping[str, str], *names: str) -> str:
    """The first of ``names`` (e.g. ``"g++", "c++"``) found on ``env``'s PATH.

    Raises:
        Unmet: none is installed (the lesson's ``requires`` normally catches this before grading).
    """
    for name in names:
        found = shutil.which(name, path=env.get("PATH", os.defpath))
        if found:
            return found
    raise Unmet(f"{' or '.join(names)} is not on PATH: install it (apt-get install cmake g++)")


def step(s: Session, check_id: str, argv: list[str], label: str, *, shown: str, expected: str,
         passed: str | None = None, env: dict[str, str] | None = None, cwd: Path | None = None,
         paths: Mapping[str, str] | None = None, timeout: float = BUILD_TIMEOUT) -> ProgramRun:
    """Run one build command; on failure record ``check_id`` with its error lines and raise :class:`Unmet`.

    Args:
        shown: the command as the learner would type it (e.g. ``"cmake --build build"``), for feedback.
        passed: when given, ``check_id`` is recorded as passed with this text on success (several
            steps can share one check: only the last one says ``passed``).
        paths: grader folders to shorten in the quoted errors (:func:`compile_errors`).

    Raises:
        Unmet: it exited non-zero or ran past ``timeout`` seconds.
    """
    run = run_program(s, argv, label, timeout=timeout, env=env, cwd=cwd)
    if run.returncode != 0 or run.timed_out:
        s.record(check_id, False, f"{shown} failed ({run.describe()}):\n{compile_errors(run, paths=paths)}", expected)
        raise Unmet(f"{shown} failed")
    if passed is not None:
        s.record(check_id, True, passed, expected)
    return run


def cache_value(cache: Path, name: str) -> str | None:
    """``name``'s value in a ``CMakeCache.txt`` (e.g. ``Greeting_DIR``), None when absent or unreadable."""
    try:
        text = cache.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    match = re.search(rf"^{re.escape(name)}:[A-Z]+=(.*)$", text, re.MULTILINE)
    return match.group(1).strip() if match else None


def strip_comments(text: str) -> str:
    """CMake text without ``#`` comments (bracket comments ``#[[ ... ]]`` included, approximately)."""
    text = re.sub(r"#\[(=*)\[.*?\]\1\]", "", text, flags=re.DOTALL)
    return "\n".join(re.sub(r"#.*", "", line) for line in text.splitlines())


def cmake_files(folder: Path) -> list[Path]:
    """The CMake files a project owns: every CMakeLists.txt and ``*.cmake``, skipping build and install folders."""
    out = []
    for path in sorted(folder.rglob("*")):
        rel = path.relative_to(folder)
        if any(part.startswith("build") or part in ("CMakeFiles", "install", "prefix") for part in rel.parts[:-1]):
            continue
        if path.is_file() and (path.name == "CMakeLists.txt" or path.suffix == ".cmake"):
            out.append(path)
    return out


#: An install destination made absolute from the configured prefix (``DESTINATION ${CMAKE_INSTALL_PREFIX}/lib``,
#: ``DESTINATION "${CMAKE_INSTALL_FULL_LIBDIR}"``), ``INSTALL_DESTINATION`` of configure_package_config_file too.
_PREFIXED_DESTINATION = re.compile(r"""DESTINATION\s+"?(\$\{CMAKE_INSTALL_(?:PREFIX|FULL_\w+)\}[^\s)"]*)""")


def hardcoded_paths(text: str, variables: tuple[str, ...] = ("CMAKE_INSTALL_PREFIX", "CMAKE_PREFIX_PATH")) -> list[str]:
    """What in one CMake file's text hard-codes a location: absolute paths, and ``set()``s of ``variables``.

    CMake's own advice (cmake-packages(7), "Creating Relocatable Packages"):
    locations come from the command line and from ``${CMAKE_CURRENT_SOURCE_DIR}`` /
    GNUInstallDirs, so the project builds and installs anywhere. An install ``DESTINATION`` made absolute
    with ``${CMAKE_INSTALL_PREFIX}/...`` or ``${CMAKE_INSTALL_FULL_<dir>}`` counts too: it is fixed when the
    project is configured, so ``cmake --install --prefix <other>`` still writes into the configured prefix
    (install(): "relative paths are interpreted with respect to the installation prefix"), and the exported
    targets are not relocatable (cmake-packages(7)).
    """
    code = strip_comments(text)
    setter = re.compile(r"\b(?:set|list)\s*\(\s*(?:APPEND\s+|PREPEND\s+)?(" + "|".join(map(re.escape, variables))
                        + r")\b", re.IGNORECASE)
    found = [m.group(1) for m in _ABSOLUTE.finditer(code)]
    found += [f"DESTINATION {m.group(1)}" for m in _PREFIXED_DESTINATION.finditer(code)]
    found += [re.sub(r"\s+", " ", m.group(0)) + " ...)" for m in setter.finditer(code)]
    return list(dict.fromkeys(found))


def inside(path: Path, folder: Path) -> bool:
    """True when ``path`` lies in ``folder`` once both are resolved (False if either cannot be resolved)."""
    try:
        return path.resolve().is_relative_to(folder.resolve())
    except OSError:
        return False


def listing(prefix: Path, most: int = 12) -> str:
    """The files under an install ``prefix``, for feedback: ``include/a.hpp, lib/liba.so ...`` or ``nothing``."""
    files = sorted(str(p.relative_to(prefix)) for p in prefix.rglob("*") if p.is_file() or p.is_symlink())
    return ", ".join(files[:most]) + (" ..." if len(files) > most else "") if files else "nothing"


def exported_targets(config_folder: Path) -> dict[str, str]:
    """The imported targets the ``*.cmake`` files of an installed package define: ``{target: file name}``.

    ``install(EXPORT ...)`` writes them as ``add_library(<Namespace>::<name> SHARED IMPORTED)``
    (cmake-packages(7)).
    """
    found = {}
    for path in sorted(config_folder.glob("*.cmake")):
        for target in re.findall(r"add_library\(\s*(\S+)\s", path.read_text(encoding="utf-8", errors="replace")):
            found.setdefault(target, path.name)
    return found


def links_from(build: Path, folder: Path, library: str) -> bool:
    """Whether a link line of the Makefile build in ``build`` names ``<folder>/lib*/lib<library>...``."""
    pattern = re.escape(str(folder)) + rf"/lib[^/\s]*/lib{re.escape(library)}"
    return any(re.search(pattern, p.read_text(encoding="utf-8", errors="replace"))
               for p in build.glob("CMakeFiles/*.dir/link.txt"))


#: Configure options that keep a grader's build honest: no package registries (only the prefix may find a
#: package), and an absolute install destination is an error instead of a write outside the grader's prefix.
ISOLATED_OPTIONS = ("-DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF", "-DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF",
                    "-DCMAKE_ERROR_ON_ABSOLUTE_INSTALL_DESTINATION=ON")
#: Environment variables that let a compiler or CMake find headers and libraries without CMAKE_PREFIX_PATH.
_SHORTCUTS = ("CPATH", "C_INCLUDE_PATH", "CPLUS_INCLUDE_PATH", "LIBRARY_PATH", "LD_LIBRARY_PATH", "CMAKE_INCLUDE_PATH",
              "CMAKE_LIBRARY_PATH")


def prefix_only_env(base: Mapping[str, str], prefix: Path, package: str) -> dict[str, str]:
    """``base`` with ``CMAKE_PREFIX_PATH`` holding only ``prefix`` and no other way to find ``package``.

    Drops the compiler's include/library search variables and ``<package>_DIR`` /
    ``<package>_ROOT`` (find_package's search procedure, cmake-commands(7)).
    """
    drop = (*_SHORTCUTS, f"{package}_DIR", f"{package}_ROOT")
    return {k: v for k, v in base.items() if k not in drop} | {"CMAKE_PREFIX_PATH": str(prefix)}


def configured_prefixes(folder: Path, source: Path) -> dict[Path, str]:
    """``{build folder: CMAKE_INSTALL_PREFIX}`` of every build under ``folder`` configured from ``source``."""
    found = {}
    for cache in sorted(folder.rglob("CMakeCache.txt")):
        home, value = cache_value(cache, "CMAKE_HOME_DIRECTORY"), cache_value(cache, "CMAKE_INSTALL_PREFIX")
        if home is not None and value is not None and Path(home).resolve() == source.resolve():
            found[cache.parent] = value
    return found


def found_package(s: Session, check_id: str, build: Path, package: str, prefix: Path, expected: str,
                  paths: Mapping[str, str] | None = None) -> bool:
    """Record ``check_id``: the configured ``build`` found ``package`` (``<package>_DIR`` in its cache) under ``prefix``.

    Raises:
        Unmet: ``find_package`` was never called, or found the package elsewhere.
    """
    found = cache_value(build / "CMakeCache.txt", f"{package}_DIR") or ""
    ok = not found.endswith("-NOTFOUND") and inside(Path(found), prefix) if found else False
    for path, short in (paths or {}).items():
        found = found.replace(path, short)
    if not s.record(check_id, ok, f"configured; {package}_DIR = {found}" if ok
                    else f"configured, but {package}_DIR is {found or 'not set'}: "
                    + (f"find_package({package}) did not find the package in the prefix" if found
                       else f"the project never calls find_package({package})"), expected):
        raise Unmet(f"the project does not find {package} through the prefix")
    return ok


def installed_file(s: Session, check_id: str, prefix: Path, pattern: str, expected: str) -> bool:
    """Record ``check_id``: an install put a file matching ``pattern`` (a glob under ``prefix``) there."""
    found = sorted(p for p in prefix.glob(pattern) if p.is_file())
    return s.record(check_id, bool(found), f"found {found[0].relative_to(prefix)}" if found
                    else f"nothing matches {pattern}; the prefix holds: {listing(prefix)}", expected)


def package_config(s: Session, check_id: str, prefix: Path, package: str, target: str) -> bool:
    """Record ``check_id``: ``<prefix>/lib*/cmake/<package>/<package>Config.cmake`` exists and a file beside it
    defines the imported ``target`` (what ``install(EXPORT ... NAMESPACE <package>::)`` writes, cmake-packages(7))."""
    expected = (f"{package}Config.cmake and the exported targets file defining {target} "
                f"(install(EXPORT ... NAMESPACE {package}:: ...))")
    configs = sorted(prefix.glob(f"lib*/cmake/{package}/{package}Config.cmake"))
    if not configs:
        return s.record(check_id, False, f"no lib/cmake/{package}/{package}Config.cmake; the prefix holds: "
                        f"{listing(prefix)}", expected)
    folder = configs[0].parent
    targets = exported_targets(folder)
    return s.record(check_id, target in targets,
                    f"{folder.relative_to(prefix)} holds {', '.join(p.name for p in sorted(folder.glob('*.cmake')))}; "
                    + (f"{targets[target]} defines {target}" if target in targets else
                       f"no file there defines {target} (imported targets found: {', '.join(targets) or 'none'})"),
                    expected)


def build_and_install(s: Session, checks: tuple[str, str, str], source: Path, build: Path, prefix: Path, *,
                      label: str, env: dict[str, str] | None = None, paths: Mapping[str, str] | None = None) -> None:
    """Configure ``source`` into ``build`` with ``CMAKE_INSTALL_PREFIX=<prefix>``, build it, install it into ``prefix``.

    Each stage records its own check of ``checks`` (configure, build, install): passed,
    or failed with CMake's or the compiler's error lines. Configured with
    :data:`ISOLATED_OPTIONS`; the install repeats ``--prefix``, so a
    ``set(CMAKE_INSTALL_PREFIX ...)`` in the project cannot redirect it.

    Raises:
        Unmet: a stage failed (the later ones are then "not checked" through their needs).
    """
    cmake = tool(env or s.base_env, "cmake")
    configure_id, build_id, install_id = checks
    step(s, configure_id, [cmake, "-S", str(source), "-B", str(build), f"-DCMAKE_INSTALL_PREFIX={prefix}",
                           *ISOLATED_OPTIONS], f"cmake-configure-{label}", shown="cmake configure", passed="configured",
         expected="cmake -S <source> -B <build> -DCMAKE_INSTALL_PREFIX=<prefix> exits with 0", env=env, paths=paths)
    step(s, build_id, [cmake, "--build", str(build), "--parallel", "2"], f"cmake-build-{label}", shown="cmake --build",
         passed="built", expected="it compiles and links", env=env, paths=paths)
    step(s, install_id, [cmake, "--install", str(build), "--prefix", str(prefix)], f"cmake-install-{label}",
         shown="cmake --install", passed="installed", env=env, paths=paths,
         expected="cmake --install <build> succeeds with relative install destinations")
