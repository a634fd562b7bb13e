"""Passing a request on after a middleware has read its body: the body message is given again."""

from __future__ import annotations

from starlette.types import Message, Receive


def replaying(message: Message, receive: Receive) -> Receive:
    """Return a ``receive`` that gives ``message`` (the body, already read) first, then what ``receive`` gives."""
    delivered = False

    async def replay() -> Message:
        nonlocal delivered
        if delivered:
            return await receive()
        delivered = True
        return message

    return replay
