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

from ros2course.builder.colcon import colcon_command
from ros2course.grade.checklist import Unmet
from ros2course.kit.session_protocol import Session
from ros2course.ros import index as ament_index
from ros2course import sandbox
from ros2course.run.probes import stamp_seconds
from ros2course.kit.nodes import executable as executable_step

# --- setup.cfg and setup.py ----------------------------------------------------------

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


def colcon_python(s: Session) -> str:
    """The interpreter colcon runs ``setup.py`` with (its script's shebang), else ``sys.executable``.

    It has setuptools (colcon needs it to build ``ament_python`` packages); the course's own
    interpreter may not (a Python 3.12 venv ships without setuptools).
    """
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


def setup_py_arguments(s: Session, folder: Path, timeout: float = 30.0) -> tuple[dict[str, Any], str]:
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

def install_prefix(s: Session, package: str) -> Path:
    """Where colcon installed ``package``: ``install/<package>`` (isolated layout) or ``install/`` (merged)."""
    isolated = s.workspace_root / "install" / package
    return isolated if isolated.is_dir() else s.workspace_root / "install"


def site_packages(prefix: Path) -> list[Path]:
    """The ``lib/python3.*/site-packages`` folders under ``prefix`` (sorted)."""
    return sorted(prefix.glob("lib/python3*/site-packages"))


def relative(s: Session, path: Path) -> str:
    """``path`` relative to the workspace when it is inside it (shorter observations)."""
    try:
        return str(path.relative_to(s.workspace_root))
    except ValueError:
        return str(path)


def ament_index_packages(s: Session) -> dict[str, str]:
    """Package name -> prefix, as ``ros2 pkg list`` sees them with the workspace sourced.

    Read from the overlay itself (:mod:`ros2course.ros.index`), not the process environment.
    """
    return {name: str(prefix) for name, prefix in ament_index.packages_with_prefixes(s.overlay()).items()}


def run_installed_python(s: Session, code: str, timeout: float = 20.0,
                         args: tuple[str, ...] = ()) -> tuple[dict[str, Any], str]:
    """Run ``code`` with the sourced workspace's Python, from an empty folder outside the source tree.

    ``code`` finds the path of a JSON output file in ``sys.argv[1]`` (then ``args``) and writes
    its findings there (so whatever the learner's code prints cannot garble them). ``timeout``
    is in seconds.

    Returns:
        ``(result, problem)``: the decoded JSON (``{}`` if none) and, when the run itself
        failed (timeout, crash before writing), a sentence saying so.
    """
    with sandbox.private_dir("ros2course-import-") as folder:
        out = folder / "result.json"
        env = s.overlay()
        env["PYTHONDONTWRITEBYTECODE"] = "1"
        try:
            proc = sandbox.run([sys.executable, "-c", code, str(out), *args], cwd=folder, env=env,
                                  stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=timeout,
                                  check=False)
        except subprocess.TimeoutExpired:
            return {}, f"importing the library did not finish within {timeout:.0f} s"
        try:
            return json.loads(out.read_text(encoding="utf-8")), ""
        except (OSError, ValueError):
            tail = (proc.stderr.strip().splitlines() or ["no output"])[-1]
            return {}, f"the import test crashed (exit code {proc.returncode}): {tail}"


#: Imports the module named in ``sys.argv[2]`` and writes ``{"file": ...}`` or ``{"error": ...}`` to ``sys.argv[1]``.
IMPORT_PROBE = """
import importlib, json, sys
out = {}
try:
    m = importlib.import_module(sys.argv[2])
    out["file"] = str(getattr(m, "__file__", None) or list(getattr(m, "__path__", [])))
except BaseException as exc:
    out["error"] = f"{type(exc).__name__}: {exc}"
with open(sys.argv[1], "w") as f:
    json.dump(out, f)
"""


