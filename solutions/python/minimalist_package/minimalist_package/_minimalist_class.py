"""The module behind ``minimalist_package.MinimalistClass`` (the leading underscore: import it from the package)."""


class MinimalistClass:
    """A class with one of each basic ingredient: class attribute, attributes, methods, a static method."""

    #: Shared by every instance and reachable without one: ``MinimalistClass.attribute_reference``.
    attribute_reference: str = "Hello "

    def __init__(self, attribute_arg: float = 10.0, private_attribute_arg: float = 20.0) -> None:
        """Store the two numbers.

        :param attribute_arg: the public attribute's value.
        :param private_attribute_arg: the private attribute's value (read it with the getter).
        """
        self.attribute: float = attribute_arg
        # one leading underscore: "not part of the public interface", by convention only
        self._private_attribute: float = private_attribute_arg

    def method(self) -> float:
        """Return the sum of the public and the private attribute."""
        return self.attribute + self._private_attribute

    def set_private_attribute(self, private_attribute_arg: float) -> None:
        """Replace the private attribute's value.

        :param private_attribute_arg: the new value.
        """
        self._private_attribute = private_attribute_arg

    def get_private_attribute(self) -> float:
        """Return the private attribute's value."""
        return self._private_attribute

    @staticmethod
    def static_method() -> str:
        """Return ``"Hello World!"``, built from the class attribute (no instance needed)."""
        return MinimalistClass.attribute_reference + "World!"
