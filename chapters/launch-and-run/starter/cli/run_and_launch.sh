#!/usr/bin/env bash
# Start two things at once with `ros2 run` and `ros2 launch` (tutorial ch. 10 and 23).
# Run it from the workspace root, with the workspace sourced:  bash cli/run_and_launch.sh
# Stop it with Ctrl+C.

# TODO 3: keep bash alive when Ctrl+C comes (a trap on INT), so that it can wait for the nodes.

# TODO 1: start print_forever_node of python_package_with_a_node with ros2 run,
#         in the background (a command ending with & does not block the script).

# TODO 2: start peanut_butter_falcon_quote_publisher_launch.py of
#         python_package_that_uses_parameters_and_launch_files with ros2 launch, in the background.

# TODO 4: wait for both (and, after Ctrl+C, wait again until they have stopped).
