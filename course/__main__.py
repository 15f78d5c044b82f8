"""``python -m course`` runs the ``ros2course`` command line."""

from course.cli import main

main()
