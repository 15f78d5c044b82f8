"""Grader for ``fastdds-udp-profile`` (tutorial ch. 32.4.2 and 32.6.2; contract in shared/LESSONS.md).

``docker/fastrtps_profile.xml`` is graded live: two grader nodes in child
processes use it as their Fast DDS default profile and must exchange messages
without any shared-memory segment (:mod:`graders._dds`); Fast DDS's own
parser errors are quoted. ``docker/compose.yml`` is read, not run: two
services of one image, ``stop_signal: SIGINT``, the profile mounted and
``FASTRTPS_DEFAULT_PROFILES_FILE`` pointing at the mounted file.
"""

from __future__ import annotations

from pathlib import PurePosixPath

from ros2course.kit import Check, Session, Unmet
from . import _dds as dds

PROFILE = "docker/fastrtps_profile.xml"
COMPOSE = "docker/compose.yml"
VARIABLE = dds.PROFILE_VARIABLES[0]

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
    s.record("compose_services", not error and one_image,
             error or ", ".join(f"{n}: image {i!r}" for n, i in images.items()) or "no service",
             f"{COMPOSE} has two services using one image")
    wrong = [n for n, svc in services.items() if str(svc.get("stop_signal", "")).upper() not in ("SIGINT", "INT", "2")]
    s.record("compose_stop_signal", not wrong and bool(services),
             f"no `stop_signal: SIGINT` in {', '.join(wrong)}" if wrong else "every service stops with SIGINT",
             "stop_signal: SIGINT in every service (Ctrl+C, as the nodes expect)")
    bad = [f"{n}: {why}" for n, svc in services.items() if (why := _profile_problem(svc))]
    s.record("compose_profile", not bad and bool(services), "; ".join(bad) or
             f"every service mounts fastrtps_profile.xml and sets {VARIABLE} to it",
             f"each service mounts fastrtps_profile.xml and sets {VARIABLE} to the path inside the container")


def _profile_problem(service: dict) -> str:
    """Why a compose service would not use the profile ("" if it would)."""
    mounted = [target for target, source in dds.mounts(service).items()
               if PurePosixPath(source).name == "fastrtps_profile.xml"]
    env = dds.environment(service)
    value = env.get(VARIABLE)
    if not mounted:
        return "fastrtps_profile.xml is not mounted (volumes:)"
    if value is None:
        other = [k for k in dds.PROFILE_VARIABLES[1:] if k in env]
        return f"{VARIABLE} is not set" + (f" ({other[0]} is Fast DDS 3's name: Jazzy's Fast DDS 2.14 ignores it)"
                                           if other else "")
    if value not in mounted:
        return f"{VARIABLE}={value}, but the profile is mounted at {', '.join(mounted)}"
    return ""
