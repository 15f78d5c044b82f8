#!/usr/bin/env bash
# Gradescope autograder setup (runs once, as root, when Gradescope builds the image).
# Gradescope unpacks the autograder zip into /autograder/source: zip this whole repository
# (see docs/instructors.md "On Gradescope"), with gradescope/lesson naming the lesson(s) to grade.
set -euo pipefail
export DEBIAN_FRONTEND=noninteractive
apt-get update -q
# python3 with venv, cmake and a C++ compiler (ament_cmake lessons), util-linux + iproute2
# (per-submission network / mount namespaces when the container allows them)
apt-get install -y -q python3 python3-venv python3-pip cmake g++ util-linux iproute2
cd /autograder/source
VENV=/autograder/ros2course-venv bash scripts/setup.sh
