"""Building a workspace with colcon and sourcing its overlay."""
