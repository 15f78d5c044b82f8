#!/usr/bin/env bash
# Create (or update) .venv with ros2course, ROS 2 Jazzy from PyPI and the test
# tools (and Dask, for the batch grader's cluster test), then repair the wheels' CMake files. Idempotent; run from anywhere.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python3}"
VENV="${VENV:-.venv}"
if [ ! -x "$VENV/bin/python" ]; then
  "$PYTHON" -m venv "$VENV"
  "$VENV/bin/python" -m pip install --quiet --upgrade pip
fi
if [ -n "${ROS_DISTRO:-}" ] && [ -n "${AMENT_PREFIX_PATH:-}" ]; then
  echo "using the sourced ROS 2 $ROS_DISTRO"
  "$VENV/bin/python" -m pip install --quiet -e '.[test,dask]'
else
  "$VENV/bin/python" -m pip install --quiet -e '.[ros,test,dask]'
fi
"$VENV/bin/ros2course" doctor --fix >/dev/null || "$VENV/bin/ros2course" doctor