def installed_import(s: Session, check_id: str, module: str, expected: str, note: str = "",
                     code: str = "") -> dict[str, Any]:
    """Record ``check_id`` on whether ``import module`` works with the workspace sourced and loads install/'s copy.

    Runs ``code`` (default :data:`IMPORT_PROBE`) with :func:`run_installed_python`, from an
    empty folder outside the source tree, so a module found only in ``src/`` does not count
    (other packages import the installed copy: seed ch. 14-15). ``code`` gets the JSON output
    path in ``sys.argv[1]`` and ``module`` in ``sys.argv[2]``; it writes ``"file"`` (the
    module's ``__file__``) or ``"error"`` (the import's exception), plus anything else the
    grader wants back.

    Args:
        note: appended to the observation when the import fails (e.g. where colcon should
            have installed it).

    Returns:
        The decoded JSON the code wrote (``{}`` when it crashed before writing).
    """
    result, problem = run_installed_python(s, code or IMPORT_PROBE, args=(module,))
    if problem:
        s.record(check_id, False, problem, expected)
    elif "error" in result:
        s.record(check_id, False, f"import {module} with the workspace sourced: {result['error']}{note}", expected)
    else:
        where = result.get("file", "")
        inside = str(s.workspace_root / "install") in where
        s.record(check_id, inside, f"import {module} loads {relative(s, Path(where))}", expected,
                 None if inside else "that is not the copy colcon installed under install/: rebuild and "
                 "source install/setup.bash")
    return result


def ros2_run_executable(s: Session, check_id: str, package: str, executable: str, hint: str = "") -> Path:
    """:func:`ros2course.kit.executable`, saying so when the script went to ``bin/`` instead.

    Records ``check_id`` on whether ``ros2 run package executable`` finds
    ``<prefix>/lib/<package>/<executable>``. Without ``setup.cfg`` (or with a wrong
    ``install_scripts``) setuptools installs console scripts in ``<prefix>/bin``, where
    ``ros2 run`` does not look (ros2run source; shared/ROS_ENV.md): the observation then
    names the stray file and the hint the ``setup.cfg`` lines of the ``ros2 pkg create``
    template (seed ch. 7-8).

    Raises:
        Unmet: not found (nothing to run).
    """
    try:
        return executable_step(s, check_id, package, executable, hint)
    except Unmet:
        prefix = install_prefix(s, package)
        strays = [p for p in (prefix / "bin" / executable, prefix / "lib" / executable) if p.is_file()]
        if strays:
            s.amend(check_id, observed=f"{s.results[check_id].observed}; it was installed as "
                    f"{relative(s, strays[0])} instead",
                    hint=f"setup.cfg must say install_scripts=$base/lib/{package} "
                    f"(and script_dir=$base/lib/{package} under [develop]); then colcon build")
        raise


def installed_subpackage(s: Session, check_id: str, package: str, subpackage: str) -> bool:
    """Record ``check_id`` on whether colcon installed ``package/subpackage/__init__.py`` in site-packages.

    Looks under ``<prefix>/lib/python3.*/site-packages`` of the package's install
    prefix (isolated or merged layout). ``packages=[package_name]`` in ``setup.py``
    installs only the top level; ``find_packages()`` installs every folder with an
    ``__init__.py`` (seed ch. 14.1; setuptools docs, "Package Discovery").
    Observed lists what was installed instead.
    """
    prefix = install_prefix(s, package)
    roots = site_packages(prefix)
    found = [p for p in (root / package / subpackage / "__init__.py" for root in roots) if p.is_file()]
    expected = f"install/{package}/lib/python3.*/site-packages/{package}/{subpackage}/__init__.py"
    if found:
        files = sorted(p.name for p in found[0].parent.iterdir() if p.suffix == ".py")
        return s.record(check_id, True, f"{relative(s, found[0].parent)} holds {', '.join(files)}", expected)
    if not roots:
        observed = f"no {relative(s, prefix)}/lib/python3.*/site-packages folder (was the package built?)"
    else:
        top = roots[0] / package
        listing = sorted(p.name + ("/" if p.is_dir() else "") for p in top.iterdir()) if top.is_dir() else []
        observed = (f"{relative(s, top)} holds {', '.join(listing) or 'nothing'}: no {subpackage}/"
                    if top.is_dir() else f"no {relative(s, top)}")
    return s.record(check_id, False, observed, expected)


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


