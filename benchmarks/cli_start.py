"""Start time of the commands a learner types most: ``--help``, ``list``, ``show``, ``hint`` (a script, not a test).

Each command runs ``--runs`` times through the installed console script in a
fresh initialised workspace; the table gives median and min wall seconds.
Issue 13's goal: ``--help`` and ``list`` under 0.25 s on the 2-core machine.

    python benchmarks/cli_start.py [--runs 15] [--json]
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rich.console import Console
from rich.table import Table

GOAL = 0.25
COMMANDS = (["--help"], ["list"], ["show", "terminal-basics"], ["hint", "terminal-basics"])


def timed(argv: list[str], cwd: Path, runs: int) -> list[float]:
    """Wall seconds of ``runs`` runs of ``argv`` (output discarded; a failing run raises)."""
    out = []
    for _ in range(runs):
        begin = time.perf_counter()
        subprocess.run(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        out.append(time.perf_counter() - begin)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=15)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    script = Path(sys.executable).parent / "ros2course"
    root = Path(tempfile.mkdtemp(prefix="ros2course-cli-start-"))
    try:
        subprocess.run([str(script), "init", "ws"], cwd=root, check=True, stdout=subprocess.DEVNULL)
        rows = []
        for command in COMMANDS:
            times = timed([str(script), *command], root / "ws", args.runs)
            rows.append({"command": " ".join(command), "median": statistics.median(times), "min": min(times)})
    finally:
        shutil.rmtree(root, ignore_errors=True)
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    table = Table(title=f"ros2course start time (seconds, {args.runs} runs; goal {GOAL} s for --help and list)",
                  title_justify="left")
    for column in ("command", "median", "min"):
        table.add_column(column, justify="left" if column == "command" else "right")
    for row in rows:
        table.add_row(row["command"], f"{row['median']:.3f}", f"{row['min']:.3f}")
    Console().print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
