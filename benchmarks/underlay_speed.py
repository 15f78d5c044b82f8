"""Set-up time of the ROS 2 underlay: cold build, warm (cached) no-op, installed size.

Builds the pinned underlay (course/ros/underlay_pins.py) into a temporary root, as
``ros2course env --build`` does, then asks again with the same pins (the cache:
nothing is built), and prints the times and the installed size. The
project's own underlay is not touched. A script, not a timed test::

    python benchmarks/underlay_speed.py [--sources ../shared/ros-src] [--json] [--keep]

Also prints the warm time of the real command a learner runs again
(``ros2course env --build`` on the project's underlay, when it is built).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from ros2course.ros import env as env_mod  # noqa: E402
from ros2course.ros import underlay, underlay_build  # noqa: E402


def main() -> int:
    """Run the measurements; 0 when both builds succeeded."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sources", type=Path, default=None, help="folder of the pinned archives")
    parser.add_argument("--json", action="store_true", help="print only a JSON object")
    parser.add_argument("--keep", action="store_true", help="keep the temporary underlay")
    args = parser.parse_args()
    env_mod.activate_process(underlay=False)
    base = Path(tempfile.mkdtemp(prefix="ros2course-underlay-bench-"))
    say = (lambda line: None) if args.json else (lambda line: print(f"  {line}", file=sys.stderr))
    try:
        begin = time.monotonic()
        made, built = underlay_build.build(args.sources, force=True, progress=say, base=base)
        cold = time.monotonic() - begin
        begin = time.monotonic()
        _, rebuilt = underlay_build.build(args.sources, progress=say, base=base)
        warm = time.monotonic() - begin
        size = underlay.installed_size(made.prefix)
        result = {"cold_s": round(cold, 1), "warm_s": round(warm, 3), "rebuilt_when_warm": rebuilt,
                  "installed_mb": round(size / 1e6, 1), "cores": os.cpu_count()}
        if underlay.up_to_date():
            cli = Path(sys.executable).parent / "ros2course"
            begin = time.monotonic()
            subprocess.run([str(cli), "env", "--build"], check=True, capture_output=True)
            result["cli_warm_s"] = round(time.monotonic() - begin, 2)
    finally:
        if not args.keep:
            shutil.rmtree(base, ignore_errors=True)
    if args.json:
        print(json.dumps(result))
    else:
        print(f"cold build          {result['cold_s']:8.1f} s   ({result['cores']} cores)")
        print(f"warm (same pins)    {result['warm_s']:8.3f} s   rebuilt: {result['rebuilt_when_warm']}")
        if "cli_warm_s" in result:
            print(f"ros2course env --build, warm  {result['cli_warm_s']:.2f} s (interpreter start included)")
        print(f"installed size      {result['installed_mb']:8.1f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
