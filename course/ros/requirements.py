"""The names a lesson's ``requires:`` may use (a leaf module: the catalog imports it on every ``list``).

What each name means, how it is probed and what to install live in
:mod:`ros2course.ros.env` (``probe_requirement``, ``doctor``).
"""

KNOWN_REQUIREMENTS = ("rclpy", "colcon", "ament_cmake", "rosidl", "cmake", "cxx", "rclcpp", "launch", "ros2", "tf2", "eigen3",
                      "qt5core")
