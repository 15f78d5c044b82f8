#!/usr/bin/env bash
# Inspect a running system with `ros2 topic` (tutorial ch. 19).
# Run it from the workspace root, with the workspace sourced:  bash cli/inspect_topics.sh

# 1. Find the mystery topic: every topic with "quote" in its name, except the inbox.
#    The ros2 daemon caches the graph for every later command; a daemon that just started
#    has not discovered every node yet, so ask it again until the topic shows up.
ros2 daemon start
for attempt in 1 2 3 4 5 6 7 8 9 10; do
  TOPIC=$(ros2 topic list | grep quote | grep -v amazing_quote_in) && break
  sleep 1
done
echo "The mystery topic is ${TOPIC}"

# 2. Its type and how many publishers and subscriptions it has.
ros2 topic info "${TOPIC}"

# 3. One message, then stop (--once). Naming the type (the one `info` printed) lets echo
#    subscribe at once; without it, echo asks the graph for the type and gives up with
#    "does not appear to be published yet" when discovery has not caught up.
ros2 topic echo --once "${TOPIC}" package_with_interfaces/msg/AmazingQuote

# 4. Send one quote to the inbox, then stop (--once).
ros2 topic pub --once /amazing_quote_in package_with_interfaces/msg/AmazingQuote \
  "{id: 1994, quote: So you are telling me there is a chance, philosopher_name: Lloyd}"
