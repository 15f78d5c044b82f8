"""Unit tests of MinimalistClass."""
import unittest

from minimalist_package import MinimalistClass


class TestMinimalistClass(unittest.TestCase):
    """unittest runs every method whose name starts with test_."""

    def setUp(self) -> None:
        """A fresh instance before each test, with values that differ from the defaults."""
        self.minimalist_instance = MinimalistClass(attribute_arg=15.0, private_attribute_arg=35.0)

    def test_attribute(self) -> None:
        self.assertEqual(self.minimalist_instance.attribute, 15.0)

    # TODO: one test each for _private_attribute, method(), the getter and setter, and static_method()


if __name__ == "__main__":
    unittest.main()
