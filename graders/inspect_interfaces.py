"""Grader for ``inspect-interfaces`` (tutorial ch. 16 and 17.10; contract in shared/LESSONS.md).

No node runs: ``ros2 interface`` reads the interface files installed with
their packages. The grader runs the learner's ``cli/inspect_interfaces.sh``
with the sourced workspace and looks in its output for the field lines of
the installed definitions (read from each package's ``share/`` folder, found
through the ament index as ``ros2 interface`` finds them), and for every
interface type the learner's own ``package_with_interfaces`` build installed.
"""

from __future__ import annotations

import re

from pathlib import Path

from ros2course.kit import Check, Session, Unmet, scripts

SCRIPT = "cli/inspect_interfaces.sh"
PACKAGE = "package_with_interfaces"
TIMEOUT = 20.0  # seconds; each `ros2 interface` command takes well under 1 s

SCRIPTED = ("script",)
#: (check id, interface type, points) of each definition the script must show.
SHOWN = [
    ("string", "std_msgs/msg/String", 1),
    ("point", "geometry_msgs/msg/Point", 1),
    ("amazing_quote", f"{PACKAGE}/msg/AmazingQuote", 2),
    ("what_is_the_point", f"{PACKAGE}/srv/WhatIsThePoint", 1),
]
CHECKS = [
    Check("build", f"{PACKAGE} builds with colcon", 1),
    Check("script", f"{SCRIPT} exists and is valid bash", 1),
    Check("ends", "The script ends by itself, with exit code 0", 1,
          "run it yourself: the first command that prints an error is the one to fix", needs=SCRIPTED),
    Check("package", f"It lists the interface types of your {PACKAGE} (ros2 interface package)", 2,
          f"ros2 interface package {PACKAGE}", needs=SCRIPTED),
    *(Check(check_id, f"It shows the definition of {name} (ros2 interface show)", points,
            f"ros2 interface show {name}", needs=SCRIPTED) for check_id, name, points in SHOWN),
]


def definition_file(s: Session, name: str) -> Path | None:
    """The installed ``.msg``/``.srv`` file of ``pkg/kind/Name`` (``share/pkg/kind/Name.kind``), or None.

    ``ros2 interface show`` prints this file (rosidl_runtime_py ``get_interface_path``).
    """
    package, kind, base = name.split("/")
    share = s.find_share(package)
    path = share / kind / f"{base}.{kind}" if share is not None else None
    return path if path is not None and path.is_file() else None


def field_lines(path: Path) -> list[str]:
    """The definition's lines without comments and blanks (what every ``ros2 interface show`` prints)."""
    lines = (line.split("#", 1)[0].strip() for line in path.read_text(encoding="utf-8").splitlines())
    return [line for line in lines if line]


def package_types(s: Session) -> list[str]:
    """``package_with_interfaces/msg/AmazingQuote``... for every interface file the build installed.

    Raises:
        Unmet: the package is not in the ament index (not built and installed).
    """
    share = s.find_share(PACKAGE)
    if share is None:
        raise Unmet(f"{PACKAGE} is not installed")
    return sorted(f"{PACKAGE}/{p.parent.name}/{p.stem}" for kind in ("msg", "srv", "action")
                  for p in (share / kind).glob(f"*.{kind}"))


def grade(s: Session) -> None:
    path = scripts.script(s, "script", SCRIPT)
    run = scripts.run_script(s, path, timeout=TIMEOUT)
    scripts.ended(s, "ends", run, "it ends by itself with exit code 0")
    scripts.printed(s, "package", run, package_types(s), f"interface types of {PACKAGE}",
                    f"ros2 interface package {PACKAGE}")
    for check_id, name, _ in SHOWN:
        found = definition_file(s, name)
        if found is None:
            s.record(check_id, False, f"{name} is not installed here", f"{name} is installed",
                     hint="this is a fault of the course's ROS install, not of your script")
            continue
        if not _named(name, found, _commands(path.read_text(encoding="utf-8", errors="replace")), run.stdout):
            s.record(check_id, False, f"your script never names {name} and printed none of its comments: the "
                     "field lines alone do not tell it from another type with the same fields "
                     "(geometry_msgs/msg/Vector3 and Point both hold float64 x, y, z)",
                     f"your script prints the definition of {name}", hint=f"`ros2 interface show {name}` prints it")
            continue
        scripts.printed(s, check_id, run, field_lines(found), f"definition of {name}", f"ros2 interface show {name}",
                        whole_lines=True)


def _commands(script: str) -> str:
    """``script`` without its comments (a whole-line ``# ...`` or a trailing `` # ...``): a type named only in a
    comment is not shown (the independent review of stop 82: the starter's ``# TODO 2: show the definition of
    geometry_msgs/msg/Point.`` kept above ``ros2 interface show geometry_msgs/msg/Vector3`` got full marks)."""
    return "\n".join(re.sub(r"(^|\s)#.*$", "", line) for line in script.splitlines())


def _named(name: str, definition: Path, script: str, stdout: str) -> bool:
    """Whether the run's definition is ``name``'s: the script names the type (``pkg/kind/Name`` or the short
    ``pkg/Name`` ros2 interface show accepts), or the output holds one of the definition's comments (helper
    audit of issue 37: ``ros2 interface show geometry_msgs/msg/Vector3`` printed Point's three field lines)."""
    package, _, base = name.split("/")
    comments = [line.split("#", 1)[1].strip() for line in definition.read_text(encoding="utf-8").splitlines()
                if "#" in line and len(line.split("#", 1)[1].strip()) > 10]
    return name in script or f"{package}/{base}" in script or any(comment in stdout for comment in comments)
