"""Helpers of the packaging lessons (seed ch. 7-8, 14-15): installed files, the ament
index, importing the installed library, and the log lines of ``use-python-library``.

Everything that needs no ROS (the parsers, ``setup.cfg`` reading) is plain Python and
unit-tested in ``tests/test_lessons_packaging.py``.
"""

from __future__ import annotations

import configparser
import dataclasses
import json
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

from course import index as ament_index
from course import sandbox
from course.grading import GradingSession

# --- package.xml and setup.cfg ------------------------------------------------------

def source_package(s: GradingSession, name: str) -> tuple[Path, Any] | None:
    """``(folder, catkin_pkg Package)`` of the workspace package ``name`` under ``src/``, or None."""
    from course.build import find_packages

    return find_packages(s.workspace_root / "src").get(name)


def run_dependencies(package: Any) -> set[str]:
    """Names a ``package.xml`` lists as build or run dependencies (``<depend>`` counts as both)."""
    return {d.name for d in (*package.exec_depends, *package.build_depends, *package.build_export_depends)}


def read_setup_cfg(path: Path) -> dict[str, dict[str, str]]:
    """``setup.cfg`` as ``{section: {key: value}}``; keys normalised (``script-dir`` -> ``script_dir``).

    setuptools reads dashed keys too (with a deprecation warning), and the Foxy-era
    template used them, so both spellings count. Returns {} for a missing or unreadable file.
    """
    parser = configparser.ConfigParser(interpolation=None)
    try:
        parser.read_string(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, configparser.Error):
        return {}
    return {section: {key.replace("-", "_"): value.strip() for key, value in parser.items(section)}
            for section in parser.sections()}


def setup_cfg_problems(path: Path, package: str) -> list[str]:
    """What is wrong with an ``ament_python`` ``setup.cfg`` (empty list: nothing).

    The ``ros2 pkg create`` template (Humble and Jazzy) sets ``[develop] script_dir`` and
    ``[install] install_scripts`` to ``$base/lib/<package>``: that is where ``ros2 run``
    looks for executables (ros2run source; shared/ROS_ENV.md).
    """
    if not path.is_file():
        return [f"there is no {path.name}"]
    cfg = read_setup_cfg(path)
    wanted = f"$base/lib/{package}"
    problems = []
    for section, key in (("develop", "script_dir"), ("install", "install_scripts")):
        value = cfg.get(section, {}).get(key)
        if value is None:
            problems.append(f"[{section}] has no {key}")
        elif value.rstrip("/") != wanted:
            problems.append(f"[{section}] {key}={value}")
    return problems


_SETUP_ARGS = """
import json, os, runpy, sys
import setuptools
captured = {}


def fake_setup(**kwargs):
    captured.update(kwargs)


setuptools.setup = fake_setup
out = sys.argv[1]
sys.argv = ['setup.py', '--dry-run']
sys.path.insert(0, os.getcwd())
try:
    runpy.run_path('setup.py', run_name='__main__')
    result = {'arguments': captured}
except BaseException as exc:
    result = {'error': f'{type(exc).__name__}: {exc}'}
with open(out, 'w') as f:
    json.dump(result, f, default=repr)
"""


def colcon_python(s: GradingSession) -> str:
    """The interpreter colcon runs ``setup.py`` with (its script's shebang), else ``sys.executable``.

    It has setuptools (colcon needs it to build ``ament_python`` packages); the course's own
    interpreter may not (a Python 3.12 venv ships without setuptools).
    """
    from course.build import colcon_command

    command = colcon_command(s.base_env)[0]
    script = command if os.path.isabs(command) else shutil.which(command, path=s.base_env.get("PATH"))
    try:
        with open(script or "", "rb") as handle:
            first = handle.readline().decode(errors="replace").strip()
    except OSError:
        return sys.executable
    if first.startswith("#!"):
        parts = first[2:].split()
        if parts and os.path.basename(parts[0]) == "env" and len(parts) > 1:
            found = shutil.which(parts[1], path=s.base_env.get("PATH"))
            return found or sys.executable
        if parts and os.access(parts[0], os.X_OK):
            return parts[0]
    return sys.executable


