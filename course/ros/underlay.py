"""The ROS 2 underlay: the Jazzy pieces PyPI lacks, built from source on top of the wheels.

What, and the repairs it needs, come from shared/ROS_ENV.md ("Building the
missing ROS pieces from source"); which commits, from
:mod:`ros2course.ros.underlay_pins`. The underlay belongs to the ros2course install: it
lives under ``<venv>/opt/ros2course-jazzy`` (``ROS2COURSE_UNDERLAY`` moves it)::

    <root>/current -> builds/<key>     the only thing ever trusted (a symlink)
    <root>/builds/<key>/               a colcon merged install prefix
    <root>/builds/<key>/ros2course-underlay.json   its stamp (pins, repairs, python)
    <root>/work/                       sources, build/ and colcon logs while building
    <root>/logs/build-<time>.log       the output of every build
    <root>/setup.bash                  the learner's activation script (ros2course.ros.env)
    <root>/sas/...                     the optional sas component, same layout, built on top
    <root>/nav2/...                    the optional nav2 component (nav2 and Gazebo interfaces), same layout

Atomic: a build goes into a fresh ``builds/<key>`` folder; only when colcon
succeeded is the stamp written and ``current`` switched with one
``os.replace`` of a symlink. An interrupted or failed build leaves
``current`` (the earlier working underlay, if any) as it was; leftovers are
removed by the next build. The installed files name their own prefix (colcon's
setup files, console_bridge's CMake config), which is why the prefix is
never renamed after the build: the symlink is.

Cached: the folder name is a hash of the pins, :data:`REPAIRS_VERSION`, the
interpreter and the venv prefix (:func:`cache_key`); when ``current`` points
at a folder with that name and a stamp, :func:`build` returns at once.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import sysconfig
import tarfile
from pathlib import Path

from ros2course.errors import CourseError, ExitStatus
from ros2course.ros.underlay_pins import JAZZY, NAV2, PATCHES, REPAIRS_VERSION, SAS, Pin

#: Environment variable: the underlay's root folder (default ``<sys.prefix>/opt/ros2course-jazzy``).
ROOT_VAR = "ROS2COURSE_UNDERLAY"
#: Environment variable: a folder holding the pinned archives (``<org>--<repo>-<commit>.tar.gz``).
SOURCES_VAR = "ROS2COURSE_ROS_SOURCES"
STAMP = "ros2course-underlay.json"
#: Seconds before a colcon pass is stopped (a cold build takes about 4 min on 2 cores).
BUILD_TIMEOUT = 3600.0
DOWNLOAD_TIMEOUT = 120.0


class UnderlayBuildFailed(CourseError):
    """Building the underlay failed; the one-line message names the step, the package and the log."""

    exit_status = ExitStatus.MISSING_REQUIREMENT


@dataclasses.dataclass(frozen=True)
class Underlay:
    """A built underlay.

    Attributes:
        prefix: the install prefix (resolved ``builds/<key>`` folder).
        stamp: the stamp's content (``key``, ``pins``, ``repairs``, ``python``, ``built``, ``seconds``).
    """

    prefix: Path
    stamp: dict

    @property
    def site_packages(self) -> Path:
        """Where its Python packages are (``lib/python3.X/site-packages``)."""
        return self.prefix / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"

    def commit_of(self, repo: str) -> str | None:
        """The commit ``repo`` (``"ros2cli"``) was built from, per the stamp, or None."""
        for pin in self.stamp.get("pins", []):
            if pin.get("repo") == repo:
                return pin.get("commit")
        return None


@dataclasses.dataclass(frozen=True)
class Component:
    """A set of pins built together into one prefix.

    Attributes:
        name: ``"jazzy"`` (the ROS 2 underlay), ``"sas"`` or ``"nav2"`` (optional, each on top of it).
        pins: what it is built from.
        subdir: its folder under :func:`root` (``""``: the root itself).
        what: how messages name it.
    """

    name: str
    pins: tuple[Pin, ...]
    subdir: str
    what: str


#: The ROS 2 pieces PyPI lacks (built by ``scripts/setup.sh``).
JAZZY_COMPONENT = Component("jazzy", JAZZY, "", "the ROS 2 underlay (ros2 CLI, launch, rclcpp)")
#: SmartArmStack + DQ Robotics for the sas lesson's C++ path (on demand: ``ros2course env --build --with sas``).
SAS_COMPONENT = Component("sas", SAS, "sas", "SmartArmStack (sas) and DQ Robotics C++")
#: The interfaces of the author's Gazebo and nav2 chapters (ros_gz_interfaces, nav2_msgs; on demand:
#: ``ros2course env --build --with nav2``; GitHub issue 40).
NAV2_COMPONENT = Component("nav2", NAV2, "nav2", "the nav2 and Gazebo interfaces (nav2_msgs, ros_gz_interfaces)")
COMPONENTS = {c.name: c for c in (JAZZY_COMPONENT, SAS_COMPONENT, NAV2_COMPONENT)}
#: The optional components, in the order they are built and activated (each on top of the underlay only).
OPTIONAL = tuple(c for c in COMPONENTS.values() if c is not JAZZY_COMPONENT)
#: What a sourced system ROS 2 Jazzy installs instead of the nav2 component (Ubuntu's apt names of the
#: build farm's packages; geographic_msgs and nav_msgs come along as their dependencies).
NAV2_APT_PACKAGES = ("ros-jazzy-ros-gz-interfaces", "ros-jazzy-nav2-msgs")


def root() -> Path:
    """The underlay's root folder (``$ROS2COURSE_UNDERLAY`` or ``<sys.prefix>/opt/ros2course-jazzy``)."""
    override = os.environ.get(ROOT_VAR)
    return Path(override).expanduser().absolute() if override else Path(sys.prefix) / "opt" / "ros2course-jazzy"


