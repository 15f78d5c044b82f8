def main():
    """Entry point of the template executable: greet and exit."""
    print('Hi from python_package_with_a_node.')


if __name__ == '__main__':
    main()
