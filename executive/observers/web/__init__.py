"""The live view in a browser: ``executive run --web [HOST:]PORT`` and ``executive replay SNAPSHOTS --web PORT``.

The tick loop never waits for the web side. Each tick the runtime's :class:`~executive.observers.web.feed.LiveFeed`
(a service the :func:`~executive.observers.web.plug.live_view` plug adds) keeps the vehicle's track and, when the web side has asked
for one, hands over an immutable :class:`~executive.observers.web.feed.Frame` (the latest wins). The server
(:mod:`executive.observers.web.server`, aiohttp in a thread of its own) sends frames to each browser over a
WebSocket at its own pace, and passes pause / resume / abort back to the operator, answered on the
tick thread as ``executive ctl``'s are. Every asset is served from this package: no internet.
"""
