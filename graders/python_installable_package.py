"""Grader for ``python-installable-package`` (seed ch. 2.6): pip installs the minimalist package.

The learner's ``python/minimalist_package`` is copied to ``s.log_dir`` (a pip
build writes ``build/`` and ``*.egg-info`` next to the sources, which must not
land in the learner's workspace) and installed with pip into a **fresh venv**
made under ``s.log_dir``, offline:

* ``python -m venv --without-pip``: no ensurepip (Ubuntu 24.04 ships it in a
  separate ``python3.12-venv`` package, and it costs seconds); the grader's own
  pip installs into that venv with ``pip --python <venv>/bin/python``;
* ``--no-index --no-build-isolation --no-deps``: nothing is downloaded. The
  build backend (setuptools, plus ``wheel`` when setuptools is older than 70.1,
  which is when setuptools learned to build wheels itself) is put on
  ``PYTHONPATH`` for the pip run only, from a folder of links to the grader's
  own setuptools/wheel (:func:`build_backend`), or unpacked from local wheel
  files when the grader's interpreter lacks them. The venv itself stays bare,
  like a Python 3.12 venv, which has no setuptools.

Then, from ``/``: ``import minimalist_package`` must work with the venv's
interpreter, the console script ``minimalist_script`` must print Howdy!, and
``pip uninstall`` must remove both.
"""

from __future__ import annotations

import importlib.metadata
import re
import shutil
import sys
import zipfile
from pathlib import Path

import tomllib

from graders.kit import Check, GradingSession, Unmet
from graders.kit.programs import interrupt_after, run_program

#: Seconds the console script is watched (Howdy! every 0.5 s: at least 2 expected).
WINDOW = 1.6

FOLDER = Path("python") / "minimalist_package"
PACKAGE = "minimalist_package"
SCRIPT = "minimalist_script"
#: Deadline of each pip run, in seconds (an offline install of this package takes 1-3 s).
PIP_TIMEOUT = 120.0
#: setuptools builds wheels without the ``wheel`` package from this version on.
SETUPTOOLS_WITH_BDIST_WHEEL = (70, 1)
#: Folders searched last for ``setuptools-*.whl`` / ``wheel-*.whl`` when the grader's interpreter lacks them
#: (Debian/Ubuntu's python3-setuptools-whl and python3-wheel-whl install here). Searched before them:
#: ``ROS2COURSE_WHEELHOUSE`` (``:``-separated), pip's local find-links. (ros2course itself depends on
#: ``wheel``, so the grader's own interpreter normally provides everything.)
WHEELHOUSES = ("/usr/share/python-wheels",)

CHECKS = [
    Check("project_file", "python/minimalist_package has a valid pyproject.toml (or setup.py)", 1,
          "create python/minimalist_package/pyproject.toml with [build-system], [project] and [project.scripts]"),
    Check("installs", "pip installs it into a fresh venv", 3,
          "run 'python3 -m pip install ./minimalist_package' from python/ in a venv and read pip's error",
          needs=("project_file",)),
    Check("importable", "'import minimalist_package' works from any folder after installing", 2,
          "let setuptools find the package: [tool.setuptools.packages.find] include = [\"minimalist_package*\"]",
          needs=("installs",)),
    Check("console_script", "The installed minimalist_script command prints Howdy!", 3,
          "[project.scripts] minimalist_script = \"minimalist_package.minimalist_script:main\"",
          needs=("installs",)),
    Check("uninstall", "pip uninstall removes the package and its command", 1,
          "pip uninstall -y minimalist_package should work once the name in [project] is minimalist_package",
          needs=("installs",)),
]


class BuildBackendMissing(RuntimeError):
    """The grader's machine has no offline setuptools (and wheel) to build the learner's package with."""


def _version(text: str) -> tuple[int, ...]:
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


