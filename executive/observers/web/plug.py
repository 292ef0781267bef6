"""The live view as a plug of the runtime: ``executive run --web`` adds it (:func:`live_view`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from executive.observers.web.feed import LiveFeed
from executive.observers.web.server import LiveSource, WebServer
from executive.runtime.services import FunctionService

if TYPE_CHECKING:
    from executive.runtime.assembly import Plug, Wiring


def live_view(server: WebServer) -> Plug:
    """The live view in a browser on ``server``: a frame handed over after each tick it asks for one, its buttons' requests to the operator."""

    def plug(w: Wiring) -> None:
        feed = LiveFeed(w.mission_state, w.status, w.operator, w.clock.now)
        w.readers.append(FunctionService("live view requests", feed.answer))
        w.writers.append(FunctionService("live view", feed.publish))
        w.observers.append(feed)
        server.start(LiveSource(feed), ask=feed.ask)
        w.closers.append(server.close)

    return plug
