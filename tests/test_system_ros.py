"""ros2course on a sourced "system" ROS 2 Jazzy, through scripts/setup.sh's system path (issue 18).

No system ROS can be installed here, so scripts/system_ros_standin.sh builds a
stand-in of /opt/ros/jazzy (plus what apt puts in /usr beside it) from a source
venv holding the ROS wheels and the source-built underlay: ament's own
prefix-level setup.bash sets AMENT_PREFIX_PATH, PATH, LD_LIBRARY_PATH,
PYTHONPATH, ROS_DISTRO... as on Ubuntu, and apt's Python packages belong to a
"system" python3 (PREFIX/usr/bin/python3), not to PYTHONPATH. With it sourced in a clean bash,
scripts/setup.sh makes a fresh venv with ros2course *without* the ``ros``
extra (its system-ROS branch), and the references of print-forever-node
(Python) and cpp-node (C++, rclcpp) get full marks from ``ros2course check``.

The source venv: ``$ROS2COURSE_STANDIN_SOURCE``, else the repository's .venv
(in CI, the full ROS venv). Skipped when it has no wheels or no underlay.
About 1.5-2 min here (2 cores, busy): the stand-in 4-7 s, setup.sh 40-45 s (pip
from its cache, the test and dask extras), the two checks 15-25 s and 35-40 s.
"""

from __future__ import annotations

import itertools
import json
import os
import shlex
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

#: colcon builds C++: never beside each other (conftest.cpu_exclusive)
pytestmark = [pytest.mark.ros, pytest.mark.usefixtures("cpu_exclusive"), pytest.mark.timeout(900)]

REPO = Path(__file__).resolve().parents[1]
STANDIN = REPO / "scripts" / "system_ros_standin.sh"
SOLUTIONS = REPO / "solutions" / "src"
#: lesson id -> the reference packages to copy into the workspace (its lesson.yaml `packages:`)
LESSONS = {"print-forever-node": ["python_package_with_a_node"], "cpp-node": ["cpp_package_with_a_node"]}
#: what the clean bash keeps of this process's environment (pip's cache and configuration, proxies)
KEEP = ("HOME", "USER", "LANG", "LC_ALL", "TMPDIR", "ROS2COURSE_CACHE_DIR", "ROS2COURSE_ROS_SOURCES",
        "PIP_INDEX_URL", "PIP_EXTRA_INDEX_URL", "PIP_FIND_LINKS", "PIP_CONFIG_FILE", "PIP_CACHE_DIR",
        "XDG_CACHE_HOME", "XDG_CONFIG_HOME", "HTTP_PROXY", "HTTPS_PROXY", "NO_PROXY", "http_proxy",
        "https_proxy", "no_proxy")


def _source_venv() -> tuple[Path, str | None]:
    """The venv the stand-in is made from (``$ROS2COURSE_STANDIN_SOURCE`` or ``<repo>/.venv``) and why not, if unusable."""
    given = os.environ.get("ROS2COURSE_STANDIN_SOURCE")
    venv = Path(given).expanduser().absolute() if given else REPO / ".venv"
    pyver = f"python{sys.version_info.major}.{sys.version_info.minor}"
    if not (venv / "lib" / pyver / "site-packages" / "rclpy").is_dir():
        return venv, (f"the stand-in's source venv {venv} has no ROS 2 wheels (rclpy for {pyver}); "
                      "set ROS2COURSE_STANDIN_SOURCE to a venv made by scripts/setup.sh")
    if not (venv / "opt" / "ros2course-jazzy" / "current" / "ros2course-underlay.json").is_file():
        return venv, f"the stand-in's source venv {venv} has no built underlay (ros2course env --build)"
    return venv, None


SOURCE_VENV, SKIP_REASON = _source_venv()
# skipped before the CPU lock is taken (a skip must not wait for the CPU lock)
pytestmark.insert(0, pytest.mark.skipif(SKIP_REASON is not None, reason=SKIP_REASON or ""))


@pytest.fixture(scope="module")
def source_venv() -> Path:
    """The venv the stand-in is made from: ``$ROS2COURSE_STANDIN_SOURCE`` or ``<repo>/.venv``."""
    return SOURCE_VENV


def _clean_env(tmp_path: Path) -> dict[str, str]:
    """A login-like environment: nothing of this process's ROS activation (conftest activates the wheels)."""
    env = {name: os.environ[name] for name in KEEP if name in os.environ}
    env["PATH"] = "/usr/local/bin:/usr/bin:/bin"
    env["COLUMNS"] = "200"
    env.setdefault("HOME", str(tmp_path))
    return env


