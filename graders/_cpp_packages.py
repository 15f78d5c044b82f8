"""Kit steps for C++ packages: use a learner's installed library from another package, read an executable's ELF.

* :func:`build_consumer` is what any other package of the workspace would do
  with the learner's library (seed ch. 27; ament_cmake's "Building a library"
  guide): ``find_package(<pkg>)`` through ``CMAKE_PREFIX_PATH`` and a link to
  the exported target ``<pkg>::<target>``. It configures and builds a small
  CMake project of the grader's in the check's log folder (inside the learner's
  workspace, nothing written elsewhere) with the learner's ``install/`` and
  the ROS install as the only ways to find anything.
* :func:`needed_libraries` and :func:`defined_functions` read an executable
  with binutils' ``readelf -d`` and ``nm`` (installed with g++), to tell a node
  that loads the library from one that compiled its own copy of its sources.

Every program runs through :func:`ros2course.kit.programs.run_program` (own
process group, deadline, capped output).
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from ros2course.kit import Session, Unmet
from ros2course.kit import package_prefix
from ros2course.kit.programs import compile_errors, run_program

#: Seconds for each cmake configure / build step of the consumer (about 1.5 s and 2.5 s on 2 idle cores).
BUILD_TIMEOUT = 120.0
#: Variables that would let the compiler or CMake find headers, libraries or the package some other way than
#: through the exported target: the consumer must see only what ``find_package`` gives it.
LEAKY_VARIABLES = ("CPATH", "C_INCLUDE_PATH", "CPLUS_INCLUDE_PATH", "LIBRARY_PATH", "CMAKE_INCLUDE_PATH",
                   "CMAKE_LIBRARY_PATH")
#: No package registries: a build tree exported with export(PACKAGE) must not stand in for the install.
_CONFIGURE_OPTIONS = ["-DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF", "-DCMAKE_FIND_USE_SYSTEM_PACKAGE_REGISTRY=OFF"]


def consumer_env(s: Session, package: str) -> dict[str, str]:
    """The workspace overlay (``source install/setup.bash``) without :data:`LEAKY_VARIABLES` and ``<package>_DIR``."""
    drop = {*LEAKY_VARIABLES, f"{package}_DIR", f"{package}_ROOT"}
    return {k: v for k, v in s.overlay().items() if k not in drop}


def _cache_value(build: Path, name: str) -> str | None:
    """``name``'s value in ``build/CMakeCache.txt``; None when absent."""
    try:
        text = (build / "CMakeCache.txt").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    match = re.search(rf"^{re.escape(name)}:[A-Z]+=(.*)$", text, re.MULTILINE)
    return match.group(1).strip() if match else None


def _errors(run, paths: dict[str, str]) -> str:
    """:func:`compile_errors` without lines repeating part of an earlier one (CMake's explanations often do)."""
    kept: list[str] = []
    for line in compile_errors(run, paths=paths).splitlines():
        if not any(line.strip() in earlier for earlier in kept):
            kept.append(line)
    return "\n".join(kept)


def build_consumer(s: Session, configure_check: str, build_check: str, template: Path, package: str,
                   library_file: str) -> Path:
    """Configure and build the CMake project ``template`` against the learner's install of ``package``.

    Records ``configure_check`` (cmake configures, and ``find_package(package)``
    found ``install/<package>/share/<package>/cmake``) and ``build_check``
    (it compiles, and the link line names ``<install prefix>/lib/<library_file>``).

    Args:
        template: folder with the consumer's CMakeLists.txt and sources (copied to ``<log_dir>/<template name>/src``).
        package: the learner's package, as ``find_package`` and the ament index name it.
        library_file: the library's file name, e.g. ``libcpp_package_with_a_library.so``.

    Returns:
        the consumer's build folder.

    Raises:
        Unmet: the package is not installed, or the consumer does not configure or build.
    """
    env = consumer_env(s, package)
    prefix = package_prefix(package, env)
    # the consumer is configured and built as the submission (it compiles the learner's headers)
    scratch = s.submission_folder(template.name, lambda folder: shutil.copytree(template, folder / "src"))
    build = scratch / "build"
    short = {str(scratch): "<grader>", str(s.workspace_root): "<workspace>"}
    expected = (f"find_package({package}) in another package finds install/{package}/share/{package}/cmake "
                "and the exported target brings everything the header needs")
    if prefix is None:
        s.record(configure_check, False, f"package {package} is not in the ament index of install/", expected)
        raise Unmet(f"{package} is not installed")
    configure = run_program(s, ["cmake", "-S", str(scratch / "src"), "-B", str(build), *_CONFIGURE_OPTIONS],
                            "consumer-configure", timeout=BUILD_TIMEOUT, env=env)
    found = _cache_value(build, f"{package}_DIR") or "not set"
    config = prefix / "share" / package / "cmake"
    if configure.returncode != 0 or configure.timed_out:
        s.record(configure_check, False, f"cmake configure: {configure.ending()} ({package}_DIR = {found})\n"
                 + _errors(configure, short), expected)
        raise Unmet("the consumer package does not configure")
    s.record(configure_check, Path(found).resolve() == config.resolve(),
             f"configured; {package}_DIR = {found}".replace(str(s.workspace_root), "<workspace>"), expected)
    s.require(configure_check)
    built = run_program(s, ["cmake", "--build", str(build), "--parallel", "2"], "consumer-build",
                        timeout=BUILD_TIMEOUT, env=env)
    expected = f"the consumer compiles and links install/{prefix.name}/lib/{library_file}"
    if built.returncode != 0 or built.timed_out:
        s.record(build_check, False, f"cmake --build: {built.ending()}\n" + _errors(built, short),
                 expected)
        raise Unmet("the consumer package does not build")
    links = " ".join(p.read_text(encoding="utf-8", errors="replace") for p in build.glob("CMakeFiles/*.dir/link.txt"))
    linked = str(prefix / "lib" / library_file) in links
    s.record(build_check, linked, f"built; the link line {'names' if linked else 'does not name'} "
             f"install/{package}/lib/{library_file}", expected)
    s.require(build_check)
    return build


