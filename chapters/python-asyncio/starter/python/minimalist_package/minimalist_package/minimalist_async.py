"""A coroutine that keeps us waiting, to practise asyncio (tutorial ch. 2.5)."""

import asyncio  # noqa: F401  (you will need it)
import random  # noqa: F401  (you will need it)


async def unlikely_to_return(tag: str, likelihood: float = 0.1) -> float:
    """Draw random numbers in [0, 1) until one is below ``likelihood``.

    :param tag: a name printed with every message, to tell concurrent calls apart.
    :param likelihood: the chance (0 to 1) that one draw succeeds.
    :return: the successful draw, a float smaller than ``likelihood``.
    """
    # TODO: loop forever:
    #   - draw a roll with random.uniform(0.0, 1.0)
    #   - if it is below likelihood: print f"{tag} Done." and return the roll
    #   - otherwise print that a retry is needed and WAIT 0.1 s without blocking other tasks
    raise NotImplementedError("unlikely_to_return is not written yet")
