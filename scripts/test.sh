#!/usr/bin/env bash
# The whole test suite: unit tests, integration tests with real ROS 2 nodes,
# and the course's self-validation (every lesson's reference, starter and wrong
# solutions). Run from the repository root inside the project's venv.
set -euo pipefail
cd "$(dirname "$0")/.."
python -m pytest -q -p no:cacheprovider "$@"
