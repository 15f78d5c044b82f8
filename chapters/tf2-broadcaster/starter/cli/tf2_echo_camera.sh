#!/bin/bash
# Where is the camera, seen from the robot? Run it from the workspace root, with the workspace
# sourced and your broadcaster running:  bash cli/tf2_echo_camera.sh
#
# TODO: print the transform robot -> camera with tf2_echo (package tf2_ros). It prints once a
#       second until Ctrl+C: stop it after 3 s with `timeout --signal=INT 3 ...`, so that the
#       script ends by itself.
echo "nothing yet"
