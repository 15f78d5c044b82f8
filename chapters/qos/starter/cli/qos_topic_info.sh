#!/usr/bin/env bash
# Show the QoS of every endpoint of the lesson's two topics (qos lesson).
# Run it from the workspace root, with the workspace sourced:  bash cli/qos_topic_info.sh

# A ros2 daemon that just started has not discovered every node yet:
# start it, then ask again (up to 10 times) until both topics show up.
ros2 daemon start
for attempt in 1 2 3 4 5 6 7 8 9 10; do
  TOPICS=$(ros2 topic list)
  if grep -qx /temperature <<< "${TOPICS}" && grep -qx /sensor_config <<< "${TOPICS}"; then
    break
  fi
  sleep 1
done

# TODO: these print only the type and the counts. Make each one list every endpoint
#       with its node name and its QoS profile (one option of `ros2 topic info`).
ros2 topic info /temperature
ros2 topic info /sensor_config
