"""Two tasks run concurrently; their results are handled in the order we await them."""

import asyncio

from minimalist_package.minimalist_async import unlikely_to_return  # noqa: F401  (you will need it)


async def async_main() -> None:
    """Start both tasks first, then await each one in turn."""
    tags: list[str] = ["task1", "task2"]
    # TODO 1: make one asyncio.Task per tag with asyncio.create_task(unlikely_to_return(tag=...)),
    #         ALL of them before the first await (that is what makes them concurrent).
    print("Awaiting results...")
    # TODO 2: for each (tag, task), in order: result = await task, then print
    #         f"The result of task={tag} was {result}."
    del tags


def main() -> None:
    """Run the example until both tasks have returned (Ctrl+C stops it quietly)."""
    try:
        asyncio.run(async_main())
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
