"""The minimalist package (a folder with an __init__.py is a Python package)."""
# TODO: export the class, so that users can write
#       from minimalist_package import MinimalistClass
#       (import it with the package's full name, not with a relative "from . import").
