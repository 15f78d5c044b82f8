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

The kit's modules, by what they observe (graders import the ones they use,
``from graders.kit import scripts``):

* nodes, node_watch, judge, checks, parts: executables, nodes, rates, Ctrl+C, shared check declarations;
* topics_services, services, quotes, params, launch: the Python track's topics, services, parameters, launch;
* scripts, mystery, mystery_services: the ``ros2`` command-line lessons and the grader's own "mystery" nodes;
* dds: Fast DDS profiles tried by grader nodes in child processes;
* joint_stream, sas: the SmartArmStack driver's 500 Hz stream and the stand-in driver;
* packages, packaging, cpp_packages, cmake: package.xml, setup.py, CMake installs and consumers;
* programs, python_programs, asyncio_trace, pip, files: learner programs that are not nodes.
"""

from course.grade.engine import Check, GradingSession, Unmet
from graders.kit.judge import RATE_TOLERANCE, STANDARD_TOPICS, rate, topics_seen
from graders.kit.nodes import (
    StartedNode,
    executable,
    process_state,
    sigint_exit,
    start_node,
    wait_for_node,
)
from graders.kit.packages import (
    declared_dependencies,
    depends,
    project_files,
    source_package,
)

__all__ = [
    "RATE_TOLERANCE", "STANDARD_TOPICS", "Check", "GradingSession", "StartedNode", "Unmet", "declared_dependencies",
    "depends", "executable", "process_state", "project_files", "rate", "sigint_exit", "source_package", "start_node", "topics_seen",
    "wait_for_node",
]