def component_root(component: Component) -> Path:
    """Where ``component`` lives (``root()`` for jazzy, ``root()/sas`` for sas)."""
    return root() / component.subdir if component.subdir else root()


def project_mirror() -> Path | None:
    """``../shared/ros-src`` beside this project's checkout, when it holds the archives (CI, course machines)."""
    candidate = Path(__file__).resolve().parents[2].parent / "shared" / "ros-src"
    return candidate if (candidate / "SOURCES.md").is_file() else None


def default_sources() -> Path | None:
    """Where archives come from: ``$ROS2COURSE_ROS_SOURCES``, else :func:`project_mirror`, else None (GitHub)."""
    given = os.environ.get(SOURCES_VAR)
    if given:
        return Path(given).expanduser().absolute()
    return project_mirror()


def cache_key(pins: tuple[Pin, ...] = JAZZY, below: str = "") -> str:
    """16 hex digits naming one build: pins, repairs version, interpreter version and prefix.

    ``below``: the key of the component it is built on (sas on jazzy), so that a
    rebuilt underlay invalidates what was built on top of it.
    """
    data = {
        "pins": [dataclasses.asdict(pin) for pin in pins],
        "repairs": REPAIRS_VERSION,
        "python": list(sys.version_info[:2]),
        "prefix": sys.prefix,
        "below": below,
    }
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()[:16]


