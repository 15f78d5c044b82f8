"""Using the workspace's own generated interface types (msg/srv) inside the grader.

``source install/setup.bash`` would put the package's ``lib/`` on
``LD_LIBRARY_PATH`` and its Python folder on ``PYTHONPATH`` before Python
starts. The grader process is already running, so we do what the dynamic
linker and ``PYTHONPATH`` would have done:

* prepend ``<prefix>/lib`` to ``os.environ["LD_LIBRARY_PATH"]``: rosidl's
  typesupport dispatch finds ``lib<pkg>__rosidl_typesupport_*.so`` through
  ``rcpputils::find_library_path``, which reads that variable at call time;
* load the package's ``lib*.so`` with ``RTLD_GLOBAL`` so the Python extension's
  ``NEEDED`` entries resolve (the generated libraries carry no RUNPATH), after
  those of the interface packages its ``package.xml`` depends on that the process
  has not loaded yet, each from its own prefix (:func:`_preload_dependencies`:
  nav2_msgs needs geographic_msgs' and nav_msgs', from other prefixes);
* add the package's Python folder to ``sys.path`` and import.

One process holds one build of each interface package at a time. When a
later check grades another workspace (``dev validate`` and the tests grade
many throw-away workspaces in one process), the build imported first may be
deleted already, and its submodules not imported yet (``.srv`` after
``.msg``) could not be found any more: a package imported from another
install prefix is forgotten and imported again from this workspace's
(:func:`_forget_other_prefix`). Graders that must judge the learner's own
definition of an interface (the custom-interfaces lesson) inspect it in a
subprocess instead.
"""

from __future__ import annotations

import ctypes
import importlib
import os
import sys
import threading
from pathlib import Path
from typing import Any

from ros2course.errors import NotGradable
from ros2course.ros.index import package_prefix
from ros2course.ros.manifests import read_manifest


def _loaded_libraries() -> set[str]:
    """The file names of the shared libraries this process has mapped (``/proc/self/maps``); empty elsewhere."""
    try:
        maps = Path("/proc/self/maps").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return set()
    return {Path(line.split()[-1]).name for line in maps.splitlines() if ".so" in line and "/" in line}


def _preload_dependencies(overlay: dict[str, str], package: str, prefix: Path, seen: set[str],
                          loaded: set[str] | None = None) -> None:
    """Load, dependencies first, the generated libraries of the interface packages ``package`` depends on.

    An interface package's typesupport libraries need those of the interface packages its ``package.xml``
    names (``nav2_msgs``: ``geographic_msgs``, ``nav_msgs``...). When those lie in another prefix than the
    ones on the library path the process started with (an underlay component, a wheel installed later),
    the dynamic loader of a running process does not find them through ``LD_LIBRARY_PATH`` set now
    (dlopen reads it once, at start-up: ld.so(8)), so each is loaded from its own prefix first. A library
    the process has mapped already (rclpy's own messages, from wherever they were loaded) is left alone:
    loading another copy of one soname would give the process two type registries.

    Args:
        overlay: the environment whose ament index is searched (``GradingSession.overlay()`` or ``base_env``).
        package: the interface package (its ``share/<package>/package.xml`` under ``prefix`` is read).
        seen: the packages visited already in this lookup (cycles and shared dependencies, once each).
        loaded: the library file names the process had mapped when the lookup began (read once, at the top
            of the recursion: a dependency the lookup itself loads is another name, which ``seen`` covers).
    """
    try:
        manifest = read_manifest(prefix / "share" / package / "package.xml")
    except NotGradable:
        return  # no readable package.xml: its own libraries are loaded as before, and say so if they fail
    names = {d.name for key in ("build_depends", "exec_depends", "build_export_depends")
             for d in getattr(manifest, key)}
    loaded = _loaded_libraries() if loaded is None else loaded
    for name in sorted(names - seen):
        seen.add(name)
        where = package_prefix(name, overlay)
        if where is None or not any((where / "lib").glob(f"lib{name}__*.so")):
            continue  # not installed here, or not an interface package
        _preload_dependencies(overlay, name, where, seen, loaded)
        if not any(f"lib{name}__" in lib for lib in loaded):
            try:
                _preload(where / "lib", name)
            except NotGradable:
                pass  # the package's own libraries then fail to load, and that error names what is missing


def _preload(lib_dir: Path, package: str) -> None:
    pending = sorted(lib_dir.glob(f"lib{package}__*.so"))
    for _ in range(len(pending) + 1):  # load order unknown: retry until nothing changes
        left = []
        for path in pending:
            try:
                ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)
            except OSError:
                left.append(path)
        if not left or len(left) == len(pending):
            pending = left
            break
        pending = left
    if pending:
        raise NotGradable(f"cannot load {pending[0].name} of {package}", "rebuild the package: colcon build")


