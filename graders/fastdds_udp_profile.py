"""Grader for ``fastdds-udp-profile`` (tutorial ch. 32.4.2 and 32.6.2; contract in shared/LESSONS.md).

``docker/fastrtps_profile.xml`` is graded live: two grader nodes in child
processes use it as their Fast DDS default profile and must exchange messages
without any shared-memory segment (:mod:`graders._dds`); Fast DDS's own
parser errors are quoted. ``docker/compose.yml`` is read, not run: two
services of one image, ``stop_signal: SIGINT``, the profile mounted and
``FASTRTPS_DEFAULT_PROFILES_FILE`` pointing at the mounted file, a talker and a
listener of ``/chatter`` as docker would start them, in one ROS domain.
"""

from __future__ import annotations

import os
import re
import shlex
from pathlib import Path, PurePosixPath

from ros2course.kit import Check, Session, Unmet
from . import _dds as dds

PROFILE = "docker/fastrtps_profile.xml"
COMPOSE = "docker/compose.yml"
VARIABLE = dds.PROFILE_VARIABLES[0]
#: Programs a compose ``command:`` may start: a shell given ``-c`` and a script, or ``ros2`` itself (the
#: osrf/ros images' entrypoint sources ROS 2 before it runs the command, docker docs: ENTRYPOINT and CMD).
SHELLS = ("/bin/bash", "/bin/sh", "/usr/bin/bash", "/usr/bin/sh", "bash", "sh")
#: What the lesson's two services run (tutorial ch. 32.4.2): a talker on /chatter, and a listener of it.
TALKER = re.compile(r"\bros2\s+run\s+demo_nodes_(cpp|py)\s+talker\b|\bros2\s+topic\s+pub\s.*?/?\bchatter\b")
#: The listener: `ros2 topic echo /chatter`, which task 2 names (the independent review of stop 82 got full marks with
#: demo_nodes_cpp's listener, which the check's own title did not accept)
LISTENER = re.compile(r"\bros2\s+topic\s+echo\s.*?/?\bchatter\b")
#: The variable with which Jazzy's RMW picks the transports itself (the lesson: leave it unset in a container).
DISCOVERY_RANGE = "ROS_AUTOMATIC_DISCOVERY_RANGE"
#: ROS 2 distributions other than Jazzy, as an image's name or tag may say (ROS 2 docs, Distributions): the lesson
#: takes "any image with ROS 2 Jazzy".
OTHER_DISTROS = ("ardent", "bouncy", "crystal", "dashing", "eloquent", "foxy", "galactic", "humble", "iron",
                 "kilted", "rolling")
#: The largest ROS domain id (ROS 2 docs, "The ROS_DOMAIN_ID": 0-232; 0-101 are safe on every platform).
MAX_DOMAIN_ID = 232

CHECKS = [
    Check("profile_file", f"{PROFILE} exists", 1, f"create {PROFILE} (the starter has one with TODOs)",
          part="profile"),
    Check("profile_loads", "Fast DDS loads the profile without an error", 2,
          "fix the element Fast DDS names; each tag closes (`</tag>`), values are plain (`false`, not `>false`)",
          needs=("profile_file",), part="profile"),
    Check("udp_only", "The default participant profile uses a UDPv4 transport and no builtin ones", 2,
          "a transport_descriptor of <type>UDPv4</type>, named in <userTransports>, and "
          "<useBuiltinTransports>false</useBuiltinTransports>, in a <participant is_default_profile=\"true\">",
          needs=("profile_file",), part="profile"),
    Check("exchange", "Two nodes using the profile exchange messages", 2,
          "keep a UDPv4 transport: with the builtin transports off and none of your own, nodes cannot talk",
          needs=("profile_file",), part="profile"),
    Check("no_shm", "They use no shared memory (/dev/shm/fastrtps_*)", 2,
          "<useBuiltinTransports>false</useBuiltinTransports> turns shared memory off; do not list an SHM transport",
          needs=("exchange",), part="profile"),
    Check("compose_services", f"{COMPOSE}: two services using one image", 1,
          "services: talker and listener, each with the same `image:`", part="compose"),
    Check("compose_stop_signal", "Every service has stop_signal: SIGINT", 1,
          "add `stop_signal: SIGINT` to each service: docker's default SIGTERM skips the nodes' clean shutdown",
          needs=("compose_services",), part="compose"),
    Check("compose_profile", f"Every service mounts the profile and sets {VARIABLE} to it", 2,
          f"volumes: [./fastrtps_profile.xml:/profiles/fastrtps_profile.xml:ro] and environment: "
          f"[{VARIABLE}=/profiles/fastrtps_profile.xml]", needs=("compose_services",), part="compose"),
    Check("compose_commands", "One service runs a talker and another `ros2 topic echo /chatter`", 1,
          "command: /bin/bash -c \"source /opt/ros/jazzy/setup.bash && ros2 topic echo /chatter\" in the listener "
          "(a shell needs -c before its script)", needs=("compose_services",), part="compose"),
    Check("compose_domain", "Both services are in one ROS domain", 1,
          "set the same ROS_DOMAIN_ID (an integer, 0-101) in every service's environment, or in none",
          needs=("compose_services",), part="compose"),
]


