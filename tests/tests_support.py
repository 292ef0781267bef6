"""Test helpers of our own suite (the rest is the public kit, :mod:`executive.testing`): a runtime over a real socket."""

from __future__ import annotations

from typing import Any

from executive.assembly import build_runtime
from executive.clock import ScaledClock
from executive.io.mavlink.link import PymavlinkLink
from executive.mission.model import Mission
from executive.pacing import SpeedGovernor
from executive.runtime import Outcome, Runtime


def run_over(url: str, mission: Mission, clock: ScaledClock, **options: Any) -> tuple[Runtime, Outcome]:
    """A runtime on a real link to ``url`` (a simulator), connected and run to the mission's end; the link closed after.

    ``options`` go to :func:`~executive.assembly.build_runtime` (progress, plugs...).
    """
    link = PymavlinkLink(url)
    try:
        runtime = build_runtime(mission, link, clock, **options)
        runtime.pacer.listeners.append(SpeedGovernor(clock))  # as `executive run` does: a busy machine slows the world, not the verdict
        assert runtime.connect(10.0 * clock.speedup)
        return runtime, runtime.run()
    finally:
        link.close()
