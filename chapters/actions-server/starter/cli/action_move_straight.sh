#!/bin/bash
# The MoveStraightIn2D action from the terminal. Run it with a goal's x and y (metres):
#   bash cli/action_move_straight.sh 0.6 0.8
# TODO: list the actions in the graph
# TODO: show who serves /move_straight_in_2d (ros2 action info)
# TODO: send the goal ($1, $2) to /move_straight_in_2d and print its feedback
#       (ros2 action send_goal --feedback <action> <type> "<goal in YAML>")
