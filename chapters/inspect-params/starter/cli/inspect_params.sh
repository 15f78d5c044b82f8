#!/usr/bin/env bash
# Inspect and change a running node's parameters with `ros2 param` (tutorial ch. 24).
# Run it from the workspace root, with the workspace sourced:  bash cli/inspect_params.sh
NODE=/peanut_butter_falcon_quote_publisher_node

# A freshly started ros2 daemon may not know the node yet: start it, wait until it lists the node.
ros2 daemon start
for attempt in 1 2 3 4 5 6 7 8 9 10; do
  ros2 node list | grep -q "^${NODE}$" && break
  sleep 1
done

# TODO 1: print the node's parameter names (ros2 param list).

# TODO 2: print its current quote (ros2 param get).

# TODO 3: set quote to: You got a good-guy heart. That's just who you are.

# TODO 4: save all its parameters to cli/params_dump.yaml (ros2 param dump, then a redirection).
