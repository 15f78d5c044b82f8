# TODO: line 1 must be the shebang that finds python3 on PATH (not a fixed path such as /bin/python3)
"""Print Howdy! twice a second until Ctrl+C."""


def main() -> None:
    """Print 'Howdy!' every 0.5 s until Ctrl+C."""
    # TODO: loop forever: print Howdy!, then sleep 0.5 s (module time)
    # TODO: wrap the loop in try/except so that Ctrl+C ends it quietly
    print("Howdy!")


# TODO: when this file is run directly, call main() (and do nothing else there)
