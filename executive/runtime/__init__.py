"""The runtime: the fixed-rate loop, how a run is put together from plugs, the services around each tick, and its pacing."""

import executive


def __getattr__(name: str) -> object:  # the names of the module this package replaced (0.2), for one release
    return executive.moved_attribute(__name__, name)
