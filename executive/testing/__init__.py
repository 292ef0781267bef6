"""``executive.testing``: test a behaviour tree tick by tick, and a whole mission in a deterministic simulation.

Installed with the package; its pytest plugin (entry point ``pytest11``) gives the fixtures below
to any project that installs ``executive``. Nothing here touches a socket or the wall clock.

Tick by tick (:class:`Harness`)
    ``h = Harness.build(mission, root=my_tree)`` sets a tree up as the runtime does, on a
    :class:`~executive.world.clock.ManualClock`, with the mission started. Script the inputs between
    ticks with ``h.vehicle.set(vehicle__mode="GUIDED", link__up=True, vehicle__ekf=...)`` (any
    documented blackboard key under ``/vehicle/``, ``/link/``, ``/rc/``, ``/heading/``), tick
    with ``h.tick(dt)``, answer commands with ``h.ack(MAV_CMD_...)`` and assert on
    ``h.asked()`` (``[("mode", "HOLD"), ("arm", True), ("goto", lat, lon, alt)...]``) and on
    ``h.status("Mission/.../My guard")`` / ``h.feedback(...)`` by path.

A scripted autopilot (:class:`ScriptedAutopilot`)
    Behind a harness, it acks modes and arming at once, steps toward GUIDED targets each tick
    and publishes mode, armed and position; ``refuse`` makes it say no. Subclass it to script
    another firmware (``on_command``, ``on_setpoint``, ``enter_mode``, ``move``, ``facts``).
    :class:`MissionAutopilot` holds a mission as ArduPilot does and drives it in AUTO (a harness
    built with ``transfer=True``).

A whole mission (:class:`Lockstep`)
    ``Lockstep(mission, events=["faults.yaml"]).run_to_end(limit_s=900)`` runs the runtime
    against the built-in simulated autopilot of the mission's kind (rover, boat, bunker with
    its CAN base, sub, vtol), with fault and operator-event files, on one clock stepped only
    when the runtime waits: deterministic, and as fast as the CPU allows. ``run(until=...)``
    stops at a moment of interest; ``at(t, action)`` and ``observers`` act and watch on the
    vehicle's clock. ``Lockstep(mission, overload=Overload(seed=7))`` runs it as an overloaded
    machine would, as deterministically: late and skipped ticks, a world stepped coarsely.

A whole runtime, by hand (:class:`RuntimeOnLink`)
    ``r = RuntimeOnLink(mission, root=..., beat=True)``: the runtime over a :class:`FakeLink`, an
    :class:`ObedientAutopilot` answering, its position (the mission's home) with its heartbeat: the
    runtime ticks no tree before it knows where the vehicle is (the distance rule, :mod:`executive.admission.reach`);
    ``r.tick(n)`` on its manual clock, ``r.modes_sent()``, ``r.texts()``, ``r.status``: for what
    lies around the tree (operator, intervention, plugs).

A CAN bus (:class:`VirtualCan`)
    ``with VirtualCan() as (base, ours):`` two ends of a fresh in-memory bus (python-can's
    ``virtual`` interface): what the base sends, the executive's end receives.

Fixtures (plugin :mod:`executive.testing.plugin`): ``clock``, ``link``, ``commander``,
``autopilot`` (the autopilot port over ``commander``), ``vehicle``, ``mission_state`` (the lifecycle: the leg and route at
``.legs``, the samples at ``.sample_log``), ``harness`` (``harness(root)``), ``lockstep``
(``lockstep(mission, ...)``, closed after the test), ``runtime_on_link`` (``runtime_on_link(mission, ...)``),
``can_buses`` (a :class:`VirtualCan`, shut after the test).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from executive import lazy_exports

if TYPE_CHECKING:
    from executive.testing.canbus import VirtualCan
    from executive.testing.harness import BATTERY_FULL, EKF_READY, START_S, Harness, Vehicle, describe, port_for
    from executive.testing.links import AUTOPILOT, GCS, FakeLink, Peer, ack
    from executive.testing.lockstep import Lockstep, LockstepClock, Overload, VehicleTimeLimit, Wire
    from executive.testing.missions import mission_errors
    from executive.testing.on_link import RuntimeOnLink
    from executive.testing.scripted import MissionAutopilot, ObedientAutopilot, ScriptedAutopilot

#: The module of the kit each name is in, imported on first use: pytest loads the plugin, and so this package, in every
#: process it starts, xdist's controller too, which runs no test (the whole kit cost it 0.6 s of CPU before its workers started).
_MODULE_OF = {
    **dict.fromkeys(("VirtualCan",), "canbus"),
    **dict.fromkeys(("BATTERY_FULL", "EKF_READY", "START_S", "Harness", "Vehicle", "describe", "port_for"), "harness"),
    **dict.fromkeys(("AUTOPILOT", "GCS", "FakeLink", "Peer", "ack"), "links"),
    **dict.fromkeys(("Lockstep", "LockstepClock", "Overload", "VehicleTimeLimit", "Wire"), "lockstep"),
    **dict.fromkeys(("mission_errors",), "missions"),
    **dict.fromkeys(("RuntimeOnLink",), "on_link"),
    **dict.fromkeys(("MissionAutopilot", "ObedientAutopilot", "ScriptedAutopilot"), "scripted"),
}

__all__ = [
    "AUTOPILOT",
    "BATTERY_FULL",
    "EKF_READY",
    "GCS",
    "START_S",
    "FakeLink",
    "Harness",
    "Lockstep",
    "LockstepClock",
    "MissionAutopilot",
    "ObedientAutopilot",
    "Overload",
    "Peer",
    "RuntimeOnLink",
    "ScriptedAutopilot",
    "Vehicle",
    "VehicleTimeLimit",
    "VirtualCan",
    "Wire",
    "ack",
    "describe",
    "mission_errors",
    "port_for",
]

__getattr__, __dir__ = lazy_exports(__name__, _MODULE_OF)