def _forget_other_prefix(package: str, prefix: Path) -> None:
    """Drop ``package`` and its submodules from ``sys.modules`` when imported from outside ``prefix``.

    Importing again then loads this workspace's copy of the generated
    libraries (rosidl's typesupport dispatch looks them up through
    ``LD_LIBRARY_PATH`` when a type is first used, so ``prefix/lib`` is put first).
    """
    cached = sys.modules.get(package)
    if cached is None:
        return
    here = prefix.resolve()
    folders = [Path(p) for p in getattr(cached, "__path__", [])]
    if any(f.is_dir() and f.resolve().is_relative_to(here) for f in folders):
        return
    for module in [m for m in sys.modules if m == package or m.startswith(package + ".")]:
        del sys.modules[module]


#: One lookup at a time: two parts graded at once (kit.parts.at_once) may ask for the same type together,
#: and a module another thread is still importing is already in ``sys.modules`` with none of its classes.
_LOOKUP = threading.Lock()


#: The interface packages of the optional components (issue 40): package -> (what they are, the component
#: ``ros2course env --build --with`` builds them in, what a sourced system ROS 2 Jazzy installs instead).
OPTIONAL_INTERFACES = {
    "nav2_msgs": ("the nav2 interfaces", "nav2", "ros-jazzy-nav2-msgs"),
    "ros_gz_interfaces": ("the Gazebo interfaces", "nav2", "ros-jazzy-ros-gz-interfaces"),
}


def component_type(env: dict[str, str], package: str, kind: str, name: str, *, needed_by: str) -> Any:
    """The class ``package.kind.name`` of an optional component of the ROS install (:data:`OPTIONAL_INTERFACES`),
    with one refusal, worded alike for every lesson and world that needs one, when it does not load.

    Args:
        env: the ROS install's environment (a grading session's ``base_env``), never a workspace's.
        needed_by: who needs it, the refusal's subject (``"this lesson"``, ``"the simulated Gazebo world"``).

    Raises:
        NotGradable: the package (or one it depends on) is not installed or does not load: "<needed_by> needs
            <what> (<package>), which do not load here: <why>", hinting ``ros2course env --build --with
            <component>`` and, for a system ROS, the apt package.
        KeyError: ``package`` is not an optional component's (a fault of the course).
    """
    what, component, apt = OPTIONAL_INTERFACES[package]
    try:
        return workspace_type(env, package, kind, name)
    except NotGradable as exc:
        raise NotGradable(f"{needed_by} needs {what} ({package}), which do not load here: {exc.message}",
                          f"ros2course env --build --with {component} (with a system ROS 2 Jazzy: sudo apt install "
                          f"{apt})") from exc


def workspace_type(overlay: dict[str, str], package: str, kind: str, name: str) -> Any:
    """The generated class ``package.kind.name`` (e.g. ``package_with_interfaces``, ``msg``, ``AmazingQuote``).

    Thread-safe (one lookup at a time in the process).

    Args:
        overlay: the sourced workspace environment (``GradingSession.overlay()``).
        kind: ``"msg"``, ``"srv"`` or ``"action"``.

    Raises:
        NotGradable: the package is not installed in the workspace, or its types do not load.
    """
    prefix = package_prefix(package, overlay)
    if prefix is None:
        # Checked before the module cache: a build imported from another workspace would hide it.
        raise NotGradable(f"interface package {package} is not installed in the workspace",
                          f"build it: colcon build --packages-up-to {package}")
    with _LOOKUP:
        return _import_type(prefix, overlay, package, kind, name)


def _import_type(prefix: Path, overlay: dict[str, str], package: str, kind: str, name: str) -> Any:
    """:func:`workspace_type` once the package's install prefix is known (called holding ``_LOOKUP``)."""
    module_name = f"{package}.{kind}"
    lib_dir = str(prefix / "lib")
    paths = [p for p in os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep) if p and p != lib_dir]
    os.environ["LD_LIBRARY_PATH"] = os.pathsep.join([lib_dir, *paths])
    _forget_other_prefix(package, prefix)
    module = sys.modules.get(module_name)
    if module is None:
        _preload_dependencies(overlay, package, prefix, {package})
        _preload(prefix / "lib", package)
        for entry in reversed(overlay.get("PYTHONPATH", "").split(os.pathsep)):
            if entry and entry.startswith(str(prefix)) and entry not in sys.path:
                sys.path.insert(0, entry)
        importlib.invalidate_caches()
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:
            raise NotGradable(f"cannot import {module_name}: {exc}", f"rebuild {package}: colcon build") from exc
    try:
        return getattr(module, name)
    except AttributeError as exc:
        raise NotGradable(f"{module_name} has no type {name}",
                          f"declare it in {kind}/{name}.{kind} and list it in rosidl_generate_interfaces") from exc
