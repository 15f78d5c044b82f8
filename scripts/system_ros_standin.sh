#!/usr/bin/env bash
# Make a stand-in "system ROS 2 Jazzy" at PREFIX from a ros2course venv that has the
# ROS 2 wheels (pip install 'ros2course[ros]') and the source-built underlay
# (ros2course env --build), so that ros2course's system-ROS path can be tested on
# machines where /opt/ros/jazzy cannot be installed (issue 18).
#
#   scripts/system_ros_standin.sh PREFIX [SOURCE_VENV]     (default SOURCE_VENV: <repo>/.venv)
#   source PREFIX/setup.bash                                 (then: as after source /opt/ros/jazzy/setup.bash)
#
# Layout (thin: symlinks to SOURCE_VENV's files, nothing big is copied; SOURCE_VENV is
# only read, and must stay where it is):
#   PREFIX/opt/ros/jazzy/   what /opt/ros/jazzy holds: one merged prefix (bin, include,
#                           lib, lib/python3.X/site-packages, share with one ament index)
#                           of every file of the venv's ros-* wheels and of the underlay's
#                           packages, plus the prefix-level setup.bash / setup.sh /
#                           local_setup.* / _local_setup_util.py of ament_package (what the
#                           Debian package ros-jazzy-ros-workspace installs), configured
#                           like the Debian build (SKIP_PARENT_PREFIX_PATH, the "system"
#                           python3), and a ros_environment package (ROS_DISTRO=jazzy,
#                           ROS_VERSION=2, ROS_PYTHON_VERSION=3 hooks). Sourcing its
#                           setup.bash runs ament's own machinery: every package's hooks
#                           prepend AMENT_PREFIX_PATH, PATH, LD_LIBRARY_PATH, PYTHONPATH.
#   PREFIX/usr/             what apt puts in /usr on Ubuntu beside ROS: a "system" python3
#                           (bin/python3: a copy of the venv's base interpreter binary, whose
#                           prefix is PREFIX/usr: its standard library is symlinked, its own
#                           site-packages plays /usr/lib/python3/dist-packages and holds the
#                           non-ROS Python packages ROS needs: numpy, yaml, lark, empy,
#                           catkin_pkg, osrf_pycommon, colcon...; so `PREFIX/usr/bin/python3
#                           -m venv --system-site-packages` sees them as on Ubuntu), bin/colcon
#                           (python3-colcon-common-extensions), lib/ros-wheel-libs (the
#                           libraries the wheels bundle in ros_*.libs: tinyxml2, spdlog,
#                           lttng-ust... which Ubuntu has in /usr/lib/x86_64-linux-gnu).
#   PREFIX/setup.bash       the entry point: puts PREFIX/usr where the system would have
#                           it (PATH, LD_LIBRARY_PATH; see "differs" below), then sources
#                           PREFIX/opt/ros/jazzy/setup.bash.
#
# What differs from a real /opt/ros/jazzy on Ubuntu 24.04:
# * Python 3.11 (the venv's interpreter; the wheels are cp311) instead of Ubuntu's 3.12,
#   and the ROS binaries are the PyPI wheels (manylinux, with their bundled libraries
#   and the CMake repairs of shared/ROS_ENV.md) plus the source-built underlay (ros2
#   CLI, launch, rclcpp), not the ROS build farm's .debs; only the packages the course
#   uses are there (no rviz, no demo_nodes, no ros2doctor...).
# * apt's /usr is PREFIX/usr, which the system would search by itself: setup.bash adds
#   PREFIX/usr/bin to PATH (so `python3` is the stand-in's, not /usr/bin/python3) and
#   PREFIX/usr/lib/ros-wheel-libs to LD_LIBRARY_PATH. The "system" python3 is the source
#   venv's base interpreter (its standard library and libpython), not Debian's build of it.
# * CMAKE_PREFIX_PATH: ament's hooks do not set it for /opt/ros/jazzy (CMake finds the
#   prefix from PREFIX/opt/ros/jazzy/bin on PATH; only vendor packages under opt/ add
#   entries). The underlay's packages were built by colcon, whose hooks also prepend the
#   prefix to CMAKE_PREFIX_PATH here.
# * The wheels' CMake files are the source venv's, as `ros2course doctor --fix` repaired
#   them there (shared/ROS_ENV.md): a source venv that was never repaired gives a stand-in
#   whose C++ builds fail the way the unrepaired wheels do.
# * Scripts of bin/ are copies whose "#!" names PREFIX/usr/bin/python3 (Ubuntu: /usr/bin/python3).
# * Files are symlinks into SOURCE_VENV: deleting or rebuilding it breaks the stand-in.
set -euo pipefail
if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $0 PREFIX [SOURCE_VENV]" >&2
  exit 2