def _wheel_file(name: str, s: GradingSession) -> Path | None:
    """The newest local ``<name>-*.whl``: in ``ROS2COURSE_WHEELHOUSE``, pip's find-links, :data:`WHEELHOUSES`."""
    folders = [p for p in s.base_env.get("ROS2COURSE_WHEELHOUSE", "").split(":") if p]
    folders += [p for p in re.split(r"[\s:]+", s.base_env.get("PIP_FIND_LINKS", "")) if p.startswith("/")]
    folders += list(WHEELHOUSES)
    found = [w for folder in folders if Path(folder).is_dir() for w in Path(folder).glob(f"{name}-*.whl")]
    return max(found, key=lambda w: _version(w.name.split("-")[1]), default=None)


def build_backend(s: GradingSession) -> Path:
    """A folder (under ``s.log_dir``) holding setuptools, and ``wheel`` if setuptools needs it, for ``PYTHONPATH``.

    Raises:
        BuildBackendMissing: neither the grader's interpreter nor a local wheel file provides them
            (a fault of the course's installation, reported as a grader error).
    """
    dest = s.log_dir / "build_backend"
    shutil.rmtree(dest, ignore_errors=True)
    dest.mkdir(parents=True)
    versions = {}
    for name in ("setuptools", "wheel"):
        if name == "wheel" and _version(versions["setuptools"]) >= SETUPTOOLS_WITH_BDIST_WHEEL:
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


def _source_copy(s: GradingSession) -> Path:
    """Copy the learner's project to ``s.log_dir`` without build leftovers; return the copy."""
    copy = s.log_dir / "source" / "minimalist_package"
    shutil.rmtree(copy.parent, ignore_errors=True)
    shutil.copytree(s.workspace_root / FOLDER, copy, symlinks=True,
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "build", "dist", ".venv", "venv"))
    return copy


