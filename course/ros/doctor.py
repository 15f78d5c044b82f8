"""``ros2course doctor`` and the optional components a workspace needs, built on demand.

Above both the ROS install's activation (:mod:`ros2course.ros.env`) and the
underlay's build (:mod:`ros2course.ros.underlay_build`), which it calls: split
from :mod:`ros2course.ros.env` so that no module of the ROS layer imports another
in a cycle (issue 23).
"""

from __future__ import annotations

import dataclasses
import importlib.util
import subprocess
import sys
import sysconfig
from collections.abc import Callable
from pathlib import Path

from ros2course.errors import CourseError, MissingRequirement, NotGradable
from ros2course.ros import compiler_cache
from ros2course.ros import env as env_mod
from ros2course.ros import underlay as _underlay
from ros2course.ros import underlay_build
from ros2course.ros.manifests import dependency_closure, find_packages
from ros2course.ros.requirements import KNOWN_REQUIREMENTS
from ros2course.ros.underlay_pins import JAZZY


@dataclasses.dataclass
class DoctorRow:
    """One line of ``ros2course doctor``: a component, whether it is fine, and details."""

    component: str
    ok: bool
    detail: str
    hint: str = ""


#: The ``doctor`` row of the optional nav2 component.
NAV2_ROW = "nav2 interfaces (optional)"


@dataclasses.dataclass(frozen=True)
class _OptionalRow:
    """How ``doctor`` shows one optional underlay component (``ros2course.ros.underlay.OPTIONAL``).

    Attributes:
        label: the row's name.
        users: who needs it (said when it is missing, which is no fault).
        build: the command that builds it, with how long it takes on 2 cores.
        provides: the packages a sourced system ROS must have instead (its ament index); () when a system ROS
            has no row for it.
        apt: the apt packages that give ``provides``.
    """

    label: str
    users: str
    build: str
    provides: tuple[str, ...] = ()
    apt: tuple[str, ...] = ()


_OPTIONAL_ROWS = {
    "sas": _OptionalRow("sas (optional)", "only the sas lesson's C++ path needs it",
                        "ros2course env --build --with sas (about 6 min)"),
    "nav2": _OptionalRow(NAV2_ROW, "only the Gazebo and nav2 chapters need them",
                         "ros2course env --build --with nav2 (7-14 min on 2 cores)",
                         ("nav2_msgs", "ros_gz_interfaces"), _underlay.NAV2_APT_PACKAGES),
}


def component_row(component: _underlay.Component, install: env_mod.RosInstall, failure: str = "") -> DoctorRow | None:
    """The ``doctor`` row of an optional underlay component (sas, nav2: GitHub issue 40).

    Args:
        component: one of :data:`ros2course.ros.underlay.OPTIONAL`.
        install: the ROS install in use (:func:`ros2course.ros.env.detect`).
        failure: the one-line message of a build that ``doctor --fix`` just tried and that failed.

    Returns:
        With a sourced system ROS: present when the packages the component stands for are in its ament
        index, else missing with the apt packages that give them; nothing is built there (None: no row,
        for a component a system ROS has no packages for). With the wheels: built (when, where) or not
        built, with the command that builds it, or what the build lacks. ``ok`` is False when it is not
        there, but the row is optional: ``doctor``'s exit status ignores it.
    """
    text = _OPTIONAL_ROWS[component.name]
    if install.kind == "system":
        if not text.provides:
            return None
        absent = [name for name in text.provides if not env_mod.ament_has(name)]
        if not absent:
            return DoctorRow(text.label, True, f"{' and '.join(text.provides)} from the system ROS ({install.prefix})")
        return DoctorRow(text.label, False, f"{' and '.join(absent)} not installed ({text.users})",
                         f"sudo apt-get install {' '.join(text.apt)}")
    on_top = _underlay.built(component)
    if on_top is not None:
        how = (f"restored {on_top.stamp.get('built', '?')} from the build cache" if on_top.stamp.get("restored_from")
               else f"built {on_top.stamp.get('built', '?')} in {on_top.stamp.get('seconds', '?')} s")
        what = f"{', '.join(text.provides)} ({len(component.pins)} pinned repos)" if text.provides \
            else f"{len(component.pins)} pinned repos"
        return DoctorRow(text.label, True, f"{what}, {how} into {on_top.prefix}")
    missing = _underlay.component_missing_prerequisites(component)
    why = failure or (f"not built; cannot build: {missing[0][0]}" if missing else "not built")
    return DoctorRow(text.label, False, f"{why} ({text.users})", missing[0][1] if missing else text.build)


