"""Building a lesson's packages with colcon, and the workspace's overlay environment.

* Packages are found with ``catkin_pkg`` (the library colcon-ros itself uses to
  read ``package.xml``), built with ``colcon build --packages-up-to``.
* colcon re-runs every package's build even when nothing changed (a second or
  more per ament_python package). So that a warm ``check`` costs milliseconds,
  we keep a fingerprint of each built package's source tree (paths, sizes,
  mtimes) in ``build/.ros2course-fingerprints.json`` and skip colcon when the
  packages and their in-workspace dependencies are unchanged and installed.
* The environment learner executables run in is what ``source
  install/setup.bash`` produces (we source it in bash and read ``env -0``),
  so colcon's own setup files decide it, exactly as for a learner's terminal.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

from catkin_pkg.package import InvalidPackage
from catkin_pkg.packages import find_packages as catkin_find

from course.errors import NotGradable
from course.lesson.workspace import atomic_write_text
from course.run import sandbox

FINGERPRINTS = ".ros2course-fingerprints.json"
#: colcon arguments every build uses; ``BUILD_TESTING=OFF`` because ament_lint_auto
#: is not available from the wheels (shared/ROS_ENV.md).
COLCON_ARGS = ["--cmake-args", "-DBUILD_TESTING=OFF"]
BUILD_TIMEOUT = 900.0


@dataclasses.dataclass
class BuildResult:
    """Outcome of building a lesson's packages.

    Attributes:
        ok: colcon succeeded (or nothing needed building).
        packages: the packages asked for.
        seconds: wall time spent, seconds.
        cached: True when the fingerprints matched and colcon was not run.
        log_path: the captured colcon output (None if colcon was not run).
        excerpt: the relevant lines of a failed build, for the learner.
    """

    ok: bool
    packages: list[str]
    seconds: float
    cached: bool
    log_path: Path | None = None
    excerpt: str = ""


def find_packages(src: Path) -> dict[str, tuple[Path, object]]:
    """Every ROS package under ``src``: name -> (folder, catkin_pkg Package).

    Raises:
        NotGradable: a ``package.xml`` that catkin_pkg cannot parse (its message included).
    """
    if not src.is_dir():
        return {}
    try:
        found = catkin_find(str(src))
    except InvalidPackage as exc:
        detail = " ".join(line.strip() for line in str(exc).splitlines() if line.strip())
        raise NotGradable(f"a package.xml under {src} is invalid: {detail[:400]}",
                          "fix package.xml (format 3; name, version, description, maintainer with a valid email, license)") from exc
    return {pkg.name: (src / rel, pkg) for rel, pkg in found.items()}


def dependency_closure(packages: list[str], found: dict[str, tuple[Path, object]]) -> list[str]:
    """``packages`` plus every workspace package they depend on, recursively (sorted)."""
    todo = list(packages)
    seen: set[str] = set()
    while todo:
        name = todo.pop()
        if name in seen or name not in found:
            continue
        seen.add(name)
        pkg = found[name][1]
        for dep in (*pkg.build_depends, *pkg.buildtool_depends, *pkg.exec_depends, *pkg.build_export_depends):
            if dep.name in found:
                todo.append(dep.name)
    return sorted(seen)


def fingerprint(folder: Path) -> str:
    """Hash of every file's relative path, size and mtime under ``folder`` (caches skipped)."""
    digest = hashlib.sha256()
    for root, dirs, files in os.walk(folder):
        dirs[:] = sorted(d for d in dirs if d not in ("__pycache__", ".git") and not d.endswith(".egg-info"))
        for name in sorted(files):
            path = Path(root, name)
            try:
                stat = path.stat()
            except OSError:
                continue
            digest.update(f"{path.relative_to(folder)}\0{stat.st_size}\0{stat.st_mtime_ns}\n".encode())
    digest.update(f"{sys.executable}\0{COLCON_ARGS}".encode())
    return digest.hexdigest()


