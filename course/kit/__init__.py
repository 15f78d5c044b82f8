"""The grader kit: the steps graders share, each recording its own check and returning a value.

A grader is ``CHECKS`` (what is graded, each :class:`Check` naming the checks
it ``needs``) plus a ``grade(s)`` that calls kit steps in order::

    path = kit.executable(s, "executable", PACKAGE, EXECUTABLE)       # raises Unmet if missing
    node = kit.start_node(s, "node_name", path, NODE, sigint_check="sigint_exit")
    kit.rate(s, "rate", stamps, period=0.5, needed=6, waited=..., noun="record", source="...")

A step that cannot hand back its value (no executable, the process died)
raises :class:`Unmet`; the engine then records every check that needs the
failed one as "not checked" with the reason, and still runs the closing
checks (Ctrl+C of a started node). Graders never write skip logic. See
graders/README.md for a whole grader.

This is the engine's public grading API (issue 18): a course's graders import
``ros2course.kit`` and its modules, nothing else of the engine. Its version is
:data:`API_VERSION` (``ros2course --version`` prints it); a course's ``course.yaml``
names the major version its graders are written for (``kit: "2"``).

A grader reaches the machine only through the session it is handed, typed
:class:`Session` (:mod:`ros2course.kit.session_protocol`: the members a grader may use; the engine's
:class:`GradingSession` implements it)
(learner processes: ``s.launch``, ``s.start_program``; colcon: ``s.run_colcon``; the
sourced workspace: ``s.overlay()``) and the steps here, which take that session.

The kit's modules, by what they observe (graders import the ones they use,
``from ros2course.kit import scripts``):

* nodes, judge, checks, parts: executables, nodes, rates, Ctrl+C, shared check declarations;
* topics_services, services, quotes, params, launch: the Python track's topics, services (the grader as a
  server's client or a client's server), parameters (and whether a node spins), launch;
* actions: the grader as an action client of a learner's server, or as a learner client's server;
* scripts, mystery: the ``ros2`` command-line lessons and the grader's own "mystery" nodes;
* packages, packaging, cmake: package.xml, setup.py, CMake installs and consumers;
* programs, python_programs, learner_files: learner programs that are not nodes, and files a learner made;
* testing: a learner's own tests, run on the course's reference and on hidden mutants of it.

Placement rule (issues 23 and 38): a step two lessons use, or another course's author
would, lives here; a helper of one lesson lives with that lesson's grader, as
``graders/_<name>.py`` of its course (the tutorial's asyncio trace, C++ package
consumers, Fast DDS profiles, the 500 Hz joint stream and the sas stand-in
driver, the mystery services, the launch node watch, pip installs, one lesson's
long procedures), imported with ``from . import _<name>``. tests/test_grader_shape.py
keeps it: no ``graders/_x.py`` imported by two lessons, no grader importing
another lesson's grader (a lesson's C++ twin aside), no kit module nobody imports.
"""

from ros2course.errors import NotGradable
from ros2course.grade.checklist import Check, Unmet
from ros2course.grade.session import GradingSession
from ros2course.kit_version import API_VERSION
from ros2course.ros.env import foreign_python_prefix
from ros2course.ros.index import package_prefix
from ros2course.ros.interfaces import component_type
from ros2course.run.probes import (
    LATE_DELIVERY,
    RateStats,
    call_service,
    record,
    stamp_seconds,
    stop_spinning,
    wait_until,
)
from ros2course.run.process import LearnerProcess
from ros2course.kit.session_protocol import Session
from ros2course.kit.judge import RATE_TOLERANCE, STANDARD_TOPICS, rate, topics_seen
from ros2course.kit.nodes import (
    StartedNode,
    ctrl_c_once_it_logs,
    executable,
    process_state,
    sigint_exit,
    start_node,
    wait_for_node,
)
from ros2course.kit.packages import (
    declared_dependencies,
    depends,
    project_files,
    source_package,
)

__all__ = [
    "LATE_DELIVERY", "LearnerProcess", "NotGradable", "RateStats", "call_service",
    "component_type", "foreign_python_prefix", "package_prefix", "record", "stamp_seconds", "stop_spinning",
    "wait_until",
    "API_VERSION", "RATE_TOLERANCE", "STANDARD_TOPICS", "Check", "GradingSession", "StartedNode", "ctrl_c_once_it_logs", "Unmet", "declared_dependencies",
    "depends", "executable", "process_state", "project_files", "rate", "sigint_exit", "source_package", "start_node", "topics_seen",
    "wait_for_node", "Session",
]
