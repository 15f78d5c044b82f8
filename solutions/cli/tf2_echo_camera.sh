#!/bin/bash
# Where is the camera, seen from the robot? tf2_echo prints the transform robot -> camera once a
# second until it is stopped: `timeout` sends it Ctrl+C's SIGINT after 3 s.
timeout --signal=INT 3 ros2 run tf2_ros tf2_echo robot camera
exit 0
