"""Grader for ``workspace-setup`` (seed ch. 5): a colcon workspace the learner built.

Looks at the folder and asks colcon and bash, as the learner's terminal would.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from course.build import colcon_command, overlay_env
from course.errors import NotGradable
from course.grading import Check, GradingSession

#: No node is observed: the checks read the folder and ask colcon and bash.
WINDOW = 0.0

CHECKS = [
    Check("src_folder", "The workspace has a src/ folder", 1, "mkdir -p ros2_tutorial_workspace/src"),
    Check("colcon_reads", "colcon can read the workspace", 1,
          "run 'colcon list' in the workspace and fix what it complains about"),
    Check("built", "colcon build was run (build/, install/, log/)", 2,
          "cd into the workspace folder (not src/) and run 'colcon build'"),
    Check("sourceable", "install/setup.bash sources cleanly and adds the workspace", 1,
          "run 'source install/setup.bash' from the workspace folder; rebuild if it fails"),
]


def _made_by_colcon(folder: Path) -> bool:
    """True when ``folder`` exists with something colcon put there.

    ros2course itself keeps check logs in ``log/ros2course/``; that alone is
    not evidence that the learner ran colcon.
    """
    return folder.is_dir() and any(entry.name not in ("ros2course", ".ros2course") for entry in folder.iterdir())


def grade(s: GradingSession) -> None:
    """Inspect the workspace folder, then ask colcon and bash about it."""
    root = s.workspace_root
    has_src = (root / "src").is_dir()
    listing = sorted(p.name + ("/" if p.is_dir() else "") for p in root.iterdir()
                     if not p.name.startswith(".") and (p.name != "log" or _made_by_colcon(p)))
    entries = ", ".join(listing) or "nothing"
    s.record("src_folder", has_src, f"{root} holds: {entries}", "a src/ folder for the packages")

    # --log-base /dev/null: 'colcon list' must not create log/ itself (colcon's documented way to disable logs)
    proc = subprocess.run([*colcon_command(s.base_env), "--log-base", "/dev/null", "list"], cwd=root, env=s.base_env, capture_output=True,
                          text=True, timeout=120, check=False, stdin=subprocess.DEVNULL)
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
    s.record("built", not missing, "missing: " + ", ".join(missing) if missing else
             "build/, install/, log/ and install/setup.bash exist", "what 'colcon build' creates in the workspace folder")
    if not setup:
        s.skip_remaining("install/setup.bash does not exist")
        return
    try:
        env = overlay_env(root, s.base_env)
    except NotGradable as exc:
        s.record("sourceable", False, exc.message, "'source install/setup.bash' succeeds")
        return
    prefixes = env.get("COLCON_PREFIX_PATH", "").split(":")
    ok = str(root / "install") in prefixes
    s.record("sourceable", ok, f"COLCON_PREFIX_PATH after sourcing: {env.get('COLCON_PREFIX_PATH', '(unset)')}",
             f"it includes {root / 'install'}")