def grade(s: Session) -> None:
    with s.part("profile"):
        profile = s.workspace_root / PROFILE
        if not s.record("profile_file", profile.is_file(), f"{PROFILE} " + ("found" if profile.is_file() else "is missing"),
                        f"{PROFILE} exists"):
            raise Unmet(f"{PROFILE} is missing")
        problems = dds.read_profile(profile)
        s.record("udp_only", not problems, "; ".join(problems) or "a UDPv4 transport only, builtin transports off",
                 "the default participant profile: UDPv4 only, <useBuiltinTransports>false")
        run = dds.exchange(s, profile)
        s.record("profile_loads", not run.errors, "Fast DDS said: " + " | ".join(run.errors[:4]) if run.errors
                 else "Fast DDS loaded it without an error", "Fast DDS loads it without an XMLPARSER error")
        s.record("exchange", run.received > 0 and not run.failure, run.failure or
                 f"the listener received {run.received} message(s) from the talker",
                 "the grader's listener receives the talker's messages")
        s.record("no_shm", not run.shm, "they used shared memory: " + ", ".join(f"/dev/shm/{n}" for n in run.shm[:4])
                 if run.shm else "no /dev/shm/fastrtps_* file was used", "no Fast DDS shared-memory file is used")
    grade_compose(s)


def grade_compose(s: Session) -> None:
    """Record the three compose checks on ``docker/compose.yml`` (read with pyyaml, never run)."""
    services, error = dds.read_compose(s.workspace_root / COMPOSE)
    images = {name: service.get("image") for name, service in services.items()}
    one_image = len(services) >= 2 and len(set(images.values())) == 1 and None not in images.values()
    other = sorted({d for i in images.values() for d in OTHER_DISTROS if re.search(rf"\b{d}\b", str(i or ""))})
    s.record("compose_services", not error and one_image and not other,
             (error or ", ".join(f"{n}: image {i!r}" for n, i in images.items()) or "no service")
             + (f": an image of ROS 2 {other[0].capitalize()}, not Jazzy" if other and not error else ""),
             f"{COMPOSE} has two services using one image with ROS 2 Jazzy")
    wrong = [n for n, svc in services.items() if str(svc.get("stop_signal", "")).upper() not in ("SIGINT", "INT", "2")]
    s.record("compose_stop_signal", not wrong and bool(services),
             f"no `stop_signal: SIGINT` in {', '.join(wrong)}" if wrong else "every service stops with SIGINT",
             "stop_signal: SIGINT in every service (Ctrl+C, as the nodes expect)")
    compose = s.workspace_root / COMPOSE
    bad = [f"{n}: {why}" for n, svc in services.items() if (why := _profile_problem(svc, compose))]
    s.record("compose_profile", not bad and bool(services), "; ".join(bad) or
             f"every service mounts fastrtps_profile.xml and sets {VARIABLE} to it",
             f"each service mounts fastrtps_profile.xml and sets {VARIABLE} to the path inside the container")
    _commands(s, services)
    _domain(s, services)


def _commands(s: Session, services: dict[str, dict]) -> None:
    """``compose_commands``: a service whose command starts a talker, and another that echoes /chatter."""
    scripts, problems = {}, []
    for name, service in services.items():
        script, problem = _command_script(service)
        scripts[name] = script
        if problem:
            problems.append(f"{name}: {problem}")
    talkers = [n for n, text in scripts.items() if TALKER.search(text)]
    listeners = [n for n, text in scripts.items() if LISTENER.search(text) and n not in talkers[:1]]
    ok = bool(talkers) and bool(listeners)
    found = (f"talker: {talkers[0] if talkers else 'none'}; listener: {listeners[0] if listeners else 'none'}")
    s.record("compose_commands", ok, "; ".join([found, *problems]),
             "one service runs ros2 run demo_nodes_cpp talker, another ros2 topic echo /chatter, each as its "
             "command (a shell with -c and a script, or ros2 itself)")


