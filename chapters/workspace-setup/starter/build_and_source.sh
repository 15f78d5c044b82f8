#!/usr/bin/env bash
# Build the workspace and source its overlay (lesson workspace-setup).
# Usage: source build_and_source.sh   (from the workspace folder)
# No 'set -e' here: this file is sourced, and 'set -e' would then close your
# terminal at the next command that fails.

# TODO 1: go to the workspace folder, the one that contains src/
#         (hint: this script lives there: cd "$(dirname "${BASH_SOURCE[0]}")")

# TODO 2: build every package of the workspace with colcon

# TODO 3: source the overlay that colcon just created in install/