fi
REPO="$(cd "$(dirname "$0")/.." && pwd)"
PREFIX="$(mkdir -p "$1" && cd "$1" && pwd)"
SOURCE_VENV="$(cd "${2:-$REPO/.venv}" && pwd)"
if [ ! -x "$SOURCE_VENV/bin/python" ]; then
  echo "$SOURCE_VENV is not a venv (no bin/python)" >&2
  exit 2
fi
# the source venv's own interpreter reads its distributions (and writes nothing there, not even
# bytecode caches); nothing of a sourced ROS may leak in
exec env -u PYTHONPATH -u AMENT_PREFIX_PATH -u ROS_DISTRO PYTHONDONTWRITEBYTECODE=1 "$SOURCE_VENV/bin/python" - "$PREFIX" "$SOURCE_VENV" <<'PY'
import importlib.metadata as md
import json
import os
import re
import shutil
import sys
import sysconfig
from pathlib import Path

prefix, venv = Path(sys.argv[1]), Path(sys.argv[2])
ros = prefix / "opt" / "ros" / "jazzy"
usr = prefix / "usr"
pyver = f"python{sys.version_info.major}.{sys.version_info.minor}"
site = venv / "lib" / pyver / "site-packages"
base_python = Path(getattr(sys, "_base_executable", sys.executable)).resolve()
system_python = usr / "bin" / "python3"
if not (site / "rclpy").is_dir():
    sys.exit(f"{venv} has no ROS 2 wheels (rclpy): pip install 'ros2course[ros]' into it first")
underlay = (venv / "opt" / "ros2course-jazzy" / "current").resolve()
if not (underlay / "ros2course-underlay.json").is_file():
    sys.exit(f"{venv} has no built underlay (opt/ros2course-jazzy/current): run 'ros2course env --build' there")

# start afresh, but only in an empty folder or an earlier stand-in (never PREFIX=/ or $HOME)
if any(prefix.iterdir()) and not (prefix / "standin.json").is_file():
    sys.exit(f"{prefix} is not empty and is not a stand-in made by this script: give a new folder")
for part in ("opt", "usr", "setup.bash", "standin.json"):
    path = prefix / part
    if path.is_symlink() or path.is_file():
        path.unlink()
    elif path.is_dir():
        shutil.rmtree(path)
(prefix / "standin.json").write_text("{}\n")  # the mark of a stand-in (completed at the end)


