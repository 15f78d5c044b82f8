"""Kit steps that pip-install a learner's Python project into a fresh venv, offline (tutorial ch. 2.6).

* ``python -m venv --without-pip``: no ensurepip (Ubuntu 24.04 ships it in a
  separate ``python3.12-venv`` package, and it costs seconds). The venv stays
  bare, like a Python 3.12 venv, which has no setuptools.
* pip, the build backend (setuptools, plus ``wheel`` when setuptools is older
  than 70.1, which is when setuptools learned to build wheels itself) come from
  one folder of links to the grader's own installed copies (:func:`tools_folder`,
  or unpacked from local wheel files when the grader's interpreter lacks them),
  put on ``PYTHONPATH`` for pip's runs only: ``<venv>/bin/python -m pip`` then
  installs into the venv with one interpreter start (``pip --python`` would
  start the outer interpreter first and then re-run pip under the venv's).
* ``--no-index --no-build-isolation --no-deps``: nothing is downloaded.
"""

from __future__ import annotations

import importlib.metadata
import re
import shutil
import sys
import zipfile
from pathlib import Path

from ros2course.kit import Session
from ros2course.kit.programs import ProgramRun, run_program
from ros2course.kit.python_programs import python_env

#: setuptools builds wheels without the ``wheel`` package from this version on.
SETUPTOOLS_WITH_BDIST_WHEEL = (70, 1)
#: Folders searched last for ``<name>-*.whl`` when the grader's interpreter lacks a tool (Debian/Ubuntu's
#: python3-setuptools-whl, python3-wheel-whl and python3-pip-whl install here). Searched before them:
#: ``ROS2COURSE_WHEELHOUSE`` (``:``-separated), pip's local find-links. (ros2course itself depends on
#: ``wheel``, so the grader's own interpreter normally provides everything.)
WHEELHOUSES = ("/usr/share/python-wheels",)
#: Deadline of each pip run, in seconds (an offline install of a small package takes 1-3 s).
PIP_TIMEOUT = 120.0


class BuildBackendMissing(RuntimeError):
    """The grader's machine has no offline pip / setuptools (/ wheel) to build the learner's package with."""


def version_tuple(text: str) -> tuple[int, ...]:
    """``"70.1.0"`` -> ``(70, 1, 0)`` (leading numeric parts only)."""
    parts = []
    for piece in text.split("."):
        match = re.match(r"\d+", piece)
        if not match:
            break
        parts.append(int(match.group()))
    return tuple(parts)


def _link_installed(name: str, dest: Path) -> str | None:
    """Link the installed distribution ``name`` (top-level modules and dist-info) into ``dest``; its version or None."""
    try:
        dist = importlib.metadata.distribution(name)
    except importlib.metadata.PackageNotFoundError:
        return None
    tops = {Path(str(f)).parts[0] for f in (dist.files or []) if not str(f).startswith("..")}
    base = Path(str(dist.locate_file("")))
    linked = False
    for top in sorted(tops):
        source = base / top
        if top.endswith(".pth") or not source.exists() or (dest / top).exists():
            continue
        (dest / top).symlink_to(source)
        linked = True
    return dist.version if linked else None


def _wheel_file(name: str, s: Session) -> Path | None:
    """The newest local ``<name>-*.whl``: in ``ROS2COURSE_WHEELHOUSE``, pip's find-links, :data:`WHEELHOUSES`."""
    folders = [p for p in s.base_env.get("ROS2COURSE_WHEELHOUSE", "").split(":") if p]
    folders += [p for p in re.split(r"[\s:]+", s.base_env.get("PIP_FIND_LINKS", "")) if p.startswith("/")]
    folders += list(WHEELHOUSES)
    found = [w for folder in folders if Path(folder).is_dir() for w in Path(folder).glob(f"{name}-*.whl")]
    return max(found, key=lambda w: version_tuple(w.name.split("-")[1]), default=None)