def installed_library(s: Session, check_ids: tuple[str, str, str], package: str, library_file: str,
                      header: str, target: str) -> None:
    """Record three checks on the install prefix of ``package`` (ament index): library file, header, export.

    Args:
        check_ids: ``(library, header, export)`` check ids.
        library_file: e.g. ``libcpp_package_with_a_library.so``, looked for in ``<prefix>/lib``.
        header: e.g. ``cpp_package_with_a_library/sample_class.hpp``, looked for in ``<prefix>/include`` and
            ``<prefix>/include/<package>`` (the layout ament_cmake's Jazzy docs suggest).
        target: the imported target a ``share/<package>/cmake/*.cmake`` file must define (``add_library(<target> ...``),
            as ``ament_export_targets`` writes it.
    """
    library_id, header_id, export_id = check_ids
    prefix = package_prefix(package, s.overlay())
    if prefix is None:
        for check_id in check_ids:
            s.record(check_id, False, f"{package} is not in the ament index of install/", f"install/{package}/...")
        return
    library = prefix / "lib" / library_file
    s.record(library_id, library.is_file(), f"{library_file} {'is' if library.is_file() else 'is not'} "
             f"in install/{prefix.name}/lib", f"install/{prefix.name}/lib/{library_file} (a shared library)")
    headers = [h for h in (prefix / "include" / header, prefix / "include" / package / header) if h.is_file()]
    s.record(header_id, bool(headers), f"found {headers[0].relative_to(prefix)}" if headers else
             f"no include/{header} in install/{prefix.name}", f"install/{prefix.name}/include/{header}")
    texts = {p.name: p.read_text(encoding="utf-8", errors="replace")
             for p in sorted((prefix / "share" / package / "cmake").glob("*.cmake"))}
    defines = [name for name, text in texts.items() if re.search(rf"add_library\(\s*{re.escape(target)}\s", text)]
    s.record(export_id, bool(defines), f"{defines[0]} defines {target}" if defines else
             f"no file in share/{package}/cmake defines {target} (files: {', '.join(texts) or 'none'})",
             f"share/{package}/cmake/export_{package}Export.cmake defining {target}")


def needed_libraries(s: Session, executable: Path) -> list[str] | None:
    """The ``NEEDED`` entries of ``executable``'s dynamic section (``readelf -d``); None when unreadable."""
    run = run_program(s, ["readelf", "-d", str(executable)], "readelf", timeout=20.0)
    if run.returncode != 0:
        return None
    return re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", run.stdout)


def defined_functions(s: Session, executable: Path, prefix: str) -> list[str] | None:
    """Functions whose demangled names start with ``prefix`` (e.g. ``SampleClass::``) that ``executable``
    defines itself (``nm -C --defined-only``, types T/t: compiled into it, not inline copies); None when unreadable.
    """
    run = run_program(s, ["nm", "-C", "--defined-only", str(executable)], "nm", timeout=20.0)
    if run.returncode != 0:
        return None
    found = re.findall(r"^[0-9a-f]+ [Tt] (.+)$", run.stdout, re.MULTILINE)
    return sorted({name for name in found if name.startswith(prefix)})


def uses_library(s: Session, check_id: str, executable: Path, library_file: str, class_prefix: str) -> bool:
    """Record ``check_id``: ``executable`` loads ``library_file`` and compiles none of ``class_prefix``'s functions.

    The rule is the library's reason to exist (seed ch. 27.3: the local node
    uses the library of its package); listing the library's .cpp in the node's
    ``add_executable`` too compiles a second copy that the node runs instead.
    """
    needed = needed_libraries(s, executable)
    own = defined_functions(s, executable, class_prefix)
    expected = f"{executable.name} has {library_file} among its NEEDED libraries and defines no {class_prefix}* itself"
    if needed is None or own is None:
        return s.record(check_id, False, f"readelf/nm could not read {executable.name}", expected)
    problems = []
    if library_file not in needed:
        shown = ", ".join(needed[:4]) + (" ..." if len(needed) > 4 else "")
        problems.append(f"it does not load {library_file} (NEEDED: {shown or 'none'})")
    if own:
        problems.append(f"it compiled its own copy of {', '.join(own[:3])}" + (" ..." if len(own) > 3 else ""))
    return s.record(check_id, not problems, "; ".join(problems) if problems else
                    f"loads {library_file} and takes {class_prefix}* from it", expected)


__all__ = ["BUILD_TIMEOUT", "LEAKY_VARIABLES", "build_consumer", "consumer_env", "defined_functions", "installed_library",
           "needed_libraries", "uses_library"]
