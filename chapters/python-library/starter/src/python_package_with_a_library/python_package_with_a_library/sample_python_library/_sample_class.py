class SampleClass:
    """A class other ROS 2 packages can import: it keeps a name."""

    def __init__(self, name: str) -> None:
        # TODO: keep the name in a private attribute
        pass

    def get_name(self) -> str:
        """Return the name given to the constructor."""
        # TODO: return the name kept by __init__
        raise NotImplementedError('get_name')
