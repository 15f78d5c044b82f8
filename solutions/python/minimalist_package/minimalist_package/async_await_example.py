"""Two tasks run concurrently; their results are handled in the order we await them."""

import asyncio

from minimalist_package.minimalist_async import unlikely_to_return


async def async_main() -> None:
    """Start both tasks first, then await each one in turn."""
    tags: list[str] = ["task1", "task2"]
    # Creating every task before the first await is what makes them concurrent.
    tasks: list[asyncio.Task] = [asyncio.create_task(unlikely_to_return(tag=tag)) for tag in tags]

    print("Awaiting results...")
    # Results come IN THE ORDER OF THE AWAITS, even when task2 finishes first.
    for tag, task in zip(tags, tasks):
        result = await task
        print(f"The result of task={tag} was {result}.")


def main() -> None:
    """Run the example until both tasks have returned (Ctrl+C stops it quietly)."""
    try:
        asyncio.run(async_main())
    except KeyboardInterrupt:
        pass


if __name__ == "__main__":
    main()