def norm(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def link(src: Path, dst: Path) -> None:
    dst.parent.mkdir(parents=True, exist_ok=True)
    if dst.is_symlink() or dst.exists():
        dst.unlink()
    dst.symlink_to(src)


SHEBANG = re.compile(rb"^#!\S*python[0-9.]*")


def script(src: Path, dst: Path) -> None:
    """A copy of an executable whose "#!" names the "system" python3 (Ubuntu: /usr/bin/python3)."""
    data = src.read_bytes()
    if data.startswith(b"#!") and SHEBANG.match(data):
        dst.parent.mkdir(parents=True, exist_ok=True)
        dst.write_bytes(SHEBANG.sub(b"#!" + str(system_python).encode(), data, count=1))
        dst.chmod(0o755)
    else:
        link(src, dst)


# --- a "system" python3 whose prefix is PREFIX/usr (Ubuntu: /usr/bin/python3) -----------------
# a copy of the base interpreter's binary (a few kB with a shared libpython, found by its RUNPATH)
# finds its prefix from its own place (the landmark lib/python3.X/os.py): the standard library is
# symlinked there, and its site-packages is ours, not the base interpreter's
(usr / "bin").mkdir(parents=True, exist_ok=True)
shutil.copy2(base_python, usr / "bin" / base_python.name)
if base_python.name != "python3":
    link(Path(base_python.name), system_python)
stdlib = Path(sysconfig.get_path("stdlib"))
for entry in stdlib.iterdir():
    if entry.name not in ("site-packages", "dist-packages"):
        link(entry, usr / "lib" / stdlib.name / entry.name)
include = Path(sysconfig.get_path("include"))
if include.is_dir():
    link(include, usr / "include" / include.name)
libdir = sysconfig.get_config_var("LIBDIR")
for lib in sorted(Path(libdir).glob("libpython3*.so*")) if libdir else []:
    link(lib, usr / "lib" / lib.name)
import subprocess  # noqa: E402

found = subprocess.run([str(system_python), "-I", "-c", "import site, sys; print(sys.prefix); "
                        "print(*site.getsitepackages(), sep='\\n')"],
                       capture_output=True, text=True, check=True).stdout.split()
if Path(found[0]) != usr:
    sys.exit(f"the stand-in python3 takes {found[0]} as its prefix, not {usr}: cannot make a system python3 here")
dist_packages = next((Path(p) for p in found[1:] if p.endswith("/lib/python3/dist-packages")), Path(found[1]))

# --- the wheels: every file of every ros-* distribution, by its place in the venv -------
dists = {norm(d.metadata["Name"]): d for d in md.distributions(path=[str(site)])}
ros_dists = [d for n, d in dists.items() if n.startswith("ros-") and n != "ros-wheels-bootstrapper"]
libs_dir = usr / "lib" / "ros-wheel-libs"
count = 0
for dist in ros_dists:
    for file in dist.files or []:
        src = Path(os.path.normpath(dist.locate_file(file)))
        if "__pycache__" in src.parts or not (src.is_file() or src.is_symlink()):
            continue
        try:
            rel = src.relative_to(site)
            if rel.parts[0].startswith("ros_") and rel.parts[0].endswith(".libs"):
                link(src, libs_dir / rel.name)  # bundled system libraries (Ubuntu: /usr/lib/x86_64-linux-gnu)
            else:
                link(src, ros / "lib" / pyver / "site-packages" / rel)
            count += 1
            continue
        except ValueError:
            pass
        rel = src.relative_to(venv)
        if rel.parts[0] == "lib64":
            rel = Path("lib", *rel.parts[1:])
        (script if rel.parts[0] == "bin" else link)(src, ros / rel)
        count += 1
# the venv's lib64 -> lib (foonathan_memory's exported targets name <prefix>/lib64)
link(Path("lib"), ros / "lib64")

# --- the underlay (ros2 CLI, launch, rclcpp...): merged into the same prefix -----------------
for dirpath, dirnames, filenames in os.walk(underlay):
    here = Path(dirpath)
    rel_dir = here.relative_to(underlay)
    dirnames[:] = [d for d in dirnames if d != "__pycache__"]
    for name in filenames:
        if rel_dir == Path(".") :
            continue  # colcon's prefix-level setup files and stamp: ament's own take their place
        src = here / name
        rel = rel_dir / name
        (script if rel.parts[0] == "bin" else link)(src, ros / rel)
        count += 1

# --- ros_environment: what the real package's environment hooks set ---------------------
env_pkg = ros / "share" / "ros_environment"
(env_pkg / "environment").mkdir(parents=True, exist_ok=True)
hooks = {"1.ros_distro": ("ROS_DISTRO", "jazzy"), "1.ros_version": ("ROS_VERSION", "2"),
         "1.ros_python_version": ("ROS_PYTHON_VERSION", "3")}
for hook, (var, value) in hooks.items():
    (env_pkg / "environment" / f"{hook}.dsv").write_text(f"set;{var};{value}\n")
    (env_pkg / "environment" / f"{hook}.sh").write_text(f"export {var}={value}\n")
(env_pkg / "package.dsv").write_text("".join(f"source;share/ros_environment/environment/{hook}.dsv\n"
                                             for hook in hooks))
index = ros / "share" / "ament_index" / "resource_index" / "packages"
index.mkdir(parents=True, exist_ok=True)
(index / "ros_environment").write_text("")

# --- ament_package's prefix-level setup files, as the Debian build configures them ---------
import ament_package  # the wheels' ament_package (ros-jazzy-ament-package)

templates = Path(ament_package.__file__).parent / "template" / "prefix_level"
subst = {"@CMAKE_INSTALL_PREFIX@": str(ros), "@SKIP_PARENT_PREFIX_PATH@": "1",
         "@ament_package_PYTHON_EXECUTABLE@": str(system_python)}
for name in ("setup.bash", "setup.sh.in", "local_setup.bash", "local_setup.sh.in", "_local_setup_util.py"):
    text = (templates / name).read_text()
    for key, value in subst.items():
        text = text.replace(key, value)
    (ros / name.removesuffix(".in")).write_text(text)

# --- apt's /usr: colcon and the non-ROS Python packages ROS needs, in the "system" python3's site ---
# what the ROS packages need (their Requires-Dist, closed below) and what the underlay's
# Python packages import (launch: osrf_pycommon; ros2cli: argcomplete, packaging, psutil...);
# colcon-common-extensions is python3-colcon-common-extensions on Ubuntu
wanted = [norm(r.split(";")[0].split("[")[0].split(">")[0].split("<")[0].split("=")[0].split("!")[0].strip())
          for d in ros_dists for r in (d.requires or []) if "extra ==" not in r]
wanted += ["osrf-pycommon", "pyyaml", "lark", "empy", "catkin-pkg", "packaging", "psutil", "argcomplete",
           "netifaces", "importlib-metadata", "setuptools", "colcon-common-extensions", "numpy"]
seen: set[str] = set()
while wanted:
    name = wanted.pop()
    if name in seen or name not in dists or name.startswith("ros-"):
        continue
    seen.add(name)
    for req in dists[name].requires or []:
        if "extra ==" in req:
            continue
        wanted.append(norm(re.split(r"[\s;\[<>=!~(]", req.strip(), maxsplit=1)[0]))
for name in sorted(seen):
    dist = dists[name]
    for file in dist.files or []:
        src = Path(os.path.normpath(dist.locate_file(file)))
        if "__pycache__" in src.parts or not (src.is_file() or src.is_symlink()) or src.suffix == ".pth":
            continue
        try:
            link(src, dist_packages / src.relative_to(site))
        except ValueError:
            rel = src.relative_to(venv)
            if rel.parts[0] == "bin":
                script(src, usr / rel)
        count += 1

# --- the entry point ------------------------------------------------------------------
(prefix / "setup.bash").write_text(f"""\
# Stand-in for `source /opt/ros/jazzy/setup.bash` on Ubuntu 24.04 (ros2course, issue 18):
# made by scripts/system_ros_standin.sh from {venv}.
# PREFIX/usr is what apt's /usr holds on Ubuntu; the system would search it by itself:
_r2c_sys_u=""; case $- in *u*) _r2c_sys_u=1; set +u;; esac
export PATH="{usr}/bin${{PATH:+:$PATH}}"
export LD_LIBRARY_PATH="{libs_dir}${{LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}}"
# then the real thing: ament_package's prefix-level setup.bash of the ROS prefix
. "{ros}/setup.bash"
if [ -n "$_r2c_sys_u" ]; then set -u; fi; unset _r2c_sys_u
""")
(prefix / "standin.json").write_text(json.dumps({"source_venv": str(venv), "underlay": str(underlay),
                                                 "python": str(system_python), "base_python": str(base_python), "ros_prefix": str(ros),
                                                 "files": count}, indent=1) + "\n")
print(f"stand-in system ROS 2 Jazzy at {prefix} ({count} files linked from {venv}); "
      f"use: source {prefix}/setup.bash")
PY
