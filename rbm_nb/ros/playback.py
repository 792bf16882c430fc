"""``play_publisher``: the reference package's playback widget, as a Player."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy.typing as npt

if TYPE_CHECKING:
    from ..widgets.player import Player


def play_publisher(
    publisher: Any,
    step: int = 1,
    speed: float = 1.0,
    skip: int | None = None,
    timestamps: npt.ArrayLike | None = None,
) -> Player:
    """Interactive widget for playing back messages from a publisher.

    Parameters
    ----------
    publisher : object
        Anything with a ``publish(idx)`` method (or ``set_time(t)``), e.g. a
        :class:`~rbm_nb.ros.ReferenceFrameTransformBroadcaster`.
    step : int, default 1
        Index difference between consecutive messages while playing.
    speed : float, default 1.0
        Playback speed.
    skip : int, optional
        Messages jumped by the skip buttons.
    timestamps : array_like, optional
        Timestamps of the publisher's messages (float seconds or datetime64);
        by default the publisher's ``timestamps`` attribute. The play interval
        is their mean difference times ``step`` over ``speed``.

    Returns
    -------
    rbm_nb.widgets.Player
        The player, already linked to the publisher; it displays itself as
        the last expression of a cell.

    Raises
    ------
    ValueError
        If no timestamps are given and the publisher has none (a static
        transform has nothing to play).
    """
    # lazy (optional dependency): the Player needs anywidget
    from ..widgets.player import Player

    if timestamps is None:
        timestamps = getattr(publisher, "timestamps", None)
        if timestamps is None:
            raise ValueError(
                f"play_publisher: {type(publisher).__name__} has no timestamps (a static "
                "transform has nothing to play); pass timestamps=..."
            )
    player = Player(timestamps, step=step, speed=speed, skip=skip)
    if not (
        callable(getattr(publisher, "publish", None))
        or callable(getattr(publisher, "set_time", None))
    ):
        player.close()
        raise TypeError(
            f"play_publisher: {type(publisher).__name__} has no publish(idx) method"
        )
    player.link(publisher)
    return player
