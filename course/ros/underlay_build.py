"""Building the underlay (:mod:`ros2course.ros.underlay`): sources, colcon passes, the atomic switch.

Split from :mod:`ros2course.ros.underlay` (where the underlay is, whether it is
current, what a build needs) because a build needs the ROS install's
activation (:mod:`ros2course.ros.env`), which itself reads where the underlay is:
status below activation, building above it, no import cycle (issue 23).
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime
import fcntl
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from ros2course.ros import underlay_cache
from ros2course.ros.colcon_log import BuildProgress
from ros2course.ros.compiler_cache import with_compiler_cache
from ros2course.ros.env import activate, detect, repair_cmake_files
from ros2course.ros.underlay import (
    BUILD_TIMEOUT,
    EIGEN_INCLUDE,
    JAZZY_COMPONENT,
    REPAIRS_VERSION,
    SAS_COMPONENT,
    SOURCES_VAR,
    STAMP,
    Component,
    Pin,
    Underlay,
    UnderlayBuildFailed,
    built,
    cache_key,
    component_missing_prerequisites,
    component_root,
    current,
    default_sources,
    libpython_link_flags,
    missing_archives,
    missing_prerequisites,
    prepare_sources,
)


@contextlib.contextmanager
def _locked(base: Path) -> Iterator[None]:
    """Hold ``<base>/.lock`` so two builds never run at once (the second waits)."""
    base.mkdir(parents=True, exist_ok=True)
    with open(base / ".lock", "w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


_FAILED = re.compile(r"^Failed\s+<<<\s+(\S+)", re.MULTILINE)


def _run_colcon(args: list[str], env: dict[str, str], cwd: Path, log, timeout: float,
                packages: Callable[[str], None] | None = None) -> None:
    """Run one colcon pass in its own process group; on any interruption kill the group."""
    colcon = Path(sys.executable).parent / "colcon"
    command = [str(colcon) if colcon.is_file() else "colcon", *args]
    log.write(f"\n$ {' '.join(command)}\n".encode())
    log.flush()
    follower = BuildProgress(Path(log.name), packages, None) if packages is not None else None
    if follower is not None:
        follower.start()
    proc = subprocess.Popen(command, cwd=cwd, env=env, stdout=log, stderr=subprocess.STDOUT,
                            stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        code = proc.wait(timeout=timeout)
    except BaseException:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise
    finally:
        if follower is not None:
            follower.stop()
    if code != 0:
        raise subprocess.CalledProcessError(code, command)


def _build_env(prefix: Path, component: Component) -> dict[str, str]:
    env = dict(os.environ)
    for var in ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "COLCON_PREFIX_PATH", "PYTHONPATH"):
        env.pop(var, None)  # only the wheels (and what this component builds on), nothing sourced by chance
    env = activate(env, underlay=component is not JAZZY_COMPONENT, sas=False, nav2=False)
    for var in ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH"):
        env[var] = os.pathsep.join([str(prefix), *[p for p in env.get(var, "").split(os.pathsep) if p]])
    env.pop("COLCON_PREFIX_PATH", None)
    # ccache, keyed on paths relative to what holds both the build and the wheels' headers (a fresh
    # clone's venv hits the entries an earlier clone's build left): ros2course.ros.compiler_cache
    env = with_compiler_cache(env, Path(os.path.commonpath([str(prefix.resolve()), str(Path(sys.prefix).resolve())])))
    if component is SAS_COMPONENT:  # shared/ROS_ENV.md, "Building SmartArmStack (sas) from source"
        import pybind11  # noqa: PLC0415 - pybind11 only for the sas build

        env["pybind11_DIR"] = pybind11.get_cmake_dir()
        env["CPATH"] = os.pathsep.join([str(prefix / "include"), str(EIGEN_INCLUDE), env.get("CPATH", "")]).rstrip(":")
        env["LIBRARY_PATH"] = os.pathsep.join([str(prefix / "lib"), env.get("LIBRARY_PATH", "")]).rstrip(":")
    return env


def build(sources: Path | None = None, force: bool = False, progress: Callable[[str], None] | None = None,
          pins: tuple[Pin, ...] | None = None, base: Path | None = None,
          component: Component = JAZZY_COMPONENT,
          packages: Callable[[str], None] | None = None) -> tuple[Underlay, bool]:
    """Build ``component`` unless its current build is these pins; switch to the new build only on success.

    Args:
        sources: folder of pinned archives; None: :func:`default_sources` (which may
            be None: download from GitHub).
        force: rebuild even when up to date.
        progress: called with one short line per step (e.g. a console's print).
        packages: called as colcon starts and finishes each package, with a short line
            (:class:`~ros2course.ros.colcon_log.BuildProgress`; e.g. a status display's update).
        pins: what to build (default: the component's pins, course/ros/underlay_pins.py).
        base: the component's folder (default :func:`component_root`).
        component: :data:`JAZZY_COMPONENT`, or an optional one built on top of it
            (:data:`SAS_COMPONENT`, :data:`NAV2_COMPONENT`: needs the first one built).

    Returns:
        ``(underlay, built)``: ``built`` is False when the cache was used.

    Raises:
        UnderlayBuildFailed: a missing prerequisite (for nav2: the nav_msgs wheel), a
            sources folder without the pinned archives (checked before anything is
            unpacked), a damaged source or patch, or a failed colcon pass; the
            one-line message says which package and where the log is. The earlier
            build (if any) stays current.
    """
    pins = component.pins if pins is None else pins
    base = base or component_root(component)
    say = progress or (lambda line: None)

    below = ""
    under = None
    if component is not JAZZY_COMPONENT:
        under = built(JAZZY_COMPONENT)
        if under is None:
            raise UnderlayBuildFailed(f"cannot build {component.what}: the ROS 2 underlay is not built "
                                      "(ros2course env --build)")
        below = under.stamp["key"]
    key = cache_key(pins, below)
    # the machine-wide cache (ros2course.ros.underlay_cache): None where what it is built on was not keyed
    portable = (underlay_cache.portable_key(component.name, pins, under.stamp.get("portable", "") if under else "")
                if under is None or under.stamp.get("portable") else None)
    with _locked(base):
        install = detect()
        if install.kind == "wheels" and install.prefix is not None:
            # shared/ROS_ENV.md; idempotent, also when cached. It also repairs wheels installed after the
            # underlay was built: the nav2 extra's nav_msgs names the build farm's Python as the others did
            repair_cmake_files(install.prefix)
        found = current(base)
        if found is not None and found.stamp.get("key") == key and not force:
            return found, False
        missing = missing_prerequisites() + component_missing_prerequisites(component)
        if missing:
            what, hint = missing[0]
            raise UnderlayBuildFailed(f"cannot build {component.what}: {what} ({hint})")
        mirror = sources if sources is not None else default_sources()
        if mirror is not None and not mirror.is_dir():
            raise UnderlayBuildFailed(f"cannot build {component.what}: the sources folder {mirror} does not "
                                      f"exist (give a folder of the pinned archives: {SOURCES_VAR} or --sources)")
        logs = base / "logs"
        logs.mkdir(parents=True, exist_ok=True)
        log_path = logs / f"build-{datetime.datetime.now().strftime('%Y%m%d-%H%M%S')}.log"
        builds = base / "builds"
        builds.mkdir(exist_ok=True)
        prefix = builds / key
        work = base / "work"
        keep = found.prefix.name if found is not None else None
        for stale in [*builds.iterdir(), work]:  # leftovers of interrupted or failed builds: never trusted
            if stale.name != keep:
                shutil.rmtree(stale, ignore_errors=True)
        begin = time.monotonic()
        paths = {"prefix": str(prefix), "below": str(under.prefix) if under else "", "venv": sys.prefix}
        entry = underlay_cache.lookup(component.name, portable) if portable and not force and underlay_cache.enabled() \
            else None
        if entry is not None:
            try:
                rewritten = underlay_cache.restore(entry, prefix, paths)
            except (OSError, ValueError, KeyError) as exc:  # a damaged entry: build from source instead
                shutil.rmtree(prefix, ignore_errors=True)
                say(f"the cached build {entry} could not be restored ({exc}): building from source")
            else:
                say(f"restored {component.what} from the build cache {entry} ({rewritten} files relocated)")
                _write_stamp(prefix, {"key": key, "portable": portable, "component": component.name, "pins": pins,
                                      "below": below, "seconds": round(time.monotonic() - begin, 1),
                                      "restored_from": str(entry)})
                return _switch(base, key, keep), True
        absent = missing_archives(pins, mirror) if mirror is not None else []
        if absent:
            more = f" (and {len(absent) - 1} more)" if len(absent) > 1 else ""
            raise UnderlayBuildFailed(f"cannot build {component.what}: {absent[0]}{more} is not in the sources folder "
                                      f"{mirror}", "put the pinned archives there (shared/ros-src/SOURCES.md), or "
                                      f"unset {SOURCES_VAR} and leave out --sources to download them from GitHub")
        step = "preparing the sources"
        with open(log_path, "wb") as log:
            try:
                say(f"unpacking {len(pins)} pinned source archives from {mirror or 'GitHub'}")
                src = prepare_sources(work, mirror, log, pins)
                env = _build_env(prefix, component)
                linker = libpython_link_flags()
                cmake_args = ["--cmake-args", "-DBUILD_TESTING=OFF", "-DCMAKE_BUILD_TYPE=Release",
                              f"-DPython3_EXECUTABLE={sys.executable}", f"-DPYTHON_EXECUTABLE={sys.executable}"]
                if component is not SAS_COMPONENT:  # jazzy, and nav2's interface libraries, as rclcpp's
                    cmake_args.append(f"-DCMAKE_SHARED_LINKER_FLAGS={linker}")
                else:  # sas links a bare -ldqrobotics: find it in, and load it from, this prefix (ROS_ENV.md)
                    linker += f" -L{prefix / 'lib'} -Wl,-rpath,{prefix / 'lib'}"
                    cmake_args += [f"-DCMAKE_{kind}_LINKER_FLAGS={linker}" for kind in ("SHARED", "MODULE", "EXE")]
                passes = sorted({pin.colcon_pass for pin in pins if pin.into is None})
                for number in passes:
                    tops = [str(src / pin.top) for pin in pins if pin.into is None and pin.colcon_pass == number]
                    names = ", ".join(pin.repo for pin in pins if pin.into is None and pin.colcon_pass == number)
                    step = f"building {names}"
                    say(f"{step} (colcon pass {number + 1 - passes[0]} of {len(passes)}); log: {log_path}")
                    _run_colcon(["--log-base", str(work / "log"), "build", "--merge-install", "--base-paths", *tops,
                                 "--build-base", str(work / "build"), "--install-base", str(prefix),
                                 "--event-handlers", "console_direct-", "summary+", "console_start_end+",
                                 *cmake_args], env, work, log, BUILD_TIMEOUT, packages)
                _write_stamp(prefix, {"key": key, "portable": portable, "component": component.name, "pins": pins,
                                      "below": below, "seconds": round(time.monotonic() - begin, 1),
                                      "sources": str(mirror) if mirror else "github", "log": str(log_path)})
            except subprocess.CalledProcessError:
                failed = _FAILED.findall(log_path.read_text(encoding="utf-8", errors="replace"))
                where = f" (package {failed[0]})" if failed else ""
                shutil.rmtree(prefix, ignore_errors=True)
                raise UnderlayBuildFailed(f"building {component.what} failed: {step}{where}; "
                                          f"log: {log_path}") from None
            except subprocess.TimeoutExpired:
                shutil.rmtree(prefix, ignore_errors=True)
                raise UnderlayBuildFailed(f"building {component.what} failed: {step} took more than "
                                          f"{BUILD_TIMEOUT:.0f} s; log: {log_path}") from None
            except UnderlayBuildFailed as exc:
                shutil.rmtree(prefix, ignore_errors=True)
                hint = f" ({exc.hint})" if exc.hint else ""
                raise UnderlayBuildFailed(f"building {component.what} failed: {exc.message}{hint}; "
                                          f"log: {log_path}") from None
            except BaseException:
                shutil.rmtree(prefix, ignore_errors=True)
                raise
        shutil.rmtree(work, ignore_errors=True)
        if portable:
            underlay_cache.save(prefix, component.name, portable, paths)
        return _switch(base, key, keep), True


def _write_stamp(prefix: Path, fields: dict) -> None:
    """Write the build's stamp (``ros2course-underlay.json``): only a prefix with one is ever trusted."""
    stamp = {**fields, "pins": [dataclasses.asdict(pin) for pin in fields["pins"]], "repairs": REPAIRS_VERSION,
             "python": sys.executable,
             "built": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
    (prefix / STAMP).write_text(json.dumps(stamp, indent=1), encoding="utf-8")


def _switch(base: Path, key: str, keep: str | None) -> Underlay:
    """Point ``<base>/current`` at ``builds/<key>`` with one atomic rename; remove the build it replaced."""
    link = base / "current"
    tmp_link = base / f".current-{os.getpid()}"
    with contextlib.suppress(FileNotFoundError):
        tmp_link.unlink()
    tmp_link.symlink_to(Path("builds") / key)
    os.replace(tmp_link, link)
    if keep is not None and keep != key:
        shutil.rmtree(base / "builds" / keep, ignore_errors=True)
    made = current(base)
    assert made is not None
    return made
