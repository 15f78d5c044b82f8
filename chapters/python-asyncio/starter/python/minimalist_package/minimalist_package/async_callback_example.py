"""Two tasks run concurrently; a callback handles each result as soon as it is ready."""

import asyncio
from functools import partial  # noqa: F401  (you will need it)

from minimalist_package.minimalist_async import unlikely_to_return  # noqa: F401  (you will need it)


def handle_return_callback(tag: str, future: asyncio.Future) -> None:
    """Print the result of a finished task.

    :param tag: which task this was (bound with functools.partial).
    :param future: the finished task; asyncio passes it as the last argument.
    """
    if future is not None and future.done() and not future.cancelled() and future.exception() is None:
        # The tutorial has a typo here ({future.result().}): the expression is future.result()
        print(f"The result of task={tag} was {future.result()}.")
    else:
        print(f"Problem with task={tag}.")


async def async_main() -> None:
    """Start both tasks with a done-callback each, then wait until both are done."""
    tags: list[str] = ["task1", "task2"]
    # TODO 1: for each tag, create the task and attach the callback:
    #         task.add_done_callback(partial(handle_return_callback, tag))
    print("Awaiting results...")
    # TODO 2: await every task, only so that asyncio.run() does not return before they end.
    del tags


def main() -> None:
    """Run the example until both tasks have returned (Ctrl+C stops it quietly)."""
    try:
        asyncio.run(async_main())
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