def setup_py_arguments(s: GradingSession, folder: Path, timeout: float = 30.0) -> tuple[dict[str, Any], str]:
    """The keyword arguments ``folder/setup.py`` passes to ``setuptools.setup()``.

    Dry-runs the script with ``setup()`` replaced, as colcon itself does to read
    ``data_files`` (colcon-python-setup-py ``get_setup_information``), with colcon's
    interpreter (:func:`colcon_python`). Values that are not JSON (e.g. sets) come back
    as their ``repr``.

    Returns:
        ``(arguments, problem)``: ``problem`` is a sentence when the script could not be run.
    """
    with sandbox.private_dir("ros2course-setup-") as tmp:
        out = tmp / "setup.json"
        try:
            proc = sandbox.run([colcon_python(s), "-c", _SETUP_ARGS, str(out)], cwd=folder, env=s.base_env,
                                  stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=timeout,
                                  check=False)
        except subprocess.TimeoutExpired:
            return {}, f"setup.py did not finish within {timeout:.0f} s"
        try:
            data = json.loads(out.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
            return {}, f"setup.py could not be run (exit code {proc.returncode}): {tail}"
    if "error" in data:
        return {}, f"setup.py failed: {data['error']}"
    return data.get("arguments", {}), ""


def data_files_mapping(data_files: Any) -> dict[str, str]:
    """``data_files`` as ``{source file: installed path}``, the way colcon reads it
    (colcon_core.task.python.get_data_files_mapping), but never raising on odd entries."""
    mapping: dict[str, str] = {}
    for entry in data_files or []:
        if isinstance(entry, (list, tuple)) and len(entry) == 2 and isinstance(entry[1], (list, tuple)):
            dest, sources = entry
            for source in sources:
                mapping[os.path.normpath(str(source))] = os.path.normpath(os.path.join(str(dest), os.path.basename(str(source))))
        elif isinstance(entry, str):
            mapping[os.path.normpath(entry)] = os.path.basename(entry)
    return mapping


# --- the install tree ---------------------------------------------------------------

def install_prefix(s: GradingSession, package: str) -> Path:
    """Where colcon installed ``package``: ``install/<package>`` (isolated layout) or ``install/`` (merged)."""
    isolated = s.workspace_root / "install" / package
    return isolated if isolated.is_dir() else s.workspace_root / "install"


def site_packages(prefix: Path) -> list[Path]:
    """The ``lib/python3.*/site-packages`` folders under ``prefix`` (sorted)."""
    return sorted(prefix.glob("lib/python3*/site-packages"))


def relative(s: GradingSession, path: Path) -> str:
    """``path`` relative to the workspace when it is inside it (shorter observations)."""
    try:
        return str(path.relative_to(s.workspace_root))
    except ValueError:
        return str(path)


def ament_index_packages(s: GradingSession) -> dict[str, str]:
    """Package name -> prefix, as ``ros2 pkg list`` sees them with the workspace sourced.

    Read from the overlay itself (:mod:`course.index`), not the process environment.
    """
    return {name: str(prefix) for name, prefix in ament_index.packages_with_prefixes(s.overlay()).items()}


def run_installed_python(s: GradingSession, code: str, timeout: float = 20.0) -> tuple[dict[str, Any], str]:
    """Run ``code`` with the sourced workspace's Python, from an empty folder outside the source tree.

    ``code`` finds the path of a JSON output file in ``sys.argv[1]`` and writes its findings
    there (so whatever the learner's code prints cannot garble them).

    Returns:
        ``(result, problem)``: the decoded JSON (``{}`` if none) and, when the run itself
        failed (timeout, crash before writing), a sentence saying so.
    """
    with sandbox.private_dir("ros2course-import-") as folder:
        out = folder / "result.json"
        env = s.overlay()
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        try:
            proc = sandbox.run([sys.executable, "-c", code, str(out)], cwd=folder, env=env,
                                  stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=timeout,
                                  check=False)
        except subprocess.TimeoutExpired:
            return {}, f"importing the library did not finish within {timeout:.0f} s"
        try:
            return json.loads(out.read_text(encoding="utf-8")), ""
        except (OSError, ValueError):
            tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
            return {}, f"the import test crashed (exit code {proc.returncode}): {tail}"


def require_ros2_run_executable(s: GradingSession, check_id: str, package: str, executable: str,
                                hint: str = "") -> Path | None:
    """Like ``graders._common.require_executable``, but says so when the script went to ``bin/``.

    Without ``setup.cfg`` (or with a wrong ``install_scripts``) setuptools installs console
    scripts in ``<prefix>/bin``, where ``ros2 run`` does not look (shared/ROS_ENV.md).
    """
    from graders._common import require_executable

    path = require_executable(s, check_id, package, executable, hint)
    if path is None:
        prefix = install_prefix(s, package)
        strays = [p for p in (prefix / "bin" / executable, prefix / "lib" / executable) if p.is_file()]
        if strays:
            result = s.results[check_id]
            s.record(check_id, False, f"{result.observed}; it was installed as {relative(s, strays[0])} instead",
                     result.expected, f"setup.cfg must say install_scripts=$base/lib/{package} "
                     f"(and script_dir=$base/lib/{package} under [develop]); then colcon build")
    return path


# --- log lines of use-python-library (seed ch. 15.1) ---------------------------------

#: A number as Python's str()/repr() or a format spec may print it (``1``, ``-0.5``, ``.5``, ``1e-05``).
NUMBER = r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?"
SQUARE_LINE = re.compile(
    rf"^sample_function_for_square_of_sum\(\s*({NUMBER})\s*,\s*({NUMBER})\s*\)\s+returned\s+({NUMBER})\.?\s*$")
NAME_LINE = re.compile(r"^sample_class_with_random_name\.get_name\(\)\s+returned\s+(\S*?)\.?\s*$")
TEN_LETTERS = re.compile(r"^[A-Za-z]{10}$")
#: relative tolerance on c beyond the rounding of the printed numbers (float noise)
RELATIVE_TOLERANCE = 1e-9


def rounding_error(text: str) -> float:
    """Largest error of a number printed as ``text``: half a unit in its last printed digit.

    ``'0.125'`` -> 0.0005, ``'3'`` -> 0.5, ``'1.5e-05'`` -> 5e-07.
    """
    mantissa, _, exponent = text.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 0.5 * 10.0 ** (-decimals + (int(exponent) if exponent else 0))


@dataclasses.dataclass(frozen=True)
class SquareLine:
    """One ``sample_function_for_square_of_sum(a,b) returned c.`` record, parsed.

    ``ea``, ``eb``, ``ec``: how far the printed numbers may be from the values the node
    computed with (half a unit in the last printed digit), so a node that formats with
    ``{a:.3f}`` is judged on what it could print.
    """

    a: float
    b: float
    c: float
    ea: float
    eb: float
    ec: float

    def expected_c(self) -> float:
        """``(a + b) ** 2`` from the printed a and b (seed ch. 14.3)."""
        return (self.a + self.b) ** 2

    def tolerance(self) -> float:
        """Largest acceptable ``|c - (a+b)**2|`` given the printed precision, plus float noise."""
        s = abs(self.a + self.b)
        e = self.ea + self.eb
        return 2 * s * e + e * e + self.ec + RELATIVE_TOLERANCE * max(1.0, abs(self.c))

    def square_ok(self) -> bool:
        """c equals (a+b)**2 within :meth:`tolerance`."""
        return math.isfinite(self.c) and abs(self.c - self.expected_c()) <= self.tolerance()

    def ranges_ok(self) -> bool:
        """a in [0, 1] and b in [1, 2] (seed ch. 15.1: ``random.uniform(0, 1)``, ``uniform(1, 2)``)."""
        return 0.0 - self.ea <= self.a <= 1.0 + self.ea and 1.0 - self.eb <= self.b <= 2.0 + self.eb


def parse_square_line(text: str) -> SquareLine | None:
    """Parse ``sample_function_for_square_of_sum(a,b) returned c.`` (spaces after the comma and the
    final period optional); None if ``text`` is not such a line."""
    match = SQUARE_LINE.match(text.strip())
    if match is None:
        return None
    sa, sb, sc = match.groups()
    return SquareLine(float(sa), float(sb), float(sc), rounding_error(sa), rounding_error(sb), rounding_error(sc))


def parse_name_line(text: str) -> str | None:
    """The NAME of ``sample_class_with_random_name.get_name() returned NAME.``, or None.

    The final period is optional: the seed's printed output has it, its code listing
    (ch. 15.1) does not.
    """
    match = NAME_LINE.match(text.strip())
    return None if match is None else match.group(1)


def is_ten_letters(name: str) -> bool:
    """True for ten ASCII letters (``string.ascii_letters``, seed ch. 15.1)."""
    return bool(TEN_LETTERS.match(name))


def classify(text: str) -> str:
    """``'square'``, ``'name'`` or ``'other'`` for one log record's text."""
    if parse_square_line(text) is not None:
        return "square"
    if parse_name_line(text) is not None:
        return "name"
    return "other"


def unpaired(records: list[tuple[str, float]], max_gap: float) -> list[int]:
    """Indexes of records that break the pattern "square, then name, in the same tick".

    Args:
        records: ``(kind, stamp in seconds)`` per record, in order (kinds from :func:`classify`).
        max_gap: seconds a name record may come after its square record (the two are logged
            by one timer callback, so a fraction of the period, e.g. half of it).

    A square record must be followed by a name record within ``max_gap``; a name record must
    follow a square record within ``max_gap``. The last record may be a square record whose
    name record is still on its way: it is not counted.
    """
    bad = []
    for index, (kind, stamp) in enumerate(records):
        if kind == "square" and index + 1 < len(records):
            next_kind, next_stamp = records[index + 1]
            if next_kind != "name" or next_stamp - stamp > max_gap:
                bad.append(index)
        if kind == "name" and (index == 0 or records[index - 1][0] != "square"
                               or stamp - records[index - 1][1] > max_gap):
            bad.append(index)
    return bad