def test_full_marks_through_system_ros(source_venv: Path, tmp_path: Path) -> None:
    prefix, venv, ws = tmp_path / "system-ros", tmp_path / "venv", tmp_path / "ws"
    times = {}

    begin = time.monotonic()
    made = subprocess.run(["bash", str(STANDIN), str(prefix), str(source_venv)], capture_output=True, text=True,
                          env=_clean_env(tmp_path), timeout=300, check=False)
    times["stand-in"] = time.monotonic() - begin
    assert made.returncode == 0, made.stdout + made.stderr
    assert (prefix / "opt" / "ros" / "jazzy" / "setup.bash").is_file()

    copies = "\n".join(f"cp -r {shlex.quote(str(SOLUTIONS / pkg))} {shlex.quote(str(ws / 'src'))}/"
                       for packages in LESSONS.values() for pkg in packages)
    checks = "\n".join(f"ros2course check {lesson} --json > {shlex.quote(str(tmp_path / (lesson + '.json')))} "
                       f"|| echo \"check {lesson}: exit $?\"; echo \"TIME {lesson} $(( $(date +%s%N) / 1000000 ))\""
                       for lesson in LESSONS)
    script = f"""set -euo pipefail
source {shlex.quote(str(prefix / 'setup.bash'))}
echo "ROS_DISTRO=$ROS_DISTRO AMENT_PREFIX_PATH=$AMENT_PREFIX_PATH"
echo "TIME start $(( $(date +%s%N) / 1000000 ))"
VENV={shlex.quote(str(venv))} bash {shlex.quote(str(REPO / 'scripts' / 'setup.sh'))}
echo "TIME setup $(( $(date +%s%N) / 1000000 ))"
source {shlex.quote(str(venv / 'bin' / 'activate'))}
ros2course init {shlex.quote(str(ws))}
{copies}
find {shlex.quote(str(ws / 'src'))} \\( -name __pycache__ -o -name '*.egg-info' \\) -prune -exec rm -rf {{}} +
cd {shlex.quote(str(ws))}
ros2course doctor || true
echo "TIME doctor $(( $(date +%s%N) / 1000000 ))"
# as on Ubuntu, apt's Python packages are the system python3's, not on PYTHONPATH: a venv made
# without --system-site-packages does not see lark, which launch imports
python3 -m venv --without-pip {shlex.quote(str(tmp_path / 'plain-venv'))}
if {shlex.quote(str(tmp_path / 'plain-venv' / 'bin' / 'python'))} -c 'import launch' 2>/dev/null; then
  echo "PLAIN VENV IMPORTS LAUNCH"
fi
{checks}
"""
    run = subprocess.run(["bash", "-c", script], capture_output=True, text=True, env=_clean_env(tmp_path),
                         timeout=780, check=False, stdin=subprocess.DEVNULL)
    log = run.stdout + run.stderr
    stamps = [line.split() for line in run.stdout.splitlines() if line.startswith("TIME ")]
    for (_, _, before), (_, name, after) in itertools.pairwise(stamps):
        times[name] = (int(after) - int(before)) / 1000
    print(f"wall times (s): { {k: round(v, 1) for k, v in times.items()} }\n{log[-4000:]}")
    assert run.returncode == 0, log[-6000:]
    # setup.sh took its system-ROS branch: ros2course without the `ros` extra, no ROS of its own in the venv
    assert "using the sourced ROS 2 jazzy" in run.stdout, log[-6000:]
    assert "system install, distro jazzy" in run.stdout, log[-6000:]
    assert "PLAIN VENV IMPORTS LAUNCH" not in run.stdout, "the stand-in leaks apt's Python packages into every venv"
    pyver = f"python{sys.version_info.major}.{sys.version_info.minor}"
    assert not (venv / "lib" / pyver / "site-packages" / "rclpy").exists()
    assert not (venv / "opt" / "ros2course-jazzy").exists()
    for lesson in LESSONS:
        out = tmp_path / f"{lesson}.json"
        assert out.is_file(), log[-6000:]
        result = json.loads(out.read_text())
        assert result["status"] == "passed" and result["score"] == result["max_score"] > 0, \
            json.dumps(result, indent=1)[:6000]
    # the Python node was installed by the system colcon for the system python3 (Ubuntu: /usr/bin/python3)
    node = ws / "install" / "python_package_with_a_node" / "lib" / "python_package_with_a_node" / "print_forever_node"
    if node.is_file():
        shebang = node.read_text(errors="replace").splitlines()[0]
        assert str(source_venv) not in shebang and str(venv) not in shebang, shebang
    shutil.rmtree(ws / "build", ignore_errors=True)