def _read_fingerprints(path: Path) -> dict[str, str]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return {str(k): str(v) for k, v in data.items()} if isinstance(data, dict) else {}
    except (OSError, ValueError):
        return {}


_RELEVANT = re.compile(r"error|Error|ERROR|Traceback|failed|Failed|CMake Error|SyntaxError|not found|No such", re.M)


def build_log_excerpt(text: str, limit: int = 25) -> str:
    """The lines of a colcon log that explain a failure (errors plus a little context)."""
    lines = text.splitlines()
    keep: list[int] = []
    for index, line in enumerate(lines):
        if _RELEVANT.search(line):
            keep.extend(range(max(0, index - 1), min(len(lines), index + 3)))
    picked = sorted(set(keep)) or list(range(max(0, len(lines) - limit), len(lines)))
    return "\n".join(lines[i] for i in picked[-limit:])


class BuildProgress(threading.Thread):
    """Follows colcon's output in the build log and reports each package it starts and finishes.

    colcon's console_start_end event handler prints ``Starting >>> pkg`` and
    ``Finished <<< pkg [1.2s]`` (``Failed <<<``, ``Aborted <<<``) lines; each
    becomes a call ``report("building pkg (1 of 3 done)")`` for a progress display.

    Args:
        log_path: the build log being written.
        report: called from this thread with one short line.
        total: packages to build (for the "n of total" count; None: unknown).

    It reads from the log's size at construction, so an earlier pass in the same log is not reported again.
    """

    PATTERN = re.compile(r"^(Starting >>>|Finished <<<|Failed\s+<<<|Aborted\s+<<<)\s+(\S+)")

    def __init__(self, log_path: Path, report: Callable[[str], None], total: int | None) -> None:
        super().__init__(daemon=True, name="ros2course-build-progress")
        self.log_path, self.report, self.total = log_path, report, total
        self._offset = log_path.stat().st_size if log_path.is_file() else 0
        self._stop_event = threading.Event()

    def run(self) -> None:
        done, building = 0, []
        with contextlib.suppress(OSError), open(self.log_path, encoding="utf-8", errors="replace") as log:
            log.seek(self._offset)
            while True:
                line = log.readline()
                if not line:
                    if self._stop_event.wait(0.2):
                        return
                    continue
                match = self.PATTERN.match(line)
                if match is None:
                    continue
                verb, package = match.groups()
                if verb.startswith("Starting"):
                    building.append(package)
                else:
                    done += 1
                    building = [p for p in building if p != package]
                count = f"{done} of {self.total} done" if self.total else f"{done} done"
                self.report(f"building {', '.join(building) or '...'} ({count})")

    def stop(self) -> None:
        """Stop following (the thread ends within 0.2 s)."""
        self._stop_event.set()
        self.join(timeout=1.0)


