"""A coroutine that keeps us waiting, to practise asyncio (tutorial ch. 2.5)."""

import asyncio
import random


async def unlikely_to_return(tag: str, likelihood: float = 0.1) -> float:
    """Draw random numbers in [0, 1) until one is below ``likelihood``.

    Between two draws it awaits ``asyncio.sleep(0.1)`` (0.1 s), so other
    tasks run meanwhile.

    :param tag: a name printed with every message, to tell concurrent calls apart.
    :param likelihood: the chance (0 to 1) that one draw succeeds.
    :return: the successful draw, a float smaller than ``likelihood``.
    """
    while True:
        roll = random.uniform(0.0, 1.0)
        if roll < likelihood:
            print(f"{tag} Done.")
            return roll
        print(f"{tag} retry needed (roll = {roll} >= {likelihood}).")
        await asyncio.sleep(0.1)