def shorten(text: str, limit: int = 110) -> str:
    """``text`` cut to ``limit`` characters (``...`` at the end when cut), for observations."""
    return text if len(text) <= limit else text[: limit - 3] + "..."


def square_lines(s: Session, ranges_check: str, values_check: str, records: list[Any]) -> None:
    """Record ``ranges_check`` and ``values_check`` over /rosout ``records`` of square-of-sum lines.

    ``records`` are ``rcl_interfaces/msg/Log`` messages whose text :func:`parse_square_line`
    accepts. Ranges: a in [0, 1], b in [1, 2]; values: c == (a+b)**2 within the printed
    digits (:class:`SquareLine`; seed ch. 15.1).
    """
    lines = [parse_square_line(r.msg) for r in records]
    out_of_range = [r.msg for line, r in zip(lines, records) if not line.ranges_ok()]
    s.record(ranges_check, not out_of_range,
             f"all {len(lines)} records in range" if not out_of_range
             else f"{len(out_of_range)}/{len(lines)} out of range, e.g. '{shorten(out_of_range[0])}'",
             "0 <= a <= 1 and 1 <= b <= 2 in every record")
    wrong = [(line, r.msg) for line, r in zip(lines, records) if not line.square_ok()]
    if not wrong:
        observed = f"c == (a+b)**2 in all {len(lines)} records"
    else:
        line, text = wrong[0]
        observed = (f"{len(wrong)}/{len(lines)} records wrong, e.g. '{shorten(text)}': "
                    f"(a+b)**2 = {line.expected_c()!r}, logged c = {line.c!r}")
    s.record(values_check, not wrong, observed, "c == (a+b)**2 (within the digits printed)")


def name_lines(s: Session, name_check: str, pairs_check: str, differ_check: str, ordered: list[Any],
               max_gap: float) -> None:
    """Record the name-line checks over one node's /rosout ``records`` of both kinds, in order.

    ``name_check``: every ``get_name() returned NAME`` record has ten ASCII letters;
    ``pairs_check``: each square-of-sum record is followed by a name record within
    ``max_gap`` seconds (:func:`unpaired`); ``differ_check``: no name repeats (a new
    random name per tick, seed ch. 15.1). ``ordered`` holds Log messages that
    :func:`classify` calls ``"square"`` or ``"name"``.
    """
    names = [parse_name_line(r.msg) for r in ordered if classify(r.msg) == "name"]
    expected_name = "INFO records 'sample_class_with_random_name.get_name() returned NAME.', NAME ten ASCII letters"
    if not names:
        s.record(name_check, False, "no 'sample_class_with_random_name.get_name() returned ...' record from the node",
                 expected_name)
        s.record(pairs_check, False, "no name records to pair", "a name record right after each square-of-sum record")
        s.record(differ_check, False, "no names logged", "a different name in every record")
        return
    bad = [n for n in names if not is_ten_letters(n)]
    s.record(name_check, not bad,
             f"{len(names)} names like {names[0]!r}" if not bad
             else f"{len(bad)}/{len(names)} names are not ten ASCII letters, e.g. {bad[0]!r} ({len(bad[0])} characters)",
             expected_name)
    kinds = [classify(r.msg) for r in ordered]
    lonely = unpaired([(kind, stamp_seconds(r.stamp)) for kind, r in zip(kinds, ordered)], max_gap=max_gap)
    shown = " ".join("S" if k == "square" else "N" for k in kinds[:12])
    s.record(pairs_check, not lonely,
             f"{kinds.count('square')} square and {kinds.count('name')} name records alternate ({shown} ...)"
             if not lonely else f"order of records (S square, N name): {shown}{' ...' if len(kinds) > 12 else ''}"
             f"; {len(lonely)} not in a square-then-name pair logged together",
             "S N S N ...: in every tick the square-of-sum record, then at once the name record")
    distinct = len(set(names))
    s.record(differ_check, len(names) >= 2 and distinct == len(names),
             f"{distinct} different names in {len(names)} records"
             + (f" (repeated: {max(set(names), key=names.count)!r})" if distinct < len(names) else ""),
             "a new random name in every record")
