#!/bin/bash
# The action of the actions-server lesson, from the terminal: which actions exist, who serves
# /move_straight_in_2d, and one goal sent with its feedback shown. The goal is the script's two
# arguments (metres): bash cli/action_move_straight.sh 0.5 -0.25
ros2 action list
ros2 action info /move_straight_in_2d
ros2 action send_goal --feedback /move_straight_in_2d package_with_interfaces/action/MoveStraightIn2D \
  "{desired_position: {x: $1, y: $2}}"
