"""Grader for ``workspace-setup`` (seed ch. 5): a colcon workspace the learner built.

Looks at the folder and asks colcon and bash, as the learner's terminal would.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from ros2course.kit import NotGradable
from ros2course.kit import Check, Session, Unmet

#: No node is observed: the checks read the folder and ask colcon and bash.
WINDOW = 0.0

CHECKS = [
    Check("src_folder", "The workspace has a src/ folder", 1, "mkdir -p ros2_tutorial_workspace/src"),
    Check("colcon_reads", "colcon can read the workspace", 1,
          "run 'colcon list' in the workspace and fix what it complains about"),
    Check("built", "colcon build ran and succeeded (build/, install/, log/)", 2,
          "cd into the workspace folder (not src/) and run 'colcon build' until it reports no failed package"),
    # judged whenever install/setup.bash exists, even after a failed build (colcon still writes it)
    Check("sourceable", "install/setup.bash sources cleanly and adds the workspace", 1,
          "run 'source install/setup.bash' from the workspace folder; rebuild if it fails"),
]


def _made_by_colcon(folder: Path) -> bool:
    """True when ``folder`` exists with something colcon put there.

    ros2course itself keeps check logs in ``log/ros2course/``; that alone is
    not evidence that the learner ran colcon.
    """
    return folder.is_dir() and any(entry.name not in ("ros2course", ".ros2course") for entry in folder.iterdir())


#: One line of colcon's ``log/<verb>_<time>/events.log``: ``[time] (package) JobEnded: {'identifier': ..., 'rc': N}``
#: (colcon_core's log event handler writes each event's repr).
_JOB_ENDED = re.compile(r"\((?P<package>[^)]*)\) JobEnded: (?P<data>\{.*\})\s*$")


def failed_packages(events: Path) -> list[str]:
    """``"name (exit code N)"`` for each package whose job in colcon's ``events.log`` ended with rc != 0."""
    try:
        text = events.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return []
    failed = []
    for line in text.splitlines():
        match = _JOB_ENDED.search(line)
        if not match:
            continue
        try:
            data = ast.literal_eval(match.group("data"))
        except (ValueError, SyntaxError):
            continue
        rc = data.get("rc") if isinstance(data, dict) else None
        if rc not in (0, None):
            failed.append(f"{match.group('package')} (exit code {rc})")
    return failed


def grade(s: Session) -> None:
    """Inspect the workspace folder, then ask colcon and bash about it."""
    root = s.workspace_root
    has_src = (root / "src").is_dir()
    listing = sorted(p.name + ("/" if p.is_dir() else "") for p in root.iterdir()
                     if not p.name.startswith(".") and (p.name != "log" or _made_by_colcon(p)))
    entries = ", ".join(listing) or "nothing"
    s.record("src_folder", has_src, f"{root} holds: {entries}", "a src/ folder for the packages")

    # --log-base /dev/null: 'colcon list' must not create log/ itself (colcon's documented way to disable logs)
    # colcon list runs each setup.py: the submission's code, run as the submission (Session.run_colcon)
    proc = s.run_colcon(["--log-base", "/dev/null", "list"])
    packages = proc.stdout.strip().splitlines()
    s.record("colcon_reads", proc.returncode == 0,
             f"'colcon list' exited {proc.returncode}" + (f", {len(packages)} package(s)" if proc.returncode == 0
                                                          else f": {proc.stderr.strip().splitlines()[-1:]}"),
             "'colcon list' exits 0")

    made = {name: _made_by_colcon(root / name) for name in ("build", "install")}
    # colcon keeps one log folder per verb run; a build leaves log/latest_build
    made["log"] = (root / "log" / "latest_build").exists() or any((root / "log").glob("build_*"))
    setup = (root / "install" / "setup.bash").is_file()
    missing = [name + "/" for name, ok in made.items() if not ok] + ([] if setup else ["install/setup.bash"])
    failed = failed_packages(root / "log" / "latest_build" / "events.log")
    if missing:
        observed = "missing: " + ", ".join(missing)
    elif failed:
        observed = ("build/, install/, log/ exist, but the last colcon build failed for " + ", ".join(failed)
                    + " (see log/latest_build/)")
    else:
        observed = "build/, install/, log/ and install/setup.bash exist; the last colcon build succeeded"
    s.record("built", not missing and not failed, observed,
             "what a successful 'colcon build' creates in the workspace folder (LESSONS.md: the build succeeds)")
    if not setup:
        raise Unmet("install/setup.bash does not exist")
    try:
        env = s.overlay()  # what 'source install/setup.bash' makes of the ROS install's environment
    except NotGradable as exc:
        s.record("sourceable", False, exc.message, "'source install/setup.bash' succeeds")
        return
    prefixes = env.get("COLCON_PREFIX_PATH", "").split(":")
    ok = str(root / "install") in prefixes
    s.record("sourceable", ok, f"COLCON_PREFIX_PATH after sourcing: {env.get('COLCON_PREFIX_PATH', '(unset)')}",
             f"it includes {root / 'install'}")