def _env(s: GradingSession, **extra: str) -> dict[str, str]:
    """The base environment without any venv or PYTHONPATH, plus ``extra``; pip never asks or downloads."""
    env = {k: v for k, v in s.base_env.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME", "PYTHONSTARTUP")}
    env.update(PIP_NO_INPUT="1", PIP_NO_CACHE_DIR="1", PIP_DISABLE_PIP_VERSION_CHECK="1", PIP_NO_INDEX="1",
               PYTHONDONTWRITEBYTECODE="1", **extra)
    return env


def _last_error(text: str) -> str:
    """The most telling line of pip's output: the first ``error:``-like line, else the last line."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    for line in lines:
        if re.match(r"(ERROR|error|\w*Error)\b", line):
            return line[:300]
    return lines[-1][:300] if lines else "(no output)"


def _project_file(s: GradingSession) -> None:
    """Record ``project_file``: pyproject.toml parses as TOML with a build backend, or a setup.py exists."""
    folder = s.workspace_root / FOLDER
    pyproject, setup_py = folder / "pyproject.toml", folder / "setup.py"
    if not folder.is_dir():
        s.record("project_file", False, f"there is no folder {FOLDER}", f"{FOLDER} from the previous lessons")
        raise Unmet("no project folder")
    if pyproject.is_file():
        try:
            data = tomllib.loads(pyproject.read_text(encoding="utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
            s.record("project_file", False, f"pyproject.toml is not valid TOML: {exc}",
                     "a pyproject.toml that parses (quotes around strings, [section] headers)")
            raise Unmet("pyproject.toml does not parse") from exc
        backend = data.get("build-system", {}).get("build-backend")
        name = data.get("project", {}).get("name")
        ok = (backend or "").startswith("setuptools") and (name is not None or setup_py.is_file())
        s.record("project_file", ok, f"pyproject.toml: build-backend {backend!r}, [project] name {name!r}",
                 "build-backend = \"setuptools.build_meta\" and a [project] table with name = \"minimalist_package\"")
        if not ok:
            raise Unmet("pyproject.toml does not declare setuptools")
        return
    s.record("project_file", setup_py.is_file(),
             "setup.py found (no pyproject.toml)" if setup_py.is_file() else
             f"neither {FOLDER}/pyproject.toml nor {FOLDER}/setup.py exists",
             "python/minimalist_package/pyproject.toml")
    if not setup_py.is_file():
        raise Unmet("no pyproject.toml or setup.py")


def grade(s: GradingSession) -> None:
    """Install into a fresh venv, import from /, run the command, uninstall (about 4 s warm)."""
    _project_file(s)
    backend = build_backend(s)
    source = _source_copy(s)
    venv = s.log_dir / "fresh_venv"
    shutil.rmtree(venv, ignore_errors=True)
    made = run_program(s, [sys.executable, "-m", "venv", "--without-pip", str(venv)], "make_venv",
                       timeout=60.0, env=_env(s), cwd=s.log_dir)
    python = venv / "bin" / "python"
    if made.returncode != 0 or not python.exists():
        raise RuntimeError(f"'python -m venv' failed: {made.describe()}: {_last_error(made.stderr)}")
    pip = [sys.executable, "-m", "pip", "--python", str(python)]

    install = run_program(s, [*pip, "install", "--no-build-isolation", "--no-deps", str(source)], "pip_install",
                          timeout=PIP_TIMEOUT, env=_env(s, PYTHONPATH=str(backend)), cwd=source.parent)
    ok = install.returncode == 0 and not install.timed_out
    s.record("installs", ok,
             "pip install succeeded" if ok else
             f"pip install {install.describe()}: {_last_error(install.stderr + install.stdout)}",
             "'pip install ./minimalist_package' ends with 'Successfully installed minimalist-package-...'")
    if not ok:
        raise Unmet("pip install failed")

    probe = "import minimalist_package, minimalist_package.minimalist_script as m; print(minimalist_package.__file__)"
    imported = run_program(s, [str(python), "-c", probe], "import_from_root", timeout=30.0, env=_env(s), cwd=Path("/"))
    where = imported.stdout.strip().splitlines()[-1] if imported.stdout.strip() else ""
    inside = bool(where) and Path(where).resolve().is_relative_to(venv.resolve())
    s.record("importable", imported.returncode == 0 and inside,
             f"from /, the venv's python imported minimalist_package from {where}" if imported.returncode == 0 else
             f"from /, 'import minimalist_package' failed: {_last_error(imported.stderr)}",
             f"it imports from the venv's site-packages ({venv}/lib/...), i.e. pip installed the package's modules")

    command = venv / "bin" / SCRIPT
    if not command.exists():
        scripts = sorted(p.name for p in (venv / "bin").iterdir()
                         if not p.name.startswith(("python", "activate", "Activate")))
        s.record("console_script", False, f"no {SCRIPT} in the venv's bin/ (it has: {', '.join(scripts) or 'none'})",
                 f"pip installs a {SCRIPT} command")
    else:
        ran = interrupt_after(s, [str(command)], "console_script", WINDOW, exit_timeout=3.0, env=_env(s),
                              cwd=Path("/"))
        howdies = ran.stdout.count("Howdy!")
        s.record("console_script", howdies >= 2,
                 f"'{SCRIPT}' printed Howdy! {howdies} time(s) in {WINDOW} s"
                 + (f"; {_last_error(ran.stderr)}" if ran.traceback.strip() else ""),
                 f"it runs minimalist_package.minimalist_script:main, which prints Howdy! twice a second (>= 2 in {WINDOW} s)")

    removed = run_program(s, [*pip, "uninstall", "-y", PACKAGE], "pip_uninstall", timeout=PIP_TIMEOUT, env=_env(s),
                          cwd=Path("/"))
    after = run_program(s, [str(python), "-c", "import minimalist_package"], "import_after_uninstall", timeout=30.0,
                        env=_env(s), cwd=Path("/"))
    left = [what for what, there in ((f"the {SCRIPT} command", command.exists()),
                                     ("the importable package", after.returncode == 0)) if there]
    s.record("uninstall", removed.returncode == 0 and not left,
             f"pip uninstall {removed.describe()}" + (f"; still there: {', '.join(left)}" if left else
                                                       "; package and command are gone"),
             "'pip uninstall -y minimalist_package' exits 0 and removes the package and its command")
