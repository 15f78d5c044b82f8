"""ros2course: a course runner and autograder for learning ROS 2 Jazzy with real nodes.

Subpackages follow the pipeline: ``lesson`` (catalog, starters, the learner's
progress) -> ``build`` (colcon, the workspace overlay) -> ``run`` (learner
processes, probes on the ROS graph) -> ``grade`` (check declarations, the grading session, the engine, the result
model, ``watch``, course validation) -> ``report`` (console table,
gradebook). ``sandbox`` keeps a submission's code under its own uid and
limits (used by build and run); ``ros`` is the ROS 2 install (activation,
the source-built underlay, package manifests, the ament index, interface
types); ``files`` and ``errors`` serve every layer; ``batch`` grades a whole
class; ``cli`` is the command line.

Layers, top to bottom (a module imports only layers below its own; checked
by ``lint-imports``, pyproject.toml): cli, batch, report, grade, run, build,
sandbox, lesson, ros, files | errors. No import cycles, also not inside
functions.
"""

__version__ = "0.1.0"
