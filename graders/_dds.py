"""Kit steps for the Fast DDS profile lesson (tutorial ch. 32.6.2; issue 12): run, read, and the compose file.

* :func:`exchange` starts two rclpy nodes of the grader **in child processes**
  (a talker and a listener, :data:`_CHILD`) with ``FASTRTPS_DEFAULT_PROFILES_FILE``
  and ``FASTDDS_DEFAULT_PROFILES_FILE`` pointing at the learner's profile: Fast
  DDS reads them when a participant is created, so they must never be set in
  the grader's own process. Each child reports how many messages it got and
  which ``/dev/shm`` files it maps or holds open (``/proc/self/maps`` and
  ``/proc/self/fd``): a Fast DDS shared-memory segment (``fastrtps_*``) is
  attributed to the process that uses it, so checks running beside this one
  on the machine cannot be confused with it. Fast DDS's own parser errors
  (``[XMLPARSER Error] ...``, printed on stdout by Fast DDS 2's default log
  consumer) come back as :attr:`DdsRun.errors`.
* The children use ``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET`` (a container's
  setting): in ``LOCALHOST`` mode rmw_fastrtps sets the transports itself and
  turns shared memory on whatever the profile says (tried: a UDP-only profile
  still maps ``fastrtps_*`` segments there).
* Tried on Jazzy (Fast DDS 2.14): only ``FASTRTPS_DEFAULT_PROFILES_FILE`` is
  read; ``FASTDDS_DEFAULT_PROFILES_FILE`` alone is ignored (it is Fast DDS 3's
  name, ROS 2 Kilted and later).
* :func:`read_profile` reads the XML statically (xml.etree) only to say *why*
  shared memory stayed on; the live run is the verdict.
"""

from __future__ import annotations

import dataclasses
import json
import random
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import yaml

from ros2course.kit import Session
from ros2course.kit import wait_until

#: The variable Jazzy's Fast DDS reads, and Fast DDS 3's name for it (set both for the children).
PROFILE_VARIABLES = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")
_ANSI = re.compile(r"\x1b\[[0-9;]*m")
_XML_ERROR = re.compile(r"\[XMLPARSER Error\]\s*(.*?)(?:\s*->\s*Function\s+\w+)?\s*$")

#: Seconds the talker waits for the listener to match before it publishes (two of Fast DDS's announcement
#: periods of a participant past its first announcements, so one missed exchange is repeated in time).
MATCH_WAIT = 6.0
#: One child: ``python -c _CHILD ROLE TOPIC SECONDS``; prints one JSON line at the end.
_CHILD = f"MATCH_WAIT = {MATCH_WAIT}\n" + r"""
import json, os, sys, time
import rclpy
from std_msgs.msg import String
role, topic, seconds = sys.argv[1], sys.argv[2], float(sys.argv[3])
rclpy.init()
node = rclpy.create_node(f"dds_{role}_{os.getpid()}")
got = []
if role == "talker":
    pub = node.create_publisher(String, topic, 10)
    # publish once the listener is matched (or MATCH_WAIT s): a first discovery exchange missed on a loaded
    # machine is repeated only after a period, and a talker that published for its seconds from its start
    # could end before it ever matched (a correct profile failing)
    end = time.monotonic() + MATCH_WAIT
    while time.monotonic() < end and not pub.get_subscription_count():
        rclpy.spin_once(node, timeout_sec=0.05)
    node.create_timer(0.1, lambda: pub.publish(String(data="hello over UDP")))
else:
    node.create_subscription(String, topic, lambda m: got.append(m.data), 10)
end = time.monotonic() + seconds
while time.monotonic() < end and (role == "talker" or len(got) < 5):
    rclpy.spin_once(node, timeout_sec=0.05)
shm = set()
with open("/proc/self/maps") as maps:
    shm.update(line.split("/dev/shm/", 1)[1].split(" (deleted)")[0].strip() for line in maps if "/dev/shm/" in line)
for fd in os.listdir("/proc/self/fd"):
    try:
        target = os.readlink(f"/proc/self/fd/{fd}")
    except OSError:
        continue
    if target.startswith("/dev/shm/"):
        shm.add(target[len("/dev/shm/"):])
print(json.dumps({"received": len(got), "shm": sorted(n for n in shm if "fastrtps" in n)}), flush=True)
node.destroy_node()
rclpy.shutdown()
"""


