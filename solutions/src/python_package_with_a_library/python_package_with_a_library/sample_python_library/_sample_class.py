class SampleClass:
    """A class other ROS 2 packages can import: it keeps a name."""

    def __init__(self, name: str) -> None:
        self._name = name

    def get_name(self) -> str:
        """Return the name given to the constructor."""
        return self._name