def _command_script(service: dict) -> tuple[str, str]:
    """``(script, problem)``: the text a compose service's ``command:`` runs, as docker would start it
    (a string is split like a shell's words, docker compose docs: command), and why it runs nothing ("" if it
    runs something)."""
    command = service.get("command")
    if command is None:
        return "", "no command: (the image's default command starts no ROS program)"
    try:
        argv = shlex.split(command) if isinstance(command, str) else [str(word) for word in command]
    except ValueError as exc:
        return "", f"its command cannot be split into words ({exc})"
    if not argv:
        return "", "an empty command"
    if argv[0] in SHELLS:
        if len(argv) < 3 or argv[1] != "-c":
            return "", f"{argv[0]} is given {' '.join(argv[1:]) or 'nothing'!r}, not -c and a script"
        return argv[2], "" if argv[2].strip() else f"{argv[0]} -c is given an empty script"
    if argv[0] == "ros2":
        return shlex.join(argv), ""
    return "", f"the command starts {argv[0]!r}, which is neither a shell ({SHELLS[0]} -c \"...\") nor ros2"


def _domain(s: Session, services: dict[str, dict]) -> None:
    """``compose_domain``: every service's ROS_DOMAIN_ID (0 when unset) is a valid domain id, the same in all."""
    ids = {name: dds.environment(service).get("ROS_DOMAIN_ID", "0").strip() for name, service in services.items()}
    invalid = [f"{n}: ROS_DOMAIN_ID={v!r} is not an integer from 0 to {MAX_DOMAIN_ID}" for n, v in ids.items()
               if not (v.isdigit() and int(v) <= MAX_DOMAIN_ID)]
    same = len({int(v) for v in ids.values() if v.isdigit()}) <= 1
    shown = ", ".join(f"{n}: {v}" for n, v in ids.items())
    s.record("compose_domain", bool(ids) and not invalid and same,
             "; ".join(invalid) or (f"one domain id ({shown})" if same else f"different domain ids ({shown}): "
                                    "the listener never hears the talker"),
             "the same ROS_DOMAIN_ID (an integer from 0 to 232) in every service, or in none")


def _profile_problem(service: dict, compose: Path) -> str:
    """Why a compose service would not use the profile ("" if it would). A relative host path of a bind mount is
    relative to the compose file's folder (Compose file reference, volumes): it must lead to the learner's
    ``docker/fastrtps_profile.xml``, not merely end in that name (helper audit of issue 37: ``./docker/...``
    from docker/compose.yml passed; Docker then mounts an empty folder it makes, and Fast DDS falls back to
    its default transports, shared memory included)."""
    named = {target: source for target, source in dds.mounts(service).items()
             if PurePosixPath(source).name == "fastrtps_profile.xml"}
    wanted = os.path.normpath(compose.parent / PurePosixPath(PROFILE).name)
    mounted = [target for target, source in named.items()
               if os.path.normpath(compose.parent / os.path.expanduser(source)) == wanted]
    env = dds.environment(service)
    value = env.get(VARIABLE)
    if volume := next((v for v in dds.named_volumes(service) if PurePosixPath(v).name == "fastrtps_profile.xml"), ""):
        return (f"volumes: {volume}:... names a Docker volume, not the file: in the short syntax a host path "
                "starts with ./ (./fastrtps_profile.xml)")
    absolute = sorted(source for source in named.values() if source.startswith(("/", "~")))
    if absolute:  # the lesson: "a path relative to the compose file"; an absolute one is only this machine's
        return (f"the profile is mounted from the absolute host path {absolute[0]}: it exists on your machine "
                "only; give it relative to the compose file, ./fastrtps_profile.xml")
    if named and not mounted:
        return (f"the profile is mounted from {', '.join(sorted(set(named.values())))}, which from {COMPOSE}'s "
                f"folder is not {PROFILE} (a relative path starts at the compose file: ./fastrtps_profile.xml)")
    if not mounted:
        return "fastrtps_profile.xml is not mounted (volumes:)"
    if value is None:
        other = [k for k in dds.PROFILE_VARIABLES[1:] if k in env]
        return f"{VARIABLE} is not set" + (f" ({other[0]} is Fast DDS 3's name: Jazzy's Fast DDS 2.14 ignores it)"
                                           if other else "")
    if value not in mounted:
        return f"{VARIABLE}={value}, but the profile is mounted at {', '.join(mounted)}"
    if env.get(DISCOVERY_RANGE, "").strip().upper() == "LOCALHOST":  # the lesson's "Where the tutorial differs"
        return (f"{DISCOVERY_RANGE}=LOCALHOST: Jazzy's RMW then chooses the transports itself (shared memory on) "
                "whatever the profile says; leave it unset in a container")
    return ""
