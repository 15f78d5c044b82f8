#!/usr/bin/env bash
# Create (or update) .venv with ros2course, ROS 2 Jazzy from PyPI and the test
# tools (and Dask, for the batch grader's cluster test), repair the wheels' CMake
# files, then build the ROS 2 pieces PyPI lacks (ros2 CLI, launch, rclcpp) from
# their pinned sources into .venv/opt/ros2course-jazzy (course/ros/underlay.py; about
# 4 min on 2 cores the first time, a no-op afterwards). Idempotent; run from anywhere.
#
# Sources: $ROS2COURSE_ROS_SOURCES, else ../shared/ros-src beside the project when
# it exists, else GitHub. If the underlay cannot be built, setup goes on (Python
# lessons work without it) unless ROS2COURSE_REQUIRE_UNDERLAY=1 (CI).
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"
VENV="${VENV:-.venv}"
# A sourced system ROS 2 (/opt/ros/jazzy/setup.bash; not our own activation script, which
# sets ROS2COURSE_ENV): use it as it is, without the ROS wheels (the `ros` extra).
SYSTEM_ROS=""
if [ -n "${ROS_DISTRO:-}" ] && [ -n "${AMENT_PREFIX_PATH:-}" ] && [ -z "${ROS2COURSE_ENV:-}" ]; then
  SYSTEM_ROS=1
fi
if [ ! -x "$VENV/bin/python" ]; then
  # With a system ROS the venv must see apt's Python packages (python3-numpy, -yaml, -lark,
  # -empy, -catkin-pkg... that /opt/ros's rclpy, messages and launch import; only
  # /opt/ros/jazzy/lib/python3.X/site-packages comes through PYTHONPATH): --system-site-packages,
  # as the ROS 2 docs say for venvs (scripts/system_ros_standin.sh is the test stand-in).
  "$PYTHON" -m venv ${SYSTEM_ROS:+--system-site-packages} "$VENV"
  "$VENV/bin/python" -m pip install --quiet --upgrade pip
fi
if [ -n "$SYSTEM_ROS" ]; then
  echo "using the sourced ROS 2 $ROS_DISTRO"
  "$VENV/bin/python" -m pip install --quiet -e '.[test,dask,mutate,nottf2]'
  "$VENV/bin/ros2course" doctor --fix >/dev/null || "$VENV/bin/ros2course" doctor
  exit 0
fi
"$VENV/bin/python" -m pip install --quiet -e '.[ros,test,dask,mutate,nottf2]'
if ! "$VENV/bin/ros2course" env --build; then
  echo "setup: the ROS 2 underlay (ros2 CLI, launch, rclcpp) is missing; Python lessons still work" >&2
  if [ "${ROS2COURSE_REQUIRE_UNDERLAY:-0}" = 1 ]; then exit 1; fi
fi
"$VENV/bin/ros2course" doctor >/dev/null || "$VENV/bin/ros2course" doctor
echo "activate ROS 2 Jazzy in a terminal with:  source \"\$($VENV/bin/ros2course env --path)\""
