#!/usr/bin/env bash
# Look up message and service definitions with `ros2 interface` (tutorial ch. 16 and 17.10).
# Run it from the workspace root, with the workspace sourced:  bash cli/inspect_interfaces.sh
# (no node needs to run: interfaces are files installed with their packages).

# 1. A message of the standard library: one string field.
ros2 interface show std_msgs/msg/String

# 2. A geometry message: three float64 fields.
ros2 interface show geometry_msgs/msg/Point

# 3. Every interface type your package provides.
ros2 interface package package_with_interfaces

# 4. Your own message and service, as the build installed them.
ros2 interface show package_with_interfaces/msg/AmazingQuote
ros2 interface show package_with_interfaces/srv/WhatIsThePoint
