#!/usr/bin/env bash
# Inspect and call a service with `ros2 service` (tutorial ch. 21).
# Run it from the workspace root, with the workspace sourced:  bash cli/inspect_services.sh

# 1. Every service in the graph (-t would add their types). In a terminal where no ros2 daemon
#    runs yet (a fresh ROS domain), the command listens for the nodes itself: give it 2 s, not
#    0.5 s. (The check's second run has no daemon, and its server joins 1 s after the list began.)
ros2 service list --spin-time 2

# 2. The type of /what_is_the_point: the one to give `ros2 service call`.
ros2 service type /what_is_the_point

# 3. A question about life: the answer's coordinates sum to 42.
ros2 service call /what_is_the_point package_with_interfaces/srv/WhatIsThePoint \
  "{quote: {id: 42, quote: What is the meaning of life, philosopher_name: Douglas}}"

# 4. A question about something else: they do not.
ros2 service call /what_is_the_point package_with_interfaces/srv/WhatIsThePoint \
  "{quote: {id: 7, quote: Use the force, philosopher_name: Ben}}"
