"""ros2course: a course runner and autograder for learning ROS 2 Jazzy with real nodes.

Modules: ``env`` (ROS install, doctor), ``lesson`` (lesson files), ``progress``
(workspace and progress file), ``build`` (colcon), ``process`` (learner
processes), ``probes`` (ROS graph probes), ``grading`` (engine), ``report``
(rendering), ``validate`` (the course checks itself), ``cli`` (command line).
"""

__version__ = "0.1.0"