def tools_folder(s: Session) -> Path:
    """A folder (under ``s.log_dir``) holding pip and setuptools, and ``wheel`` if setuptools needs it, for
    ``PYTHONPATH``.

    Raises:
        BuildBackendMissing: neither the grader's interpreter nor a local wheel file provides them
            (a fault of the course's installation, reported as a grader error).
    """
    dest = s.log_dir / "pip_tools"
    shutil.rmtree(dest, ignore_errors=True)
    dest.mkdir(parents=True)
    versions: dict[str, str] = {}
    for name in ("pip", "setuptools", "wheel"):
        if name == "wheel" and version_tuple(versions["setuptools"]) >= SETUPTOOLS_WITH_BDIST_WHEEL:
            break
        version = _link_installed(name, dest)
        if version is None and (wheel := _wheel_file(name, s)) is not None:
            with zipfile.ZipFile(wheel) as archive:
                archive.extractall(dest)
            version = wheel.name.split("-")[1]
        if version is None:
            raise BuildBackendMissing(
                f"the grader needs '{name}' to build packages offline and found none (setuptools "
                f"{versions.get('setuptools', 'missing')}; wheel is needed below setuptools 70.1); install "
                f"'setuptools>=70.1' or 'wheel<0.46' into the course's venv, or put {name}-*.whl in a folder named "
                "by ROS2COURSE_WHEELHOUSE")
        versions[name] = version
    return dest


def fresh_venv(s: Session, name: str = "fresh_venv") -> Path:
    """A new, empty venv ``<log_dir>/<name>/venv`` (``--without-pip``) made from the grader's interpreter; its python.

    Made by the submission (it installs into it) in a :meth:`Session.submission_folder`.

    Raises:
        RuntimeError: ``python -m venv`` failed (a fault of the course's machine, not the learner's).
    """
    folder = s.submission_folder(name)
    venv = folder / "venv"
    made = run_program(s, [sys.executable, "-m", "venv", "--without-pip", str(venv)], "make_venv", timeout=60.0,
                       env=python_env(s), cwd=folder)
    python = venv / "bin" / "python"
    if made.returncode != 0 or not python.exists():
        raise RuntimeError(f"'python -m venv' failed: {made.describe()}: {last_error(made.stderr)}")
    return python


def venv_copy(s: Session, python: Path, name: str) -> Path:
    """A copy of ``python``'s venv in ``<log_dir>/<name>/venv`` (a submission folder); the copy's python.

    For judging ``pip uninstall`` while the original venv's command still
    runs (the two take about the same time, so the check takes the longer,
    not the sum): a venv is found from its interpreter's path (``pyvenv.cfg``
    beside ``bin/``), and pip's ``RECORD`` files name what it installed
    relative to ``site-packages``, so an uninstall in the copy removes the
    copy's files only. Symlinks (``bin/python``, ``lib64``) are copied as links.
    """
    venv = python.parent.parent
    folder = s.submission_folder(name, lambda dest: shutil.copytree(venv, dest / "venv", symlinks=True))
    return folder / "venv" / "bin" / python.name


def pip(s: Session, python: Path, tools: Path, args: list[str], label: str, *, cwd: Path) -> ProgramRun:
    """Run ``<python> -m pip <args>`` offline with ``tools`` (:func:`tools_folder`) on PYTHONPATH; never asks or
    downloads."""
    env = python_env(s, PYTHONPATH=str(tools), PIP_NO_INPUT="1", PIP_NO_CACHE_DIR="1",
                     PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INDEX="1")
    return run_program(s, [str(python), "-m", "pip", *args], label, timeout=PIP_TIMEOUT, env=env, cwd=cwd)


def last_error(text: str) -> str:
    """The most telling line of pip's (or Python's) output: the first ``error:``-like line, else the last line."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    for line in lines:
        if re.match(r"(ERROR|error|\w*Error)\b", line):
            return line[:300]
    return lines[-1][:300] if lines else "(no output)"
