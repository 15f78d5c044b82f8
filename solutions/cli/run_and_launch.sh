#!/usr/bin/env bash
# Start two things at once with `ros2 run` and `ros2 launch` (tutorial ch. 10 and 23).
# Run it from the workspace root, with the workspace sourced:  bash cli/run_and_launch.sh
# Stop it with Ctrl+C.

# Ctrl+C reaches every process of the terminal's foreground group: this script and the
# nodes. Without a trap, bash would die at once and leave the nodes stopping on their own;
# with one, it goes on to the second `wait` below.
trap 'echo "Ctrl+C: waiting for the nodes to stop"' INT

# 1. One node, with ros2 run, in the background (&).
ros2 run python_package_with_a_node print_forever_node &

# 2. The launch file of the launch-files lesson, in the background too.
ros2 launch python_package_that_uses_parameters_and_launch_files peanut_butter_falcon_quote_publisher_launch.py &

# 3. Wait for them: until Ctrl+C interrupts this first wait...
wait
# ...then until they have finished stopping.
wait
echo "Both are stopped."
