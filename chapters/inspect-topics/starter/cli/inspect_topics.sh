#!/usr/bin/env bash
# Inspect a running system with `ros2 topic` (tutorial ch. 19).
# Run it from the workspace root, with the workspace sourced:  bash cli/inspect_topics.sh
# Every command must end by itself: nobody presses Ctrl+C in a script.

# A ros2 daemon that just started has not discovered every node yet:
# start it, then ask again (up to 10 times) until the topic shows up.
ros2 daemon start
for attempt in 1 2 3 4 5 6 7 8 9 10; do
  # TODO 1: keep only the topic whose name contains "quote" but is not /amazing_quote_in
  #         (grep it; the loop stops as soon as the pipeline finds a line).
  TOPIC=$(ros2 topic list) && break
  sleep 1
done
echo "The mystery topic is ${TOPIC}"

# TODO 2: print its type and publisher count (ros2 topic info).

# TODO 3: print ONE message from it (ros2 topic echo, made to stop after one).

# TODO 4: publish ONE package_with_interfaces/msg/AmazingQuote with id 1994 and
#         philosopher_name Lloyd on /amazing_quote_in (ros2 topic pub).
