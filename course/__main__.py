"""``python -m ros2course`` runs the ``ros2course`` command line."""

from ros2course.cli import main

main()
