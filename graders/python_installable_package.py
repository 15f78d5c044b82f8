"""Grader for ``python-installable-package`` (seed ch. 2.6): pip installs the minimalist package.

The learner's ``python/minimalist_package`` is copied to ``s.log_dir`` (a pip
build writes ``build/`` and ``*.egg-info`` next to the sources, which must not
land in the learner's workspace) and installed with pip into a **fresh venv**
made under ``s.log_dir``, offline (:mod:`graders._pip`: ``venv
--without-pip``, the grader's own pip and setuptools on PYTHONPATH for pip's
runs only, ``--no-index --no-build-isolation --no-deps``). Then, from ``/``:
``import minimalist_package`` must work with the venv's interpreter, the
console script ``minimalist_script`` must print Howdy!, and ``pip uninstall``
must remove both.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import tomllib

from packaging.requirements import InvalidRequirement, Requirement
from packaging.utils import canonicalize_name

from ros2course.kit import Check, Session, Unmet
from . import _pip as kpip
from ros2course.kit.parts import at_once
from ros2course.kit.programs import interrupt_after, last_line, run_program
from ros2course.kit.python_programs import python_env

#: Seconds the console script is watched after its first Howdy! (then one every 0.5 s: at least 2 expected).
WINDOW = 1.6  # the lesson says so; a 0.5 s margin was all a loaded machine had before (helper audit)
#: Seconds to wait for its first line (interpreter start-up under load).
FIRST_LINE_TIMEOUT = 10.0

FOLDER = Path("python") / "minimalist_package"
PACKAGE = "minimalist_package"
SCRIPT = "minimalist_script"
#: The project's test folder, which [tool.setuptools.packages.find] must leave out of the install.
TEST_FOLDER = "test"
#: setuptools versions that read [project] (PEP 621 support came in 61.0): a requirement must admit one of them, so
#: an isolated build on the learner's machine can work ("setuptools==58.2.0", the pin many Humble guides give to
#: silence a colcon warning, installs a package named UNKNOWN there; audit of stop 71: it passed before).
PEP621_SETUPTOOLS = ("61.0", "65.0", "70.0", "75.0", "80.0")
#: What else a build may require: the tutorial installs wheel beside setuptools (the lesson: "your package may not
#: need anything else to build").
ALSO_ALLOWED = {"wheel"}

CHECKS = [
    Check("project_file", "python/minimalist_package has a valid pyproject.toml (or setup.py)", 1,
          "create python/minimalist_package/pyproject.toml with [build-system], [project] and [project.scripts]"),
    Check("build_requires", "[build-system] requires names setuptools", 1,
          "in pyproject.toml: [build-system] requires = [\"setuptools>=61\"] (what pip installs to build the package)",
          needs=("project_file",)),
    Check("installs", "pip installs it into a fresh venv", 3,
          "run 'python3 -m pip install ./minimalist_package' from python/ in a venv and read pip's error",
          needs=("project_file",)),
    Check("importable", "'import minimalist_package' works from any folder after installing", 2,
          "let setuptools find the package: [tool.setuptools.packages.find] include = [\"minimalist_package*\"]",
          needs=("installs",)),
    Check("leaves_out_tests", "The install leaves the project's test/ folder out", 1,
          "include only the package: [tool.setuptools.packages.find] include = [\"minimalist_package*\"] "
          "(without it setuptools also installs test/ as a top-level package named test)",
          needs=("installs",)),
    Check("console_script", "The installed minimalist_script command prints Howdy!", 3,
          "[project.scripts] minimalist_script = \"minimalist_package.minimalist_script:main\"",
          needs=("installs",)),
    Check("uninstall", "pip uninstall removes the package and its command", 1,
          "pip uninstall -y minimalist_package should work once the name in [project] is minimalist_package",
          needs=("installs",)),
]

def _project_file(s: Session) -> None:
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
        _build_requires(s, data)
    else:
        s.record("project_file", setup_py.is_file(), "setup.py found (no pyproject.toml)" if setup_py.is_file() else
                 f"neither {FOLDER}/pyproject.toml nor {FOLDER}/setup.py exists", f"{FOLDER}/pyproject.toml")
        # recorded after project_file: without any project file it is "not checked", not a pass
        s.record("build_requires", True, "no pyproject.toml: pip builds a setup.py with setuptools",
                 "setuptools named as the build requirement")
    s.require("project_file")


def _build_requires(s: Session, data: dict) -> None:
    """``build_requires``: ``[build-system] requires`` lists setuptools (pip installs it for an isolated build).

    The grader builds offline without isolation, so its own setuptools builds the package whatever ``requires``
    says; ``pip install`` on the learner's machine installs exactly the listed requirements first.
    """
    build_system = data.get("build-system")
    requires = build_system.get("requires") if isinstance(build_system, dict) else None
    parsed = [_requirement(r) for r in requires] if isinstance(requires, list) else []
    names = [canonicalize_name(r.name) if r else None for r in parsed]
    modern = any(r and name == "setuptools" and any(r.specifier.contains(v, prereleases=True) for v in PEP621_SETUPTOOLS)
                 for r, name in zip(parsed, names))
    others = [str(r) for r, name in zip(requires or [], names) if name not in ("setuptools", *ALSO_ALLOWED)]
    s.record("build_requires", modern and not others,
             "pyproject.toml has no [build-system] table" if build_system is None else
             "[build-system] has no requires key" if requires is None else
             f"[build-system] requires = {requires!r}" + (
                 f": the build also needs {', '.join(others)}" if others else "" if modern else
                 ": no setuptools 61 or newer (older ones ignore [project]: pip would install a package UNKNOWN)"
                 if "setuptools" in names else ": no setuptools"),
             "[build-system] requires = [\"setuptools>=61\"] (and nothing else but wheel): pip installs exactly that "
             "before building")


def _requirement(text: object) -> Requirement | None:
    """``text`` as a PEP 508 requirement (packaging's own parser), None when it is not one."""
    try:
        return Requirement(text) if isinstance(text, str) else None
    except InvalidRequirement:
        return None


def grade(s: Session) -> None:
    """Install into a fresh venv, import from /, then run the command while a copy of the venv uninstalls."""
    _project_file(s)
    tools = kpip.tools_folder(s)
    # pip builds in the source tree, as the submission: a copy in a folder the submission may write
    source = s.submission_folder("source", lambda folder: shutil.copytree(
        s.workspace_root / FOLDER, folder / "minimalist_package", symlinks=True,
        ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "build", "dist", ".venv", "venv"))
    ) / "minimalist_package"
    python = kpip.fresh_venv(s)
    venv, env = python.parent.parent, python_env(s)

    install = kpip.pip(s, python, tools, ["install", "--no-build-isolation", "--no-deps", "--no-compile", str(source)],
                       "pip_install", cwd=source.parent)
    ok = install.returncode == 0 and not install.timed_out
    s.record("installs", ok, "pip install succeeded" if ok else
             f"pip install {install.describe()}: {kpip.last_error(install.stderr + install.stdout)}",
             "'pip install ./minimalist_package' ends with 'Successfully installed minimalist-package-...'")
    s.require("installs")

    # the import and the uninstall (in a copy of the venv: graders._pip.venv_copy) are judged while the command runs
    removal = kpip.venv_copy(s, python, "uninstall_venv")
    at_once(s, "install", lambda: (_importable(s, python, env), _leaves_out_tests(s, python),
                                   _uninstall(s, removal, tools, env)), "command",
            lambda: _console_script(s, venv / "bin" / SCRIPT, env))


