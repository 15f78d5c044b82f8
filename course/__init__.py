"""ros2course: a course runner and autograder for learning ROS 2 Jazzy with real nodes.

Subpackages follow the pipeline: ``lesson`` (catalog, starters, the learner's
progress) -> ``build`` (colcon, the workspace overlay) -> ``run`` (learner
processes, the batch sandbox, probes on the ROS graph) -> ``grade`` (the
engine, the result model, course validation) -> ``report`` (console table,
gradebook). ``ros`` is the ROS 2 install (activation, the source-built
underlay, the ament index, interface types); ``batch`` grades a whole class;
``cli`` is the command line.
"""

__version__ = "0.1.0"
