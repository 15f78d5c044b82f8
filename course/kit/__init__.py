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
names the major version its graders are written for (``kit: "1"``).

The kit's modules, by what they observe (graders import the ones they use,
``from ros2course.kit import scripts``):

* nodes, node_watch, judge, checks, parts: executables, nodes, rates, Ctrl+C, shared check declarations;
* topics_services, services, quotes, params, launch: the Python track's topics, services, parameters, launch;
* scripts, mystery, mystery_services: the ``ros2`` command-line lessons and the grader's own "mystery" nodes;
* dds: Fast DDS profiles tried by grader nodes in child processes;
* joint_stream, sas: the SmartArmStack driver's 500 Hz stream and the stand-in driver;
* packages, packaging, cpp_packages, cmake: package.xml, setup.py, CMake installs and consumers;
* programs, python_programs, asyncio_trace, pip, files: learner programs that are not nodes.
"""

from ros2course.grade.engine import Check, GradingSession, Unmet
from ros2course.kit_version import API_VERSION
from ros2course.kit.judge import RATE_TOLERANCE, STANDARD_TOPICS, rate, topics_seen
from ros2course.kit.nodes import (
    StartedNode,
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
    "API_VERSION", "RATE_TOLERANCE", "STANDARD_TOPICS", "Check", "GradingSession", "StartedNode", "Unmet", "declared_dependencies",
    "depends", "executable", "process_state", "project_files", "rate", "sigint_exit", "source_package", "start_node", "topics_seen",
    "wait_for_node",
]
