"""Time the intake of a Canvas download (issue 39: 300 students in < 30 s on 2 cores).

    python benchmarks/intake_speed.py                 # 300 students, ~10 files each
    python benchmarks/intake_speed.py --count 50      # smaller
    python benchmarks/intake_speed.py --json          # the figures as JSON only

The download: a synthetic Canvas "Download Submissions" zip (member names
``<lastfirst>_<userid>_<submissionid>_<file>``, every fifth one ``_LATE_``), each student's member a small
workspace zip of ``--files`` files (``src/<pkg>/package.xml``, ``setup.py``, nodes of a few KiB). Timed:
:func:`ros2course.batch.intake.intake` from the zip to ``staging/`` (every workspace extracted with
:mod:`ros2course.batch.archive`'s checks) and ``intake.json`` written. Building the zip is not timed.
"""

from __future__ import annotations

import argparse
import io
import json
import random
import sys
import tempfile
import time
import zipfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from ros2course.batch.intake import intake  # noqa: E402

TARGET_S = 30.0


def workspace_zip(rng: random.Random, student: int, files: int) -> bytes:
    """A student's workspace zip: ``files`` files under ``ws/src/pkg_<n>/``, a few KiB each."""
    buf = io.BytesIO()
    pkg = f"pkg_{student}"
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.writestr(f"ws/src/{pkg}/package.xml", f"<package format='3'><name>{pkg}</name></package>\n")
        zf.writestr(f"ws/src/{pkg}/setup.py", "from setuptools import setup\nsetup()\n")
        for i in range(max(files - 2, 0)):
            body = "".join(f"value_{j} = {rng.randint(0, 10**6)}\n" for j in range(rng.randint(50, 200)))
            zf.writestr(f"ws/src/{pkg}/{pkg}/node_{i}.py", body)
    return buf.getvalue()


def canvas_download(path: Path, count: int, files: int, seed: int = 1) -> None:
    """Write a Canvas download of ``count`` students to ``path``."""
    rng = random.Random(seed)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED) as zf:
        for n in range(count):
            late = "LATE_" if n % 5 == 0 else ""
            zf.writestr(f"student{n:04d}_{late}{100000 + n}_{900000 + n}_workspace.zip",
                        workspace_zip(rng, n, files))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=300, help="students (default 300)")
    parser.add_argument("--files", type=int, default=10, help="files per workspace (default 10)")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON only")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="intake-speed-") as tmp:
        download = Path(tmp) / "submissions.zip"
        canvas_download(download, args.count, args.files)
        start = time.perf_counter()
        report = intake(download, "canvas", Path(tmp) / "out" / "intake")
        seconds = time.perf_counter() - start
        figures = {"students": args.count, "files_per_student": args.files,
                   "download_bytes": download.stat().st_size, "taken": len(report.taken),
                   "not_taken": len(report.problems), "seconds": round(seconds, 3), "target_s": TARGET_S,
                   "ok": seconds < TARGET_S and len(report.taken) == args.count}
    if args.json:
        print(json.dumps(figures))
    else:
        print(f"intake of a Canvas download: {figures['students']} students x {figures['files_per_student']} files "
              f"({figures['download_bytes'] / 1e6:.1f} MB): {figures['seconds']:.2f} s "
              f"(target < {TARGET_S:g} s), {figures['taken']} taken, {figures['not_taken']} not")
    return 0 if figures["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