@dataclasses.dataclass(frozen=True)
class DdsRun:
    """What the two grader nodes did with the learner's profile.

    Attributes:
        received: messages the listener got from the talker (it stops at 5).
        shm: ``/dev/shm`` Fast DDS files (``fastrtps_*``) either process used, sorted.
        errors: Fast DDS's own ``[XMLPARSER Error]`` messages, in order, without repeats.
        failure: "" when both children reported; else what went wrong (exit code, last line).
    """

    received: int
    shm: list[str]
    errors: list[str]
    failure: str


def xml_errors(text: str) -> list[str]:
    """Fast DDS's XML parser errors in ``text`` (colours stripped), e.g. ``Error parsing '/x.xml'``, no repeats."""
    found: list[str] = []
    for line in _ANSI.sub("", text).splitlines():
        match = _XML_ERROR.search(line)
        if match and match.group(1) not in found:
            found.append(match.group(1))
    return found


def exchange(s: Session, profile: Path, seconds: float = 3.0) -> DdsRun:
    """Run a talker and a listener (child processes) with ``profile`` as their Fast DDS default profile.

    Args:
        profile: the learner's XML file (absolute path).
        seconds: how long the talker publishes (every 0.1 s), once the listener has matched (or after
            :data:`MATCH_WAIT` s); the listener waits ``seconds + 3 + MATCH_WAIT`` s at most.

    They join the check's domain (``s.ros.domain_id``) on a random topic, each in
    its own process group with a deadline (:meth:`Session.start_program`).
    """
    topic = f"/udp_check_{random.SystemRandom().randrange(10000, 100000)}"
    env = dict(s.base_env)
    env.update({"ROS_DOMAIN_ID": str(s.ros.domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET",
                "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", "PYTHONUNBUFFERED": "1",
                "ROS_HOME": str(s.submission_folder(f"ros_home{topic.replace('/', '_')}"))})  # logs in the check's folder
    env.pop("ROS_LOCALHOST_ONLY", None)
    env.update({name: str(profile) for name in PROFILE_VARIABLES})
    procs = [s.start_program([sys.executable, "-c", _CHILD, role, topic, str(wait)], f"dds_{role}", env=env,
                             cwd=profile.parent, deadline=wait + 20.0)
             for role, wait in (("listener", seconds + 3.0 + MATCH_WAIT), ("talker", seconds))]
    with s.phase("run"):
        wait_until(lambda: all(p.poll() is not None for p in procs), seconds + 15.0 + MATCH_WAIT, interval=0.05)
    reports, failure = [], ""
    for proc in procs:
        proc.stop(sigint_timeout=1.0, sigterm_timeout=1.0)
        lines = [line for line in proc.stdout().splitlines() if line.startswith("{")]
        if lines:
            reports.append(json.loads(lines[-1]))
        elif not failure:
            last = ([line for line in _ANSI.sub("", proc.stderr()).splitlines() if line.strip()] or ["no output"])[-1]
            failure = f"a grader node ended with exit code {proc.poll()} before reporting: {last.strip()}"
    errors = xml_errors("\n".join(p.stdout() + "\n" + p.stderr() for p in procs))  # Fast DDS 2 logs to stdout
    return DdsRun(received=reports[0]["received"] if reports and not failure else 0,
                  shm=sorted({name for r in reports for name in r["shm"]}), errors=errors, failure=failure)


def _local(tag: Any) -> str:
    """An element's tag without its XML namespace (``{http://...}rtps`` -> ``rtps``)."""
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


def read_profile(path: Path) -> list[str]:
    """What keeps a Fast DDS profile from being "UDPv4 only" for every participant, as sentences ([] = none).

    The rules (Fast DDS XML profiles docs, "Transport descriptors" and
    "Participant profiles"; tutorial ch. 32.6.2): a ``<transport_descriptor>``
    of ``<type>UDPv4</type>``; a participant profile with
    ``is_default_profile="true"`` whose ``<rtps><userTransports>`` names it (and
    no SHM descriptor) and whose ``<useBuiltinTransports>`` is ``false``.
    """
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        return [f"it is not well-formed XML ({exc})"]
    types = {}
    for desc in (e for e in root.iter() if _local(e.tag) == "transport_descriptor"):
        fields = {_local(c.tag): (c.text or "").strip() for c in desc}
        types[fields.get("transport_id", "")] = fields.get("type", "")
    defaults = [e for e in root.iter() if _local(e.tag) == "participant" and e.get("is_default_profile") == "true"]
    if not defaults:
        return ['no <participant ... is_default_profile="true">: nodes only use a profile marked as the default']
    problems = []
    rtps = next((c for c in defaults[0] if _local(c.tag) == "rtps"), None)
    children = {_local(c.tag): c for c in (rtps if rtps is not None else [])}
    builtin = (children["useBuiltinTransports"].text or "").strip() if "useBuiltinTransports" in children else None
    if builtin != "false":
        problems.append("<useBuiltinTransports> is " + ("missing" if builtin is None else repr(builtin))
                        + ", so the builtin transports (shared memory among them) stay on: write false")
    used = [(c.text or "").strip() for c in children.get("userTransports", [])]
    kinds = [types.get(i, f"undeclared id {i!r}") for i in used]
    if "UDPv4" not in kinds:
        problems.append(f"<userTransports> names {', '.join(map(repr, used)) or 'no transport'}; none is a "
                        "transport_descriptor of <type>UDPv4</type>")
    if "SHM" in kinds:
        problems.append("<userTransports> lists a transport of <type>SHM</type> (shared memory)")
    return problems


class _ComposeLoader(yaml.SafeLoader):
    """pyyaml's safe loader that refuses a key repeated in one mapping, as docker compose (Go's yaml.v3:
    'mapping key "environment" already defined') does; pyyaml alone keeps the last one silently, so a file docker
    refuses was graded by its last key (audit of stop 71)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if isinstance(key, str) and key in seen:
                raise yaml.constructor.ConstructorError(
                    None, None, f"mapping key {key!r} already defined (line {key_node.start_mark.line + 1}): docker "
                    "compose refuses the file", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep)


def read_compose(path: Path) -> tuple[dict[str, dict], str]:
    """``(services, error)`` of a compose file: service name -> its mapping; error "" when it parses (a key twice
    in one mapping is an error, as for docker compose: :class:`_ComposeLoader`)."""
    try:
        data = yaml.load(path.read_text(encoding="utf-8"), Loader=_ComposeLoader)  # noqa: S506 - a SafeLoader
    except (OSError, yaml.YAMLError) as exc:
        return {}, f"it is not readable YAML ({str(exc).splitlines()[0]})"
    services = data.get("services") if isinstance(data, dict) else None
    if not isinstance(services, dict):
        return {}, "it has no `services:` mapping"
    return {str(k): (v if isinstance(v, dict) else {}) for k, v in services.items()}, ""


def _host_path(source: str) -> bool:
    """Whether a short-syntax volume source is a host path: Compose reads it as one only when it starts with
    ``.``, ``/`` or ``~``; anything else (``fastrtps_profile.xml``) names a Docker volume (Compose file
    reference, services.volumes, short syntax)."""
    return source.startswith((".", "/", "~"))


def volume_entries(service: dict) -> list[tuple[str, str, str]]:
    """A compose service's ``volumes:`` as ``(kind, source, target)`` in file order; ``kind`` is Compose's mount
    type, ``"bind"`` or ``"volume"`` (or what a long entry's ``type:`` says). Short syntax ``src:dst[:mode]``:
    a source that is a host path (``./``, ``/``, ``~``) is a bind mount, any other names a Docker volume
    (``fastrtps_profile.xml:/profiles/...`` mounts an empty volume of that name, never the file beside the
    compose file: independent review of stop 73). Long syntax: its ``type:``, ``bind`` when absent."""
    out = []
    for volume in service.get("volumes") or []:
        if isinstance(volume, str) and ":" in volume:
            source, target = volume.split(":")[:2]
            out.append(("bind" if _host_path(source) else "volume", source, target))
        elif isinstance(volume, dict):
            out.append((str(volume.get("type", "bind")), str(volume.get("source", "")), str(volume.get("target") or "")))
    return out


def mounts(service: dict) -> dict[str, str]:
    """A compose service's bind mounts: container path -> host path (:func:`volume_entries` of kind ``bind``)."""
    return {target: source for kind, source, target in volume_entries(service) if kind == "bind" and target}


def named_volumes(service: dict) -> list[str]:
    """The Docker volume names a compose service mounts, in file order (:func:`volume_entries` of kind
    ``volume``)."""
    return [source for kind, source, _ in volume_entries(service) if kind == "volume" and source]


def environment(service: dict) -> dict[str, str]:
    """A compose service's ``environment:`` as a dict (list ``K=V`` or mapping syntax)."""
    env = service.get("environment") or {}
    if isinstance(env, list):
        return dict(str(item).split("=", 1) if "=" in str(item) else (str(item), "") for item in env)
    return {str(k): "" if v is None else str(v) for k, v in env.items()} if isinstance(env, dict) else {}


__all__ = ["PROFILE_VARIABLES", "DdsRun", "environment", "exchange", "mounts", "named_volumes", "read_compose",
           "read_profile", "volume_entries", "xml_errors"]
