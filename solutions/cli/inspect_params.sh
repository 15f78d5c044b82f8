#!/usr/bin/env bash
# Inspect and change a running node's parameters with `ros2 param` (tutorial ch. 24).
# Run it from the workspace root, with the workspace sourced:  bash cli/inspect_params.sh
NODE=/peanut_butter_falcon_quote_publisher_node

# The ros2 daemon caches the graph for every later command; a daemon that just
# started has not discovered every node yet, so wait until it lists ours.
ros2 daemon start
for attempt in 1 2 3 4 5 6 7 8 9 10; do
  ros2 node list | grep -q "^${NODE}$" && break
  sleep 1
done

# 1. Which parameters does it have?
ros2 param list "${NODE}"

# 2. What does it say right now?
ros2 param get "${NODE}" quote

# 3. Change the quote while it runs (the next messages carry it).
ros2 param set "${NODE}" quote "You got a good-guy heart. That's just who you are."

# 4. Save every parameter in the parameters-file format (Jazzy prints it; > writes the file).
ros2 param dump "${NODE}" > cli/params_dump.yaml