def nav2_row(install: env_mod.RosInstall, failure: str = "") -> DoctorRow:
    """:func:`component_row` of the nav2 component (nav2_msgs and ros_gz_interfaces)."""
    return component_row(_underlay.NAV2_COMPONENT, install, failure)


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
    failure = ""
    if fix and _underlay.built(_underlay.JAZZY_COMPONENT) is None:
        try:
            underlay_build.build(sources)
        except CourseError as exc:
            failure = exc.message
        env_mod.activate_process()
    built = _underlay.current()
    wanted = _underlay.cache_key()
    if built is not None:
        rows.append(DoctorRow("ROS 2 underlay", built.stamp.get("key") == wanted,
                              f"{built.prefix}, " + (f"restored {built.stamp.get('built', '?')} from the build cache "
                              f"{built.stamp['restored_from']}" if built.stamp.get("restored_from") else
                              f"built {built.stamp.get('built', '?')} in {built.stamp.get('seconds', '?')} s from "
                              f"{built.stamp.get('sources', '?')}"),
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
    for component in _underlay.OPTIONAL:  # each on top of the underlay only
        component_failure = ""
        if fix and _underlay.built(_underlay.JAZZY_COMPONENT) is not None and _underlay.built(component) is None \
                and not _underlay.component_missing_prerequisites(component):
            try:
                underlay_build.build(sources, component=component)
            except CourseError as exc:
                component_failure = exc.message
            env_mod.activate_process()
        row = component_row(component, env_mod.detect(), component_failure)
        if row is not None:
            rows.append(row)
    return rows


def doctor(fix: bool = False, sources: Path | None = None) -> list[DoctorRow]:
    """Inspect (and with ``fix``, repair) the environment.

    Args:
        fix: repair the wheels' CMake files, install osrf-pycommon and build the
            underlay (``ros2course.ros.underlay``) when missing or out of date, and the
            optional components (sas, nav2) whose prerequisites are installed; idempotent.
        sources: folder of the pinned archives for the build (default
            :func:`ros2course.ros.underlay.default_sources`).

    Returns:
        one :class:`DoctorRow` per component, in a stable order. A sourced system
        ROS is reported as it is and never changed.
    """
    install = env_mod.activate_process()
    rows = [
        DoctorRow(
            "ROS 2",
            install.kind != "none",
            f"{install.kind} install, distro {install.distro}, prefix {install.prefix}"
            if install.kind != "none"
            else "no ROS 2 found",
            "" if install.kind != "none" else env_mod.INSTALL_HINTS["rclpy"],
        )
    ]
    if install.kind == "system" and install.distro != "jazzy":
        rows[0].ok = False
        rows[0].hint = f"ros2course targets Jazzy; the sourced distro is {install.distro}"
    if install.kind == "wheels" and install.prefix is not None:
        if fix:
            changed = env_mod.repair_cmake_files(install.prefix)
            rows.append(DoctorRow("wheel CMake files", True, f"repaired {len(changed)} file(s)"))
        else:
            broken = env_mod.cmake_files_needing_repair(install.prefix)
            rows.append(
                DoctorRow(
                    "wheel CMake files",
                    not broken,
                    f"{len(broken)} file(s) name the wheel build machine's Python or libraries" if broken else "clean",
                    "run 'ros2course doctor --fix'" if broken else "",
                )
            )
        rows += _underlay_rows(fix, sources)
    elif install.kind == "system":  # nothing is built: the rows say which apt packages give the components
        rows += [row for component in _underlay.OPTIONAL if (row := component_row(component, install)) is not None]
    for name in KNOWN_REQUIREMENTS:
        ok, detail = env_mod.probe_requirement(name)
        rows.append(DoctorRow(name, ok, detail, "" if ok else env_mod.INSTALL_HINTS.get(name, "")))
    rows.append(DoctorRow("ccache (optional)", True, compiler_cache.describe()))
    rows.append(physics_row())
    return rows


def physics_row() -> DoctorRow:
    """The row "MuJoCo physics (optional)": the engine of the simulated Gazebo world (ros2course.run.physics;
    only the gazebo-custom-nodes lesson needs it; issue 40). Read from the package's metadata, not imported."""
    import importlib.metadata  # noqa: PLC0415 - only doctor reads it

    try:
        version = importlib.metadata.version("mujoco")
    except importlib.metadata.PackageNotFoundError:
        version = None
    if version is None:
        return DoctorRow("MuJoCo physics (optional)", False, "mujoco not installed (only the Gazebo lesson needs it)",
                         "pip install 'ros2course[gazebo]'")
    return DoctorRow("MuJoCo physics (optional)", True, f"mujoco {version} (the Gazebo lesson's simulated world)")


#: The packages the optional nav2 component provides (course/ros/underlay_pins.py NAV2), and nav_msgs, which
#: nav2_msgs needs from the ``nav2`` extra's wheel: a learner's package that depends on one needs the component.
NAV2_PROVIDES = frozenset({name for pin in _underlay.NAV2_COMPONENT.pins for name in pin.packages or ()} | {"nav_msgs"})


def _component_of(dependency: str) -> _underlay.Component | None:
    """The optional component that provides ``dependency`` (a package name), or None."""
    if dependency.startswith("sas_"):
        return _underlay.SAS_COMPONENT
    if dependency in NAV2_PROVIDES:
        return _underlay.NAV2_COMPONENT
    return None


def ensure_components_for(workspace_root: Path, packages: list[str],
                          progress: Callable[[str], None] | None = None) -> list[str]:
    """Build the optional underlay components the learner's packages depend on, if missing.

    sas (SmartArmStack C++, tutorial ch. 29-31: a ``sas_*`` dependency) and nav2 (the
    author's nav2 and Gazebo chapters: :data:`NAV2_PROVIDES`, issue 40). When a package in
    ``workspace_root/src`` that ``packages`` need depends on such a package that neither
    the workspace nor the ament index has, and ROS 2 comes from the wheels, the component
    is built now (minutes; once). With a system ROS nothing is built: its apt packages
    are the learner's (``ros2course doctor`` names them).

    Args:
        workspace_root: the learner's workspace (holding ``src/``).
        packages: the lesson's packages.
        progress: called with one line per build step.

    Returns:
        the names of the components built (empty: nothing was needed).

    Raises:
        MissingRequirement: a component is needed but cannot be built here (one line, why, and the hint).
    """
    try:
        found = find_packages(workspace_root / "src")
    except NotGradable:
        return []  # the check reports the broken package.xml itself
    needed: dict[str, set[str]] = {}
    for name in dependency_closure([p for p in packages if p in found], found):
        pkg = found[name][1]
        for dep in (*pkg.build_depends, *pkg.buildtool_depends, *pkg.exec_depends, *pkg.build_export_depends):
            component = _component_of(dep.name)
            if component is not None and dep.name not in found and not env_mod.ament_has(dep.name):
                needed.setdefault(component.name, set()).add(dep.name)
    if not needed or env_mod.detect().kind != "wheels":
        return []
    built = []
    for component in _underlay.OPTIONAL:
        if component.name not in needed:
            continue
        what = f"{', '.join(sorted(needed[component.name]))} ({component.what})"
        missing = _underlay.missing_prerequisites() + _underlay.component_missing_prerequisites(component)
        if missing:
            raise MissingRequirement(f"your package depends on {what}, which is not installed and cannot be "
                                     f"built here: {missing[0][0]}", missing[0][1])
        try:
            underlay_build.build(component=component, progress=progress)
        except CourseError as exc:
            raise MissingRequirement(f"your package depends on {what}: {exc.message}",
                                     f"ros2course env --build --with {component.name}") from None
        built.append(component.name)
    env_mod.activate_process()
    return built
