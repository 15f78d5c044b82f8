"""Unit tests of MinimalistClass: one test per element of the class."""
import unittest

from minimalist_package import MinimalistClass


class TestMinimalistClass(unittest.TestCase):
    """Each ``test_*`` method checks one thing; ``setUp`` gives each a fresh instance."""

    def setUp(self) -> None:
        """Make an instance with values that differ from the defaults."""
        self.minimalist_instance = MinimalistClass(attribute_arg=15.0, private_attribute_arg=35.0)

    def test_attribute(self) -> None:
        self.assertEqual(self.minimalist_instance.attribute, 15.0)

    def test_private_attribute(self) -> None:
        self.assertEqual(self.minimalist_instance._private_attribute, 35.0)

    def test_method(self) -> None:
        self.assertEqual(self.minimalist_instance.method(), 15.0 + 35.0)

    def test_get_private_attribute(self) -> None:
        self.assertEqual(self.minimalist_instance.get_private_attribute(), 35.0)

    def test_get_set_private_attribute(self) -> None:
        self.minimalist_instance.set_private_attribute(20.0)
        self.assertEqual(self.minimalist_instance.get_private_attribute(), 20.0)

    def test_static_method(self) -> None:
        self.assertEqual(MinimalistClass.static_method(), "Hello World!")


def main() -> None:
    """Run these tests when the file is run as a script."""
    unittest.main()


if __name__ == "__main__":
    main()