def current(base: Path | None = None) -> Underlay | None:
    """The underlay ``current`` points at, if it has a readable stamp; never raises."""
    link = (base or root()) / "current"
    try:
        prefix = link.resolve(strict=True)
        stamp = json.loads((prefix / STAMP).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return Underlay(prefix, stamp) if isinstance(stamp, dict) else None


def up_to_date(base: Path | None = None, pins: tuple[Pin, ...] = JAZZY, below: str = "") -> bool:
    """True when ``current`` is the build of these pins (same :func:`cache_key`)."""
    found = current(base)
    return found is not None and found.stamp.get("key") == cache_key(pins, below)


def built(component: Component) -> Underlay | None:
    """The current build of ``component`` if it is up to date (pins, repairs, what it builds on), else None."""
    below = ""
    if component is not JAZZY_COMPONENT:
        under = built(JAZZY_COMPONENT)
        if under is None:
            return None
        below = under.stamp["key"]
    found = current(component_root(component))
    return found if found is not None and found.stamp.get("key") == cache_key(component.pins, below) else None


# --- What a build needs --------------------------------------------------------


EIGEN_INCLUDE = Path("/usr/include/eigen3")


def sas_missing_prerequisites() -> list[tuple[str, str]]:
    """What the sas component needs beyond :func:`missing_prerequisites` (shared/ROS_ENV.md): ``[(what, hint)]``."""
    missing = []
    if not (EIGEN_INCLUDE / "Eigen" / "Dense").is_file():
        missing.append(("no Eigen 3 headers (/usr/include/eigen3)", "apt-get install libeigen3-dev"))
    if importlib.util.find_spec("pybind11") is None:
        missing.append(("no pybind11", "pip install 'ros2course[sas]'"))
    if importlib.util.find_spec("dqrobotics") is None:
        missing.append(("no dqrobotics (Python)", "pip install 'ros2course[sas]'"))
    return missing


def nav2_missing_prerequisites(prefix: Path | None = None) -> list[tuple[str, str]]:
    """What the nav2 component needs beyond :func:`missing_prerequisites`: ``[(what, hint)]``.

    nav2_msgs' CMakeLists finds ``nav_msgs``, which is not built here: it is the PyPI
    wheel ``ros-jazzy-nav-msgs`` (the ``nav2`` extra), found through its CMake config
    under the wheels' prefix (``prefix``, default ``sys.prefix``).
    """
    config = (prefix or Path(sys.prefix)) / "share" / "nav_msgs" / "cmake" / "nav_msgsConfig.cmake"
    if not config.is_file():
        return [("no nav_msgs (the ros-jazzy-nav-msgs wheel; nav2_msgs needs it)", "pip install 'ros2course[nav2]'")]
    return []


def component_missing_prerequisites(component: Component) -> list[tuple[str, str]]:
    """What ``component`` needs beyond :func:`missing_prerequisites` (``[]`` for jazzy): ``[(what, hint)]``."""
    if component is SAS_COMPONENT:
        return sas_missing_prerequisites()
    if component is NAV2_COMPONENT:
        return nav2_missing_prerequisites()
    return []


def missing_archives(pins: tuple[Pin, ...], mirror: Path) -> list[str]:
    """The archive files (of ``pins`` and their patches) that the sources folder ``mirror`` lacks, in pin order.

    Checked before a build starts, so that a mirror older than the pins (e.g. a
    ``shared/ros-src`` without the nav2 archives) fails in one line naming the
    first missing file, not half-way through unpacking. Names are relative to
    ``mirror`` (``sas/<archive>`` for a pin with a ``mirror_dir``).
    """
    wanted = [f"{pin.mirror_dir}/{pin.archive_name}" if pin.mirror_dir else pin.archive_name for pin in pins]
    wanted += [name for pin in pins for name in pin.patches]
    return [name for name in dict.fromkeys(wanted) if not (mirror / name).is_file()]


def missing_prerequisites() -> list[tuple[str, str]]:
    """What this machine lacks to build the underlay: ``[(what, hint)]``, empty when all is there.

    Rules from shared/ROS_ENV.md: a C++ compiler and cmake; a shared libpython
    (``Py_ENABLE_SHARED``; the wheels' rcl needs libpython symbols, so
    librclcpp must link it); ``osrf_pycommon`` (launch imports it); ``patch``;
    colcon in this interpreter.
    """
    missing = []
    if not (shutil.which("c++") or shutil.which("g++")):
        missing.append(("no C++ compiler (c++/g++)", "apt-get install g++"))
    if not shutil.which("cmake"):
        missing.append(("no cmake", "apt-get install cmake"))
    if not shutil.which("patch"):
        missing.append(("no patch", "apt-get install patch"))
    if not sysconfig.get_config_var("Py_ENABLE_SHARED"):
        missing.append(("no shared libpython (this Python was built without --enable-shared)",
                        "use a Python with libpython3.X.so (Debian's python3, or pyenv with "
                        "PYTHON_CONFIGURE_OPTS=--enable-shared)"))
    if importlib.util.find_spec("osrf_pycommon") is None:
        missing.append(("no osrf_pycommon (launch imports it)", "pip install osrf-pycommon"))
    if not (Path(sys.executable).parent / "colcon").is_file() and not shutil.which("colcon"):
        missing.append(("no colcon", "pip install colcon-common-extensions"))
    return missing


def libpython_link_flags() -> str:
    """``CMAKE_SHARED_LINKER_FLAGS`` that make every shared library carry libpython.

    shared/ROS_ENV.md: the wheels' ``librcl.so`` needs ``*__rosidl_generator_py.so``,
    which leave libpython symbols unresolved, so any C++ executable fails to
    link (``undefined reference to _Py_Dealloc``) unless librclcpp carries libpython.
    """
    libdir = sysconfig.get_config_var("LIBDIR")
    version = sysconfig.get_config_var("LDVERSION") or f"{sys.version_info.major}.{sys.version_info.minor}"
    return f"-L{libdir} -Wl,-rpath,{libdir} -Wl,--no-as-needed -lpython{version} -Wl,--as-needed"


# --- Sources -------------------------------------------------------------------


def _fetch(name: str, url: str, mirror: Path | None, dest: Path) -> Path:
    """``dest/name`` from the mirror folder, or downloaded from ``url`` when there is no mirror."""
    target = dest / name
    if mirror is not None:
        source = mirror / name
        if not source.is_file():
            raise UnderlayBuildFailed(f"{name} is not in the sources folder {mirror}",
                                      f"put it there, or unset {SOURCES_VAR} to download from GitHub")
        return source
    partial = target.with_suffix(".part")
    try:
        import urllib.request  # noqa: PLC0415 - 10 ms of import every check would pay; only a download needs it

        with urllib.request.urlopen(url, timeout=DOWNLOAD_TIMEOUT) as response, open(partial, "wb") as out:
            shutil.copyfileobj(response, out)
    except OSError as exc:
        raise UnderlayBuildFailed(f"downloading {url} failed ({exc})",
                                  f"check the network, or set {SOURCES_VAR} to a folder with the archives") from exc
    os.replace(partial, target)
    return target


def _unpack(archive: Path, pin: Pin, src: Path) -> Path:
    """Unpack ``archive`` into ``src``; return the pin's top folder. Rejects unsafe members."""
    try:
        with tarfile.open(archive, "r:gz") as tar:
            for member in tar.getmembers():
                if not member.name.startswith(pin.top + "/") and member.name != pin.top:
                    raise UnderlayBuildFailed(f"{archive.name}: member {member.name!r} is outside {pin.top}/",
                                              "the archive is not the pinned commit's; replace it")
            tar.extractall(src, filter="data") if hasattr(tarfile, "data_filter") else tar.extractall(src)
    except (tarfile.TarError, OSError, EOFError) as exc:
        raise UnderlayBuildFailed(f"{archive.name} cannot be unpacked ({exc})",
                                  "the archive is damaged: fetch it again") from exc
    top = src / pin.top
    if not top.is_dir():
        raise UnderlayBuildFailed(f"{archive.name} has no folder {pin.top}/", "the archive is not the pinned commit's")
    return top


def _ignore_unused(top: Path, pin: Pin) -> list[str]:
    """Put ``COLCON_IGNORE`` in every package of ``top`` that ``pin.packages`` does not list.

    Returns the package folders kept (relative, ``"."`` for the top folder).
    """
    if pin.packages is None or pin.packages == (".",):
        return ["."]
    kept = []
    for manifest in sorted(top.rglob("package.xml")):
        rel = manifest.parent.relative_to(top).as_posix() or "."
        if rel in pin.packages:
            kept.append(rel)
        else:
            (manifest.parent / "COLCON_IGNORE").touch()
    if "." in pin.packages and (top / "CMakeLists.txt").is_file():
        kept.append(".")
    absent = sorted(set(pin.packages) - set(kept))
    if absent:
        raise UnderlayBuildFailed(f"{pin.org}/{pin.repo}@{pin.commit[:8]} has no package {absent[0]}",
                                  "course/ros/underlay_pins.py names a package the archive does not hold")
    return kept


def _apply_patch(name: str, top: Path, mirror: Path | None, dest: Path, log) -> None:
    patch = PATCHES[name]
    path = _fetch(name, patch.url, mirror, dest)
    log.write(f"\n$ patch -p1 -d {top} < {path}   # {patch.why}\n".encode())
    log.flush()
    proc = subprocess.run(["patch", "-p1", "--forward", "-d", str(top), "-i", str(path)], stdout=log,
                          stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, check=False)
    if proc.returncode != 0:
        raise UnderlayBuildFailed(f"applying {name} to {top.name} failed", "the patch no longer fits the pinned commit")


def prepare_sources(work: Path, mirror: Path | None, log, pins: tuple[Pin, ...] = JAZZY) -> Path:
    """Unpack every pin into ``work/src`` (fresh), ignore unused packages, apply patches.

    Args:
        work: scratch folder (``src``, ``archives`` are made in it).
        mirror: folder of archives, or None to download from GitHub.
        log: a binary file receiving what was done.

    Returns:
        the ``src`` folder.

    Raises:
        UnderlayBuildFailed: a missing, damaged or unexpected archive, or a patch that fails.
    """
    src = work / "src"
    archives = work / "archives"
    shutil.rmtree(src, ignore_errors=True)
    src.mkdir(parents=True)
    archives.mkdir(parents=True, exist_ok=True)
    for pin in pins:
        folder = mirror / pin.mirror_dir if mirror is not None and pin.mirror_dir else mirror
        archive = _fetch(pin.archive_name, pin.url, folder, archives)
        top = _unpack(archive, pin, src)
        if pin.into is not None:  # a git submodule of another pin
            repo, _, path = pin.into.partition("/")
            owner = next((p for p in pins if p.repo == repo), None)
            if owner is None:
                raise UnderlayBuildFailed(f"{pin.repo} goes into {repo}, which is not pinned")
            target = src / owner.top / path
            shutil.rmtree(target, ignore_errors=True)
            target.parent.mkdir(parents=True, exist_ok=True)
            top.rename(target)
            log.write(f"unpacked {archive.name} into {owner.top}/{path}\n".encode())
            continue
        kept = _ignore_unused(top, pin)
        log.write(f"unpacked {archive.name}: building {', '.join(kept)}\n".encode())
        for name in pin.patches:
            _apply_patch(name, top, mirror, archives, log)
    return src


# --- Building ------------------------------------------------------------------


def installed_size(path: Path) -> int:
    """Bytes of the regular files under ``path`` (symlinks not followed)."""
    total = 0
    for dirpath, _dirs, files in os.walk(path):
        for name in files:
            with contextlib.suppress(OSError):
                total += os.lstat(os.path.join(dirpath, name)).st_size
    return total