def _importable(s: Session, python: Path, env: dict[str, str]) -> None:
    """``importable``: from ``/``, the venv's python imports minimalist_package from the venv's site-packages."""
    venv = python.parent.parent
    probe = "import minimalist_package, minimalist_package.minimalist_script as m; print(minimalist_package.__file__)"
    imported = run_program(s, [str(python), "-c", probe], "import_from_root", timeout=30.0, env=env, cwd=Path("/"))
    where = last_line(imported.stdout)
    inside = bool(where) and Path(where).resolve().is_relative_to(venv.resolve())
    s.record("importable", imported.returncode == 0 and inside,
             f"from /, the venv's python imported minimalist_package from {where}" if imported.returncode == 0 else
             f"from /, 'import minimalist_package' failed: {kpip.last_error(imported.stderr)}",
             f"it imports from the venv's site-packages ({venv}/lib/...), i.e. pip installed the package's modules")


def _leaves_out_tests(s: Session, python: Path) -> None:
    """``leaves_out_tests``: the venv's site-packages holds no top-level ``test`` (package or module) after the install.

    The fresh venv holds nothing of its own (made without pip), so a ``test`` there came from this install.
    """
    venv = python.parent.parent
    found = sorted(str(entry.relative_to(venv)) for root in venv.glob("lib/python3*/site-packages")
                   for entry in (root / TEST_FOLDER, root / f"{TEST_FOLDER}.py") if entry.exists())
    s.record("leaves_out_tests", not found,
             f"the install put the project's tests into site-packages: {', '.join(found)}" if found else
             f"no top-level {TEST_FOLDER} in the venv's site-packages",
             f"only minimalist_package installed: {TEST_FOLDER}/ stays out of site-packages")


def _uninstall(s: Session, python: Path, tools: Path, env: dict[str, str]) -> None:
    """``uninstall``: ``pip uninstall -y`` exits 0, then neither the command nor the import is left in that venv."""
    command, root = python.parent / SCRIPT, Path("/")
    removed = kpip.pip(s, python, tools, ["uninstall", "-y", PACKAGE], "pip_uninstall", cwd=root)
    after = run_program(s, [str(python), "-c", "import minimalist_package"], "import_after_uninstall", timeout=30.0,
                        env=env, cwd=root)
    left = [what for what, there in ((f"the {SCRIPT} command", command.exists()),
                                     ("the importable package", after.returncode == 0)) if there]
    s.record("uninstall", removed.returncode == 0 and not left,
             f"pip uninstall {removed.describe()}" + (f"; still there: {', '.join(left)}" if left else
                                                       "; package and command are gone"),
             "'pip uninstall -y minimalist_package' exits 0 and removes the package and its command")


def _console_script(s: Session, command: Path, env: dict[str, str]) -> None:
    """``console_script``: the installed command prints Howdy! at least twice in WINDOW s after its first line."""
    if not command.exists():
        scripts = sorted(p.name for p in command.parent.iterdir()
                         if not p.name.startswith(("python", "activate", "Activate")))
        s.record("console_script", False, f"no {SCRIPT} in the venv's bin/ (it has: {', '.join(scripts) or 'none'})",
                 f"pip installs a {SCRIPT} command")
    else:
        ran = interrupt_after(s, [str(command)], "console_script", WINDOW, exit_timeout=3.0, env=env, cwd=Path("/"),
                              wait_for="Howdy!", first_timeout=FIRST_LINE_TIMEOUT)
        howdies = ran.stdout.count("Howdy!")
        s.record("console_script", howdies >= 2,
                 f"'{SCRIPT}' printed Howdy! {howdies} time(s) in {WINDOW} s after its first line"
                 + (f"; {kpip.last_error(ran.stderr.replace(str(s.log_dir), '<grader>'))}" if ran.traceback.strip() else ""),
                 f"it runs minimalist_package.minimalist_script:main, which prints Howdy! twice a second "
                 f"(the first line and >= 1 more in the {WINDOW} s after it)")
