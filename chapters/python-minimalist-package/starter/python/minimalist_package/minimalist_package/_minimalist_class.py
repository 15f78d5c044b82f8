"""The module behind minimalist_package.MinimalistClass."""


class MinimalistClass:
    """TODO: one line saying what this class is for."""

    # TODO: a class attribute `attribute_reference` (a str) holding "Hello "

    def __init__(self, attribute_arg: float = 10.0, private_attribute_arg: float = 20.0) -> None:
        """Store the two numbers."""
        # TODO: store attribute_arg in a public attribute named `attribute`
        # TODO: store private_attribute_arg in `_private_attribute` (leading underscore: private)

    # TODO: method(self) -> float returns the sum of the two attributes
    # TODO: set_private_attribute(self, private_attribute_arg: float) -> None
    # TODO: get_private_attribute(self) -> float

    @staticmethod
    def static_method():
        # TODO: return "Hello World!" built from attribute_reference; add a return type hint and a docstring
        raise NotImplementedError
