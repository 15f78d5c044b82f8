"""Keeping a submission's code away from the grader: namespaces, an unprivileged uid, a process limit.

Batch grading (``ros2course grade``, its Dask executor and ``ros2course
gradescope``) runs every submission in a *job*; this module gives the job its
walls, after the model of PrairieLearn's external grader and Exercism's test
runners (one container per submission, an unprivileged user, read-only course
files, no network, a PID limit), built from Linux primitives instead of Docker:

* **namespaces** (``unshare``, util-linux): a network namespace with only
  loopback, a mount namespace and a PID namespace whose init is ``dumb-init``
  (a maintained minimal init, from PyPI: it reaps orphans and, being PID 1,
  takes every process of the namespace with it when the job ends, whatever
  their session, process group or environment);
* **mounts** inside it (:func:`prelude`): a private ``/dev/shm``, ``/tmp``,
  ``/var/tmp`` and ``/run/lock``; the other submissions, the submissions
  folder, OUTDIR, the reference solutions and the grader's home hidden under
  empty tmpfs mounts; the course, the venv, the Python and ROS installs
  bound read-only (those inside a hidden folder are bound back, read-only);
* **an unprivileged identity** for everything that comes from the
  submission (colcon, which runs ``setup.py`` and CMake code, sourcing its
  ``install/setup.bash``, every learner process): :func:`command` wraps a
  command line so that it joins the job's ``pids`` cgroup, gets
  ``RLIMIT_NPROC`` and then runs under ``setpriv --reuid/--regid
  --clear-groups --no-new-privs`` with no capabilities. The grader itself (the
  worker) stays root inside the namespaces: it can still signal and reap the
  learner's processes, and they can neither signal, trace nor write it. The
  root side of the wrapper runs with a minimal environment; the learner's
  environment (which a submission controls through its ``setup.bash``: think
  ``LD_PRELOAD``) is applied only after the drop, by ``env -i``.

What the machine cannot give is listed, one protection at a time, in the
``isolation`` record of every result (:class:`Isolation`), and
``--require-isolation`` refuses to grade without all of it.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import re
import secrets
import shlex
import shutil
import stat
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

from ros2course.lesson.catalog import content_root
from ros2course.ros import env as env_mod

#: Names of the protections a job can have (keys of :attr:`Isolation.protections`).
NETWORK = "network namespace"
MOUNTS = "mount namespace"
PIDNS = "pid namespace"
UID = "unprivileged uid"
PIDS_LIMIT = "process limit"
PROTECTIONS = (NETWORK, MOUNTS, PIDNS, UID, PIDS_LIMIT)

#: Default number of tasks (processes and threads) a submission may have at once; a
#: correct node with Fast DDS has about 15, a colcon build about 30.
DEFAULT_PIDS_LIMIT = 256
#: First uid/gid of the range submissions run as (one fresh uid per job, never a real user's).
UID_BASE = 1_900_000_000
UID_SPAN = 90_000_000
#: PATH of the root side of the wrapper (its environment is otherwise empty).
SAFE_PATH = "/usr/sbin:/usr/bin:/sbin:/bin"

def fastdds_profile_xml(name: str, udp_only: bool, announcement_period: float | None = None,
                        comment: str = "") -> str:
    """A Fast DDS XML profile (the schema of Fast DDS 2.14, Jazzy's) making participant ``name`` the default.

    Args:
        name: the participant profile's name.
        udp_only: the UDPv4 transport only (no shared memory, whose segments two users cannot share).
        announcement_period: seconds between the participant's announcements (``leaseAnnouncement``;
            Fast DDS's default of 3 s when None).
        comment: a line of text for an XML comment saying whose profile it is ("" for none).

    The one template of both profiles the engine writes: a batch job's (:data:`FASTDDS_UDP_ONLY`) and the
    grader's own (``ros2course.run.probes.grader_profile_xml``).
    """
    profiles = ElementTree.Element("profiles", xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles")
    if udp_only:
        descriptor = ElementTree.SubElement(ElementTree.SubElement(profiles, "transport_descriptors"),
                                            "transport_descriptor")
        ElementTree.SubElement(descriptor, "transport_id").text = _UDP_TRANSPORT
        ElementTree.SubElement(descriptor, "type").text = "UDPv4"
    participant = ElementTree.SubElement(profiles, "participant", profile_name=name, is_default_profile="true")
    rtps = ElementTree.SubElement(participant, "rtps")
    if announcement_period is not None:
        seconds = int(announcement_period)
        lease = ElementTree.SubElement(ElementTree.SubElement(ElementTree.SubElement(rtps, "builtin"),
                                                              "discovery_config"), "leaseAnnouncement")
        ElementTree.SubElement(lease, "sec").text = str(seconds)
        ElementTree.SubElement(lease, "nanosec").text = str(round((announcement_period - seconds) * 1e9))
    if udp_only:
        ElementTree.SubElement(ElementTree.SubElement(rtps, "userTransports"), "transport_id").text = _UDP_TRANSPORT
        ElementTree.SubElement(rtps, "useBuiltinTransports").text = "false"
    ElementTree.indent(profiles)
    note = f"<!-- {comment} -->\n" if comment else ""
    return f'<?xml version="1.0" encoding="UTF-8" ?>\n{note}{ElementTree.tostring(profiles, encoding="unicode")}\n'


#: The id of the UDPv4 transport a UDP-only profile declares and makes its participant's only one.
_UDP_TRANSPORT = "ros2course_udp"


#: Fast DDS default participant profile for jobs with a submission uid: the UDPv4 transport
#: only (no shared memory, whose segments two users cannot share).
FASTDDS_UDP_ONLY = fastdds_profile_xml("ros2course_udp_only", udp_only=True)

_ENV_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


# --- inside the worker: running the submission's commands --------------------------------------

@dataclasses.dataclass(frozen=True)
class SubmissionIdentity:
    """Who the submission's processes run as, inside a job.

    Attributes:
        uid: the job's own unprivileged uid (no account, no files outside the job's scratch).
        gid: its gid (no supplementary groups).
        nproc: ``RLIMIT_NPROC`` for the uid (tasks at once; it is the job's alone).
        cgroup_procs: the ``cgroup.procs`` file of the job's ``pids`` cgroup ("" when none).
    """

    uid: int
    gid: int
    nproc: int
    cgroup_procs: str = ""


_identity: SubmissionIdentity | None = None


def configure(identity: SubmissionIdentity | None) -> None:
    """Set the identity every later :func:`command` runs submission code as (the batch worker, once at start)."""
    global _identity  # noqa: PLW0603 - one setting per worker process, made before any grading
    _identity = identity


def current() -> SubmissionIdentity | None:
    """The configured identity, or None (``check``, ``dev validate``: the learner's own code, own user)."""
    return _identity


def parent_alive_guard(parent_pid: int | None = None) -> list[str]:
    """A command prefix that execs the rest only if its parent is still ``parent_pid`` (default: this process).

    ``setpriv --pdeathsig KILL`` closes a race of its own only half: the signal is armed by
    ``prctl(PR_SET_PDEATHSIG)`` in the child, and a parent that dies between the ``fork`` and
    that call never sends it (prctl(2) says to check ``getppid()`` after it). Placed *after*
    the ``setpriv`` in an argv, this ``/bin/sh`` reads ``$PPID`` (``getppid()`` at its start, so
    after the prctl) and ends with 137 (128 + SIGKILL, as if the signal had come) when the
    parent has gone; otherwise it ``exec``s, so the PID and exit code stay the program's.
    Seen in CI: ``ros2course check`` SIGKILLed 10 ms after starting a node left the node running.
    """
    pid = os.getpid() if parent_pid is None else parent_pid
    return ["/bin/sh", "-c", '[ "$PPID" = "$0" ] || exit 137; exec "$@"', str(pid)]


def die_with_parent() -> list[str]:
    """A command prefix that makes the program die with this process: ``setpriv --pdeathsig KILL --`` and
    :func:`parent_alive_guard` (which closes the race the first leaves open), or ``[]`` where util-linux's
    ``setpriv`` is missing (the process group is then what stops the program). For a program that keeps this
    process's uid; :func:`command` (``pdeathsig=True``) arms the same signal after a uid drop.

    The signal is sent when the *thread* that forked the child ends (prctl(2)), so start children from the
    main thread or a thread that outlives them."""
    setpriv = shutil.which("setpriv")
    return [setpriv, "--pdeathsig", "KILL", "--", *parent_alive_guard()] if setpriv else []


def command(argv: list[str], env: dict[str, str], pdeathsig: bool = False,
            identity: SubmissionIdentity | None = None) -> tuple[list[str], dict[str, str]]:
    """``(argv, env)`` to give ``subprocess`` so that ``argv`` runs as the submission.

    Without an identity (:func:`configure`), returns them unchanged. With one:
    ``/bin/sh`` joins the job's pids cgroup, ``prlimit`` sets ``RLIMIT_NPROC``,
    ``setpriv`` drops to the uid/gid with no groups, no capabilities and
    ``no_new_privs``, then ``env -i`` applies ``env`` and execs ``argv``. Every
    step ``exec``s, so the PID, process group and exit code are ``argv``'s.

    Args:
        argv: the command (``argv[0]`` a path or a name found on ``env``'s PATH).
        env: the environment ``argv`` should have.
        pdeathsig: also set the parent-death signal (SIGKILL) after the drop
            (``prctl`` clears it when the uid changes, so it is set by the same ``setpriv``).
        identity: run as this identity instead of the configured one (the capability probe).
    """
    identity = identity or _identity
    if identity is None:
        return list(argv), dict(env)
    setpriv, prlimit = _tool("setpriv"), _tool("prlimit")
    shim = 'if [ -n "$1" ]; then echo $$ > "$1" || exit 126; fi; shift; exec "$@"'
    wrapped = ["/bin/sh", "-c", shim, "ros2course-sandbox", identity.cgroup_procs,
               prlimit, f"--nproc={identity.nproc}:{identity.nproc}", "--",
               setpriv, f"--reuid={identity.uid}", f"--regid={identity.gid}", "--clear-groups",
               "--no-new-privs", "--inh-caps=-all", "--bounding-set=-all",
               *(["--pdeathsig", "KILL", "--", *parent_alive_guard()] if pdeathsig else ["--"]),
               "/usr/bin/env", "-i", *[f"{k}={v}" for k, v in env.items() if _ENV_NAME.match(k)], *argv]
    return wrapped, {"PATH": SAFE_PATH, "LANG": "C.UTF-8"}


def run(argv: list[str], *, env: dict[str, str], **kwargs: Any) -> subprocess.CompletedProcess:
    """``subprocess.run(argv, env=env, **kwargs)`` with ``argv`` running as the submission (see :func:`command`)."""
    argv, env = command(argv, env)
    return subprocess.run(argv, env=env, **kwargs)  # noqa: S603, PLW1510 - the caller passes check=


def _tool(name: str) -> str:
    path = shutil.which(name, path=SAFE_PATH)
    if path is None:
        raise FileNotFoundError(f"{name} (util-linux) is needed to run submission code unprivileged")
    return path


# --- in the parent: what the machine allows -----------------------------------------------------

@dataclasses.dataclass
class Isolation:
    """What protected one job (the ``isolation`` field of its results).

    Attributes:
        protections: protection name (:data:`PROTECTIONS`) -> how it was given, or None if missing.
        missing: protection name -> why the machine could not give it.
        uid: the job's uid (None without the uid protection).
        pids_limit: tasks the submission may have at once (None: no limit).
        pids_via: ``"cgroup pids"`` and/or ``"RLIMIT_NPROC"``.
        memory: the address-space limit in words (``"RLIMIT_AS 2048 MiB per process"``, ``"none"``;
            ``""`` before the worker is started).
        pids_stats: the pids cgroup's counters after the job (``peak``, ``events_max``, ...), when there was one.
        killed_after: processes of the job still alive after its worker ended, then killed.
        not_run: why the job never started a worker (``"not run (not gradable)"``); ``""`` when it ran.
    """

    protections: dict[str, str | None]
    missing: dict[str, str]
    uid: int | None = None
    pids_limit: int | None = None
    pids_via: str = ""
    memory: str = ""
    pids_stats: dict[str, int] = dataclasses.field(default_factory=dict)
    killed_after: int = 0
    not_run: str = ""

    @classmethod
    def never_ran(cls, reason: str) -> Isolation:
        """The isolation of a job that started no worker (nothing was protected, nothing needed to be)."""
        return cls({}, {}, not_run=reason)

    @property
    def mount_namespace(self) -> bool:
        """True when the job ran in a mount namespace of its own (its shared memory died with it)."""
        return bool(self.protections.get(MOUNTS))

    def to_json(self) -> dict[str, Any]:
        """The JSON shape in ``results.jsonl``: the protections, what is missing and why, plus the older flags,
        the memory limit, the pids cgroup's counters (``pids_<name>``) and ``killed_after`` when set."""
        if self.not_run:
            return {"netns": False, "mountns": False, "reason": self.not_run}
        data = {"netns": bool(self.protections.get(NETWORK)), "mountns": self.mount_namespace,
                "pidns": bool(self.protections.get(PIDNS)), "uid": self.uid, "pids_limit": self.pids_limit,
                "pids_via": self.pids_via, "protections": dict(self.protections), "missing": dict(self.missing),
                "reason": self.summary()}
        if self.memory:
            data["memory"] = self.memory
        data.update({f"pids_{name}": value for name, value in self.pids_stats.items()})
        if self.killed_after:
            data["killed_after"] = self.killed_after
        return data

    def summary(self) -> str:
        """One line: what is in effect, then what is missing and why."""
        have = [name for name in PROTECTIONS if self.protections.get(name)]
        text = "in effect: " + (", ".join(have) or "none")
        if self.missing:
            text += "; MISSING: " + "; ".join(f"{name} ({why})" for name, why in self.missing.items())
        return text


@dataclasses.dataclass
class Capabilities:
    """What this machine allows, probed once per process (:func:`capabilities`).

    Attributes:
        unshare: the ``unshare`` flags that work (empty: no namespaces).
        pidns: whether those flags include a PID namespace with ``dumb-init``.
        uid_drop: submission code can run as another uid (root, not in a user namespace).
        pids_root: a ``pids`` cgroup folder where job cgroups can be made ("" if none).
        missing: protection -> reason, for those this machine cannot give.
    """

    unshare: list[str]
    pidns: bool
    uid_drop: bool
    pids_root: str
    missing: dict[str, str]
    tools: dict[str, str]


_caps_lock = threading.Lock()
_caps: Capabilities | None = None


def capabilities() -> Capabilities:
    """Probe (once per process) which protections this machine can give a job."""
    global _caps  # noqa: PLW0603 - a probe of the machine, cached for the process
    with _caps_lock:
        if _caps is None:
            _caps = _probe()
        return _caps


def _dumb_init() -> str | None:
    local = Path(sys.executable).parent / "dumb-init"
    return str(local) if local.is_file() else shutil.which("dumb-init")


def _ip() -> str | None:
    return shutil.which("ip") or next((p for p in ("/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip") if os.access(p, os.X_OK)), None)


def _probe() -> Capabilities:
    missing: dict[str, str] = {}
    tools = {name: shutil.which(name) or "" for name in ("unshare", "setpriv", "prlimit")}
    tools["ip"] = _ip() or ""
    tools["dumb-init"] = _dumb_init() or ""
    if sys.platform != "linux":
        why = "not Linux"
        return Capabilities([], False, False, "", {name: why for name in PROTECTIONS}, tools)
    pids_root = _pids_cgroup_root()
    unshare_flags: list[str] = []
    pidns = False
    if not tools["unshare"] or not tools["ip"]:
        why = f"no {'unshare (util-linux)' if not tools['unshare'] else 'ip (iproute2)'} command"
        missing.update({NETWORK: why, MOUNTS: why, PIDNS: why})
    else:
        reasons = []
        pid_flags = ["--pid", "--fork", "--kill-child", "--mount-proc"] if tools["dumb-init"] else []
        candidates = [["--net", "--mount", *pid_flags], ["--user", "--map-root-user", "--net", "--mount", *pid_flags]]
        if pid_flags:
            candidates += [["--net", "--mount"], ["--user", "--map-root-user", "--net", "--mount"]]
        for flags in candidates:
            init = [tools["dumb-init"], "--"] if "--pid" in flags else []
            plan = MountPlan(tools["ip"], own="", hide=[], read_only=[], keep=[], private_tmp=["/tmp"])
            ok, why = _try([tools["unshare"], *flags, *init, "/bin/sh", "-c", plan.script(), "probe", "true"])
            if ok:
                unshare_flags, pidns = flags, "--pid" in flags
                break
            reasons.append(f"unshare {' '.join(flags)}: {why}")
        if not unshare_flags:
            why = "unshare refused: " + "; ".join(reasons[:2])
            missing.update({NETWORK: why, MOUNTS: why, PIDNS: why})
        elif not pidns:
            missing[PIDNS] = ("no dumb-init (pip install dumb-init)" if not tools["dumb-init"]
                              else "unshare --pid refused: " + "; ".join(reasons[:1]))
    uid_drop = False
    if os.geteuid() != 0:
        missing[UID] = "not root: only root can run submission code as another uid (run ros2course grade as root)"
    elif "--user" in unshare_flags:
        missing[UID] = "namespaces only inside a user namespace, where no other uid is mapped"
    elif not unshare_flags:
        missing[UID] = "needs the namespaces too (DDS between the grader and another uid runs over loopback UDP)"
    elif not tools["setpriv"] or not tools["prlimit"]:
        missing[UID] = "no setpriv/prlimit command (util-linux)"
    else:
        uid_drop, why = _probe_uid_drop(unshare_flags, tools)
        if not uid_drop:
            missing[UID] = why
    if not uid_drop and not pids_root:
        missing[PIDS_LIMIT] = "no pids cgroup to write to, and RLIMIT_NPROC needs the dedicated uid"
    return Capabilities(unshare_flags, pidns, uid_drop, pids_root, missing, tools)


def _try(argv: list[str]) -> tuple[bool, str]:
    try:
        proc = subprocess.run(argv, capture_output=True, text=True, timeout=30, stdin=subprocess.DEVNULL, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return False, str(exc)
    if proc.returncode == 0:
        return True, ""
    return False, (proc.stderr.strip().splitlines() or [f"exit {proc.returncode}"])[-1]


def _probe_uid_drop(unshare_flags: list[str], tools: dict[str, str]) -> tuple[bool, str]:
    """Can a fresh uid run this Python (stdlib and ROS imports) inside the job's mounts?"""
    uid = UID_BASE + UID_SPAN  # just past the range jobs use

    ros_env = env_mod.activate()
    inner, inner_env = command([sys.executable, "-c", "import rclpy"], ros_env,
                               identity=SubmissionIdentity(uid, uid, 64))
    if unshare_flags:
        plan = MountPlan(tools["ip"], own="", hide=[], read_only=read_only_paths(content_root()), keep=[],
                         private_tmp=PRIVATE_TMP, hidden_home=grader_home())
        init = [tools["dumb-init"], "--"] if "--pid" in unshare_flags else []
        argv = [tools["unshare"], *unshare_flags, *init, "/bin/sh", "-c", plan.script(), "probe", *inner]
    else:
        argv = inner
    try:
        proc = subprocess.run(argv, env=inner_env, capture_output=True, text=True, timeout=60,
                              stdin=subprocess.DEVNULL, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return False, f"the probe as uid {uid} failed: {exc}"
    if proc.returncode == 0:
        return True, ""
    last = (proc.stderr.strip().splitlines() or [f"exit {proc.returncode}"])[-1]
    return False, f"uid {uid} cannot run {sys.executable} with rclpy ({last[:200]})"


def _pids_cgroup_root() -> str:
    """A folder of the ``pids`` controller (cgroup v1, or v2 with pids delegated) where we may make job cgroups."""
    own: dict[str, str] = {}
    with contextlib.suppress(OSError):
        for line in Path("/proc/self/cgroup").read_text().splitlines():
            _, controllers, path = line.split(":", 2)
            for c in controllers.split(",") if controllers else ["<v2>"]:
                own[c] = path
    mounts: list[tuple[str, str, str]] = []
    with contextlib.suppress(OSError):
        for line in Path("/proc/self/mountinfo").read_text().splitlines():
            pre, _, post = line.partition(" - ")
            fields, extra = pre.split(), post.split()
            if len(extra) >= 3 and extra[0] in ("cgroup", "cgroup2"):
                mounts.append((extra[0], fields[4], extra[2]))
    candidates = []
    for fstype, point, options in mounts:
        if fstype == "cgroup" and "pids" in options.split(","):
            candidates.append(Path(point) / own.get("pids", "/").lstrip("/"))
        elif fstype == "cgroup2" and "pids" in _read(Path(point) / "cgroup.controllers").split():
            candidates.append(Path(point) / own.get("<v2>", "/").lstrip("/"))
    for folder in candidates:
        probe = folder / f"ros2course-probe-{uuid.uuid4().hex[:8]}"
        try:
            probe.mkdir()
        except OSError:
            continue
        try:
            if (probe / "pids.max").is_file():
                return str(folder)
        finally:
            with contextlib.suppress(OSError):
                probe.rmdir()
    return ""


def _read(path: Path) -> str:
    try:
        return path.read_text()
    except OSError:
        return ""


# --- one job's walls --------------------------------------------------------------------------

#: Host secrets a job never sees, even through a symbolic link the grader follows as root.
SECRETS = ("/etc/shadow", "/etc/gshadow", "/etc/shadow-", "/etc/gshadow-", "/etc/ssh", "/etc/ssl/private")
#: World-writable folders each job gets a fresh, private tmpfs for.
PRIVATE_TMP = ["/tmp", "/var/tmp", "/run/lock"]


def grader_home() -> str:
    """The grading user's home folder (hidden from submissions), or "" when it is ``/``."""
    home = os.path.realpath(os.path.expanduser("~"))
    return "" if home in ("/", "") else home


def read_only_paths(course: Path) -> list[str]:
    """What a submission may read but never write: the course (the folder ``course``), the engine, the venv,
    the Python and ROS installs.

    The engine's own package folder is listed apart from the venv: an editable install (``pip install -e``)
    imports it from the source checkout, which may lie under a folder the job replaces (``/tmp``), and the
    grading worker the job starts imports ``ros2course`` from there.
    """
    engine = os.path.dirname(os.path.abspath(__file__))
    paths = [str(course), engine, sys.prefix, sys.base_prefix]
    for var in ("AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH"):
        paths += [p for p in os.environ.get(var, "").split(os.pathsep) if p]
    out: list[str] = []
    for path in sorted({os.path.realpath(p) for p in paths if os.path.isdir(p)}, key=len):
        if path != "/" and not any(path == o or path.startswith(o.rstrip("/") + "/") for o in out):
            out.append(path)
    return out


@dataclasses.dataclass
class MountPlan:
    """The shell run as root inside a job's new namespaces before the worker (``exec "$@"``).

    Attributes:
        ip: path of ``ip`` (iproute2).
        own: the job's scratch folder: stays visible and writable ("" for none).
        hide: folders covered by an empty tmpfs (mode 0755).
        read_only: folders bound onto themselves read-only.
        keep: folders that stay visible read-only even inside a hidden folder.
        private_tmp: world-writable folders replaced by a fresh tmpfs (mode 1777).
        hidden_home: the grader's home, hidden like ``hide`` (its kept folders bound back).
        secrets: files masked with ``/dev/null`` and folders with an empty tmpfs (host keys, password hashes).
    """

    ip: str
    own: str
    hide: list[str]
    read_only: list[str]
    keep: list[str]
    private_tmp: list[str]
    hidden_home: str = ""
    secrets: tuple[str, ...] = SECRETS

    def script(self) -> str:
        """The ``sh`` script (``set -e``: any failing step fails the job before the worker runs)."""
        q = shlex.quote
        hidden = [h for h in [*self.hide, self.hidden_home, *self.private_tmp] if h]
        held = [p for p in [*self.read_only, *self.keep] if any(_inside(p, h) for h in hidden)]
        held = [p for p in dict.fromkeys(held) if os.path.isdir(p)]
        lines = ["set -e", f"{q(self.ip)} link set lo up",
                 "mount -t tmpfs -o mode=1777,size=1g ros2course-shm /dev/shm",
                 "mkdir -m 0700 /dev/shm/.ros2course-hold"]
        holds = ([self.own] if self.own else []) + held
        for i, path in enumerate(holds):
            lines += [f"mkdir /dev/shm/.ros2course-hold/{i}", f"mount --bind {q(path)} /dev/shm/.ros2course-hold/{i}"]
        for path in self.read_only:
            lines += [f"mount --bind {q(path)} {q(path)}", f"mount -o remount,bind,ro {q(path)}"]
        for path in self.private_tmp:
            lines.append(f"if [ -d {q(path)} ]; then mount -t tmpfs -o mode=1777,size=1g ros2course-tmp {q(path)}; fi")
        for path in [*self.hide, self.hidden_home]:
            if path:
                lines.append(f"if [ -d {q(path)} ]; then mount -t tmpfs -o mode=0755,size=1m ros2course-hidden {q(path)}; fi")
        for path in self.secrets:
            lines.append(f"if [ -f {q(path)} ]; then mount --bind /dev/null {q(path)}; "
                         f"elif [ -d {q(path)} ]; then mount -t tmpfs -o mode=0755,size=1m ros2course-hidden {q(path)}; fi")
        for i, path in enumerate(holds):
            lines += [f"mkdir -p {q(path)}", f"mount --move /dev/shm/.ros2course-hold/{i} {q(path)}"]
            if path != self.own:
                lines.append(f"mount -o remount,bind,ro {q(path)}")
        lines += ["rmdir /dev/shm/.ros2course-hold/* 2>/dev/null || true", "rmdir /dev/shm/.ros2course-hold",
                  'exec "$@"']
        return "\n".join(lines)


def _inside(path: str, folder: str) -> bool:
    path, folder = os.path.realpath(path), os.path.realpath(folder)
    return path == folder or path.startswith(folder.rstrip("/") + "/")


class PidsCgroup:
    """A job's own ``pids`` cgroup: submission processes join it; ``pids.max`` caps them.

    Args:
        root: a folder of the pids controller (:attr:`Capabilities.pids_root`).
        limit: tasks (processes and threads) at once.

    Raises:
        OSError: the cgroup cannot be made.
    """

    def __init__(self, root: str, limit: int) -> None:
        self.path = Path(root) / f"ros2course-job-{uuid.uuid4().hex[:12]}"
        self.path.mkdir()
        (self.path / "pids.max").write_text(str(limit))
        self.limit = limit

    @property
    def procs(self) -> str:
        """The file a process writes its PID to, to join."""
        return str(self.path / "cgroup.procs")

    def stats(self) -> dict[str, int]:
        """``{"peak": tasks at most (where the kernel says), "refused": forks refused at the limit}``."""
        out = {}
        peak = _read(self.path / "pids.peak").strip()
        if peak.isdigit():
            out["peak"] = int(peak)
        for line in _read(self.path / "pids.events").splitlines():
            key, _, value = line.partition(" ")
            if key == "max" and value.strip().isdigit():
                out["refused"] = int(value)
        return out

    def close(self) -> None:
        """SIGKILL whatever is left in it, then remove it (waits up to 5 s for it to empty)."""
        deadline = time.monotonic() + 5
        while True:
            pids = [int(p) for p in _read(self.path / "cgroup.procs").split() if p.isdigit()]
            for pid in pids:
                with contextlib.suppress(ProcessLookupError, PermissionError):
                    os.kill(pid, 9)
            try:
                self.path.rmdir()
                return
            except OSError:
                if time.monotonic() > deadline:
                    return
                time.sleep(0.05)


def new_uid() -> int:
    """A fresh uid (= gid) for one job, from a range no account uses (see :data:`UID_BASE`)."""
    return UID_BASE + secrets.randbelow(UID_SPAN)


def give_tree(folder: Path, uid: int | None = None, gid: int | None = None) -> None:
    """Give ``folder`` and everything under it to the submission's uid (``lchown``: links are never followed).

    A no-op without a configured identity (``check``: the learner's own user
    already owns it). After this the grader only reads the tree: writing into a
    folder the submission owns could follow a link it planted.

    Args:
        folder: a tree the grader made (none of it may be the submission's yet).
        uid: / gid: give it to these ids instead of the configured identity's (the batch runner).
    """
    if uid is None:
        if _identity is None:
            return
        uid, gid = _identity.uid, _identity.gid
    gid = uid if gid is None else gid
    os.chown(folder, uid, gid, follow_symlinks=False)
    for root, dirs, files in os.walk(folder):
        for name in dirs + files:
            os.chown(os.path.join(root, name), uid, gid, follow_symlinks=False)


@contextlib.contextmanager
def private_dir(prefix: str):
    """A temporary folder the submission's processes may write (owned by its uid when one is configured).

    Yields:
        the folder's :class:`~pathlib.Path`; it is removed afterwards.
    """
    with tempfile.TemporaryDirectory(prefix=prefix) as folder:
        if _identity is not None:
            os.chown(folder, _identity.uid, _identity.gid)
        yield Path(folder)


def copy_logs(src: Path, dest: Path, cap: int = 200_000_000) -> list[str]:
    """Copy the regular files and folders under ``src`` into ``dest``; never a link, FIFO or device.

    A submission's processes can write into its log folder: a symbolic link
    there (to ``/etc/shadow``, or to OUTDIR) must not become a link, or the
    file it points at, in OUTDIR. Files are opened with ``O_NOFOLLOW`` and
    copied while ``cap`` bytes last.

    Returns:
        the relative paths left out, with why (e.g. ``"ros/x: symbolic link"``).
    """
    skipped: list[str] = []
    left = cap
    for folder, dirs, files in os.walk(src, followlinks=False):
        rel = Path(folder).relative_to(src)
        (dest / rel).mkdir(parents=True, exist_ok=True)
        for name in list(dirs):
            if os.path.islink(os.path.join(folder, name)):
                dirs.remove(name)
                skipped.append(f"{rel / name}: symbolic link")
        for name in files:
            path = os.path.join(folder, name)
            info = os.lstat(path)
            if not stat.S_ISREG(info.st_mode):
                skipped.append(f"{rel / name}: {'symbolic link' if stat.S_ISLNK(info.st_mode) else 'not a regular file'}")
                continue
            try:
                fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
            except OSError as exc:
                skipped.append(f"{rel / name}: {exc.strerror}")
                continue
            with os.fdopen(fd, "rb") as source, open(dest / rel / name, "wb") as target:
                if not stat.S_ISREG(os.fstat(source.fileno()).st_mode):
                    skipped.append(f"{rel / name}: not a regular file")
                    continue
                data = source.read(max(left, 0))
                target.write(data)
                left -= len(data)
                if left <= 0:
                    skipped.append(f"{rel / name}: log copy cap of {cap} bytes reached")
    if skipped:
        (dest / "ros2course-not-copied.txt").write_text("\n".join(skipped) + "\n", encoding="utf-8")
    return skipped
