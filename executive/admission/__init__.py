"""Whether a mission may run on this executive: the checks made before any tree runs."""

import executive


def __getattr__(name: str) -> object:  # the names of the module this package replaced (0.2), for one release
    return executive.moved_attribute(__name__, name)
