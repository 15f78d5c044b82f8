#!/usr/bin/env bash
# Inspect and call a service with `ros2 service` (tutorial ch. 21).
# Run it from the workspace root, with the workspace sourced:  bash cli/inspect_services.sh
# Every command must end by itself: nobody presses Ctrl+C in a script.

# TODO 1: print every service in the graph.

# TODO 2 (optional): print the type of /what_is_the_point (you need it for the calls).

# TODO 3: call /what_is_the_point with a quote that contains "life".
#         The request's only field is `quote`, an AmazingQuote: write it as nested YAML,
#         "{quote: {id: ..., quote: ..., philosopher_name: ...}}".

# TODO 4: call it again with a quote that does not contain "life".
