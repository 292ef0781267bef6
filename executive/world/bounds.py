"""A value kept within bounds, as ``max(low, min(high, value))`` gives it (ties and NaN alike), without the builtin calls.

The vehicle models, the simulated autopilots and the executive's own rover motion do this every 20 ms step, where the
builtins cost several times a comparison.
"""

from __future__ import annotations


def clamp(value: float, limit: float) -> float:
    """``max(-limit, min(limit, value))``, ties and NaN alike."""
    value = value if value < limit else limit
    return value if value > -limit else -limit


def within(value: float, low: float, high: float) -> float:
    """``max(low, min(high, value))``, ties and NaN alike."""
    value = value if value < high else high
    return value if value > low else low
