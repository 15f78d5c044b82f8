#!/usr/bin/env python3
"""Print ``Howdy!`` twice a second until Ctrl+C."""
import time


def main() -> None:
    """Print ``Howdy!`` every 0.5 s; return quietly on Ctrl+C, report any other error."""
    try:
        while True:
            print("Howdy!", flush=True)
            time.sleep(0.5)
    except KeyboardInterrupt:
        pass
    except Exception as e:  # still developing: say what went wrong instead of a raw traceback
        print(e)


if __name__ == "__main__":
    main()
