#!/usr/bin/env bash
# Look up message and service definitions with `ros2 interface` (tutorial ch. 16 and 17.10).
# Run it from the workspace root, with the workspace sourced:  bash cli/inspect_interfaces.sh

# TODO 1: show the definition of std_msgs/msg/String.

# TODO 2: show the definition of geometry_msgs/msg/Point.

# TODO 3: list the interface types of your package_with_interfaces.
ros2 interface packages

# TODO 4: show your AmazingQuote message and your WhatIsThePoint service.