def build_packages(workspace_root: Path, packages: list[str], env: dict[str, str], log_path: Path,
                   timeout: float = BUILD_TIMEOUT, progress: Callable[[str], None] | None = None) -> BuildResult:
    """Build ``packages`` (and their workspace dependencies) with colcon, unless unchanged.

    Args:
        workspace_root: the colcon workspace (holding ``src/``).
        packages: ROS package names the lesson needs.
        env: environment for colcon (ROS install activated).
        log_path: file receiving colcon's output.
        timeout: seconds before the build is stopped and reported as failed.
        progress: called with a short line as colcon starts and finishes each package
            (:class:`BuildProgress`); None for no progress display (``--json``, batch grading).

    Raises:
        NotGradable: a required package is not in ``src/`` (names the ones that are).
    """
    begin = time.monotonic()
    found = find_packages(workspace_root / "src")
    missing = [name for name in packages if name not in found]
    if missing:
        have = ", ".join(sorted(found)) or "none"
        raise NotGradable(f"package {missing[0]} not found in {workspace_root / 'src'} (packages there: {have})",
                          "create it under src/ (check the <name> in its package.xml)")
    closure = dependency_closure(packages, found)
    prints = {name: fingerprint(found[name][0]) for name in closure}
    store = workspace_root / "build" / FINGERPRINTS
    known = _read_fingerprints(store)
    installed = all((workspace_root / "install" / name).is_dir() for name in closure)
    have_setup = (workspace_root / "install" / "setup.bash").is_file()
    if installed and have_setup and all(known.get(name) == value for name, value in prints.items()):
        return BuildResult(True, packages, time.monotonic() - begin, cached=True)
    log_path.parent.mkdir(parents=True, exist_ok=True)
    command = [*colcon_command(env), "build", "--packages-up-to", *packages, *COLCON_ARGS]
    with open(log_path, "wb") as log:
        log.write(f"$ {' '.join(command)}\n".encode())
        log.flush()
        follower = BuildProgress(log_path, progress, len(closure)) if progress is not None else None
        if follower is not None:
            follower.start()
        try:
            # colcon runs the submission's setup.py and CMake code: as the submission (course.run.sandbox)
            proc = sandbox.run(command, cwd=workspace_root, env=env, stdout=log, stderr=subprocess.STDOUT,
                               stdin=subprocess.DEVNULL, timeout=timeout, start_new_session=True, check=False)
            ok = proc.returncode == 0
        except subprocess.TimeoutExpired:
            ok = False
            log.write(f"\nros2course: build stopped after {timeout:.0f} s (error: timeout)\n".encode())
        finally:
            if follower is not None:
                follower.stop()
    text = log_path.read_text(encoding="utf-8", errors="replace")
    if ok:
        known.update(prints)
        atomic_write_text(store, json.dumps(known, indent=1, sort_keys=True))
        return BuildResult(True, packages, time.monotonic() - begin, cached=False, log_path=log_path)
    for name in closure:  # a failed build must not look cached next time
        known.pop(name, None)
    if store.parent.is_dir():
        atomic_write_text(store, json.dumps(known, indent=1, sort_keys=True))
    return BuildResult(False, packages, time.monotonic() - begin, cached=False, log_path=log_path,
                       excerpt=build_log_excerpt(text))


def colcon_command(env: dict[str, str]) -> list[str]:
    """How to run colcon: the interpreter's own colcon if present, else the one on PATH."""
    local = Path(sys.executable).parent / "colcon"
    if local.is_file():
        return [str(local)]
    return ["colcon"]


_overlay_cache: dict[tuple, dict[str, str]] = {}


def overlay_env(workspace_root: Path, base_env: dict[str, str]) -> dict[str, str]:
    """The environment after ``source install/setup.bash`` on top of ``base_env``.

    Raises:
        NotGradable: the workspace was never built (no ``install/setup.bash``),
            or sourcing it fails.
    """
    setup = workspace_root / "install" / "setup.bash"
    if not setup.is_file():
        raise NotGradable(f"{workspace_root} is not built (no install/setup.bash)",
                          f"run 'colcon build' in {workspace_root}")
    layout = workspace_root / "install"
    key = (str(workspace_root), tuple(sorted(base_env.items())),
           tuple(sorted((p.name, p.stat().st_mtime_ns) for p in layout.iterdir())))
    cached = _overlay_cache.get(key)
    if cached is not None:
        return dict(cached)
    # the workspace's setup.bash is the submission's code too (course.run.sandbox)
    proc = sandbox.run(["bash", "-c", 'source "$1" >/dev/null 2>&1 && env -0', "bash", str(setup)],
                       capture_output=True, env=base_env, cwd=workspace_root, timeout=60, check=False)
    if proc.returncode != 0:
        raise NotGradable(f"sourcing {setup} failed (exit {proc.returncode})",
                          "rebuild the workspace: rm -rf build install log && colcon build")
    env = {}
    for item in proc.stdout.split(b"\0"):
        if b"=" in item:
            k, _, v = item.partition(b"=")
            env[k.decode()] = v.decode(errors="replace")
    for noise in ("SHLVL", "_", "PWD", "OLDPWD"):
        env.pop(noise, None)
    _overlay_cache.clear()
    _overlay_cache[key] = env
    return dict(env)
