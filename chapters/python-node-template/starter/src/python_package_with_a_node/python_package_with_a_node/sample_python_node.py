def main():
    """Entry point of the template executable: greet and exit."""
    # TODO: print the greeting: Hi from python_package_with_a_node.
    pass


if __name__ == '__main__':
    main()
