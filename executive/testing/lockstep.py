"""A whole mission in one thread on one manual clock: the runtime, a simulated autopilot, the CAN base and instruments over in-memory links.

Nothing waits for the wall clock: when the runtime sleeps until its next tick, the simulated
world is stepped to that instant instead, so a mission runs deterministically, as fast as the
CPU allows, and a busy machine changes nothing but how long it takes. An :class:`Overload` plays
an overloaded machine instead, as deterministically: late and skipped ticks, a world stepped coarsely.
"""

from __future__ import annotations

import json
import random
import socket
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.io.mavlink.link import MemoryLink
from executive.mission.lifecycle import MissionStatus
from executive.mission.model import Mission, SimulatorOptions
from executive.runtime.assembly import build_runtime, can_base, obstacle_camera
from executive.runtime.loop import RunOutcome
from executive.sensing.heading import wait_for_filterpy
from executive.sim import FirmwareSim, make_autopilot
from executive.sim.firmware import Home
from executive.sim.options import firmware_options, simulated_home
from executive.testing.canbus import VirtualCan
from executive.world.clock import ManualClock
from executive.world.dialect import AUTOPILOT_COMPONENT, EXECUTIVE_COMPONENT, MAVLinkMessage, mavlink

if TYPE_CHECKING:
    import can

    from executive.mission.resume import ResumePoint
    from executive.sim.agilex_base import SimulatedBase
    from executive.sim.faults import Fault, FaultInjector


class VehicleTimeLimit(AssertionError):
    """The simulation reached its limit of vehicle time before the run ended."""


@dataclass(frozen=True)
class Overload:
    """A machine too busy for the loop, played on the vehicle's clock: what ``executive run`` lives through beside CPU hogs.

    The runtime's sleep ends ``late_share`` of the time after the tick was due, by a random amount
    of vehicle time (exponential, ``mean_late_s`` on average, at most ``max_late_s``): the pacer
    counts the tick late, and skips the ticks it missed, exactly as in real time. The simulated
    autopilot, which on a real run serves from a thread starved as much, is stepped on a schedule
    of its own, every ``min_step_s`` to ``max_step_s`` of vehicle time, so the runtime sees
    telemetry as old as the last step and its commands act at the next one. ``seed`` makes the
    draws (one seed, one run). The defaults are close to a failed run's figures beside two hogs on
    2 cores: 343 of 1331 ticks late, the worst 1.51 s, 99 skipped.
    """

    seed: int = 0
    late_share: float = 0.4
    mean_late_s: float = 0.1
    max_late_s: float = 1.5
    min_step_s: float = 0.05
    max_step_s: float = 0.5

    def draws(self) -> tuple[Callable[[], float], Callable[[], float]]:
        """(how late the next wake is, the length of the world's next step), from this seed."""
        rng = random.Random(self.seed)

        def lateness() -> float:
            return min(self.max_late_s, rng.expovariate(1.0 / self.mean_late_s)) if rng.random() < self.late_share else 0.0

        return lateness, lambda: rng.uniform(self.min_step_s, self.max_step_s)


def _firmware_options(mission: Mission, autopilot: str) -> dict[str, Any]:
    """The simulated firmware's options the mission sets: all of them on ArduPilot, only its parameters on PX4 (q_guided_mode is ArduPlane's)."""
    options = firmware_options(mission)
    return options if autopilot == "ardupilot" else {k: v for k, v in options.items() if k == "params"}


class LockstepClock(ManualClock):
    """A manual clock whose :meth:`sleep_until` steps the simulated world to that instant (at most ``max_step_s`` at a time).

    With ``overload`` (:class:`Overload`), a sleep ends late now and then, and the world is
    stepped on its own coarse schedule up to the wake, not to the instant itself.
    """

    def __init__(self, step: Callable[[float], None], start: float = 0.0, max_step_s: float = 0.1, overload: Overload | None = None) -> None:
        super().__init__(start)
        self._step = step
        self.max_step_s = max_step_s
        #: Past this vehicle time, :meth:`sleep_until` raises :class:`VehicleTimeLimit` (None: no limit).
        self.deadline: float | None = None
        self.overload = overload
        if overload is not None:
            self._lateness, self._world_step = overload.draws()
            self._world_next = start + self._world_step()  # when the starved simulator steps next

    def sleep_until(self, t: float) -> None:
        if self.overload is not None:
            self._sleep_overloaded(t + self._lateness())
            return
        while self.now() < t:
            self._check_deadline()
            self._step(min(t, self.now() + self.max_step_s))

    def _sleep_overloaded(self, wake: float) -> None:
        while self._world_next <= wake:
            self._check_deadline()
            self._step(max(self._world_next, self.now()))
            self._world_next += self._world_step()
        ManualClock.sleep_until(self, wake)

    def _check_deadline(self) -> None:
        if self.deadline is not None and self.now() >= self.deadline:
            raise VehicleTimeLimit(f"still running at {self.now():.1f} s of vehicle time (the limit)")


#: QGroundControl's MAVLink system and component ids.
GROUND_STATION = (255, 190)
_COMMAND_ACK = mavlink.MAVLINK_MSG_ID_COMMAND_ACK


class Wire:
    """One way of a MAVLink link in memory: each message gets its header (system, component, sequence) as when sent.

    With ``as_bytes`` the messages are packed into bytes and parsed back, exactly as a link carries
    them (values at their wire precision; it costs about a third of a simulation's time).
    """

    def __init__(self, system_id: int, component_id: int, *, as_bytes: bool = False) -> None:
        self._buffer = bytearray()
        #: The sender's MAVLink encoder (its ``send`` may be wrapped to watch what goes onto the wire).
        self.encoder = mavlink.MAVLink(self, srcSystem=system_id, srcComponent=component_id)
        self._parser = mavlink.MAVLink(None)
        self._parser.robust_parsing = True
        self.as_bytes = as_bytes
        #: Without ``as_bytes``: pack each message too (``get_msgbuf()`` then holds its bytes), not only stamp its header.
        self.packed = False
        #: Every byte carried, when a test asks to keep them (a bytearray, with ``as_bytes``; None: not kept).
        self.recording: bytearray | None = None

    def write(self, data: bytes) -> None:
        self._buffer += data

    def carry(self, messages: Iterable[MAVLinkMessage]) -> list[MAVLinkMessage]:
        """``messages`` as the other end receives them."""
        if not self.as_bytes:
            encoder = self.encoder
            if self.packed:
                for msg in messages:
                    msg.pack(encoder)
                    encoder.seq = (encoder.seq + 1) % 256
                return list(messages)
            # the header the receiver reads (sender, sequence), as pack() would set it: packing was a tenth of a run. Each
            # message has a header of its own from its constructor: it is filled in, not made again (a third of the wire's time)
            system, component, seq = encoder.srcSystem, encoder.srcComponent, encoder.seq
            for msg in messages:
                h = msg._header  # (incompat, compat flags, length: 0)
                h.msgId, h.incompat_flags, h.compat_flags, h.mlen, h.seq, h.srcSystem, h.srcComponent = msg.id, 0, 0, 0, seq, system, component
                seq = (seq + 1) % 256
            encoder.seq = seq
            return list(messages)
        for msg in messages:
            self.encoder.send(msg)
        data = bytes(self._buffer)
        self._buffer.clear()
        if self.recording is not None:
            self.recording += data
        return self._parser.parse_buffer(data) or []


class Lockstep:
    """The runtime and a simulated autopilot of the mission's kind in one loop, on one :class:`LockstepClock`.

    ``events`` are fault/event files (and ``Fault`` objects) played on the vehicle's clock, after
    the mission's own ``simulator.events`` (a path relative to ``mission_dir``). ``can=True`` puts
    the simulated AgileX base (bunker only) and the runtime on an in-process CAN bus;
    ``obstacles=True`` gives the runtime a camera (:meth:`send_obstacles`). Other keyword arguments
    go to :func:`~executive.runtime.assembly.build_runtime` (``root=``, ``progress=``, ``plugs=``...);
    ``options_for_clock(clock)`` returns more of them, made with the simulation's clock (a journal's
    plug); ``injector(faults, clock)`` makes the fault injector (a subclass that watches the vehicle).
    ``firmware`` options go to the simulated autopilot; ``autopilot="px4"`` simulates PX4
    instead of ArduPilot. Everything the runtime sends reaches the autopilot at the instant it is
    sent; what the autopilot sends arrives at the runtime's next tick (one tick of latency, as over
    a fast link), each with its header; ``as_bytes`` packs and parses them as a real link does (see :class:`Wire`).
    ``overload`` (:class:`Overload`) runs the mission as an overloaded machine would: late and
    skipped ticks, the world stepped coarsely, still deterministic (one seed, one run). The same
    mission and options give the same run, tick for tick, in any process.
    """

    def __init__(
        self,
        mission: Mission,
        *,
        model: str | None = None,
        home: Home | None = None,
        events: Sequence[str | Path | Fault] = (),
        mission_dir: str | Path | None = None,
        ekf_ready_after_s: float | None = None,
        rate_hz: float = 10.0,
        start_s: float = 0.0,
        can: bool = False,
        obstacles: bool = False,
        firmware: dict[str, float] | None = None,
        as_bytes: bool = False,
        autopilot: str = "ardupilot",
        options_for_clock: Callable[[LockstepClock], dict[str, Any]] | None = None,
        injector: Callable[[list[Fault], LockstepClock], FaultInjector] | None = None,
        overload: Overload | None = None,
        **runtime_options: Any,
    ) -> None:
        sim = mission.simulator or SimulatorOptions()
        # the heading filter judges nothing until filterpy, loading in a thread, is in: a moment of wall
        # time, which would put its first verdict on a different tick in every process
        if not wait_for_filterpy():
            raise RuntimeError("filterpy did not load within 30 s: the heading filter cannot run")
        self.mission = mission
        self.clock = LockstepClock(self._step_to, start_s, max_step_s=1.0 / rate_hz, overload=overload)
        self.autopilot: FirmwareSim = make_autopilot(
            model or sim.model or mission.vehicle,
            self.clock,
            home or simulated_home(mission),
            autopilot=autopilot,
            ekf_ready_after_s=sim.ekf_ready_after_s if ekf_ready_after_s is None else ekf_ready_after_s,
            **{**_firmware_options(mission, autopilot), **(firmware or {})},
        )
        self.faults = self._injector(mission, events, mission_dir, injector)
        if self.faults is not None:
            self.faults.attach(self.autopilot)
        self.uplink = Wire(1, EXECUTIVE_COMPONENT, as_bytes=as_bytes)
        self.downlink = Wire(self.autopilot.system_id, AUTOPILOT_COMPONENT, as_bytes=as_bytes)
        #: A second MAVLink client on the autopilot, as a ground station (QGroundControl: system 255, component 190).
        self.ground_station = Wire(GROUND_STATION[0], GROUND_STATION[1], as_bytes=as_bytes)
        #: What the autopilot answered the ground station (its COMMAND_ACKs), oldest first.
        self.ground_station_heard: list[MAVLinkMessage] = []
        self.link = MemoryLink()
        self.base: SimulatedBase | None = None
        self.can_bus: can.BusABC | None = None
        self._can: VirtualCan | None = None
        if can:
            self.can_bus = self._open_can()
        self._camera: socket.socket | None = None
        obstacle_socket = None
        if obstacles:
            obstacle_socket, self._camera = socket.socketpair(socket.AF_UNIX, socket.SOCK_DGRAM)
            obstacle_socket.setblocking(False)
        self._sockets = [s for s in (obstacle_socket, self._camera) if s is not None]
        #: Called after each step of the world with this simulation (watch the vehicle, act at a moment).
        self.observers: list[Callable[[Lockstep], object]] = []
        self._scheduled: list[tuple[float, Callable[[Lockstep], object]]] = []
        self._started = False
        self._stop_when: Callable[[], bool] | None = None
        if options_for_clock is not None:  # what needs the clock itself (a journal, a recorder) is made here
            runtime_options = {**runtime_options, **options_for_clock(self.clock)}
        plugs = list(runtime_options.pop("plugs", ()))
        plugs += [can_base(self.can_bus)] if self.can_bus is not None else []
        plugs += [obstacle_camera(obstacle_socket)] if obstacle_socket is not None else []
        self.runtime = build_runtime(mission, self.link, self.clock, rate_hz=rate_hz, plugs=plugs, **runtime_options)

    # -- set-up ---------------------------------------------------------------------------------
    def _injector(
        self,
        mission: Mission,
        events: Sequence[str | Path | Fault],
        mission_dir: str | Path | None,
        make: Callable[[list[Fault], LockstepClock], FaultInjector] | None,
    ) -> FaultInjector | None:
        from executive.sim.faults import FaultInjector, load_faults

        faults: list[Fault] = []
        own = mission.simulator.events if mission.simulator else None
        sources: list[str | Path | Fault] = [Path(mission_dir or ".") / own] if own else []
        for source in [*sources, *events]:
            faults += load_faults(source, vehicle=mission.vehicle).faults if isinstance(source, str | Path) else [source]
        if make is not None:
            return make(faults, self.clock)
        return FaultInjector(faults, self.clock) if faults else None

    def _open_can(self) -> can.BusABC:
        from executive.sim.agilex_base import SimulatedBase

        self._can = VirtualCan("executive-lockstep")
        self.base = SimulatedBase(self._can.base, self.clock, self.autopilot, faults=self.faults)
        return self._can.ours

    def close(self) -> None:
        """Shut the CAN buses and sockets (idempotent)."""
        if self._can is not None:
            self._can.shutdown()
        for sock in self._sockets:
            sock.close()
        self._sockets = []
        self.runtime.close()

    def __enter__(self) -> Lockstep:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- the world ------------------------------------------------------------------------------
    def _step_to(self, t: float) -> None:
        """What the runtime sent reaches the autopilot; the world moves to ``t``; what the vehicle sends is queued for the runtime."""
        faults = self.faults
        if faults is not None:
            faults.update(self.autopilot)
        sent, self.link.sent = self.link.sent, []
        out: list[MAVLinkMessage] = []
        if faults is None or faults.receiving:  # during an uplink loss what is sent is lost
            for msg in self.uplink.carry(sent):
                out += self.autopilot.handle(msg)
        ManualClock.sleep_until(self.clock, t)
        if faults is not None:
            faults.update(self.autopilot)
        out += self.autopilot.update()
        if self.base is not None:
            self.base.service()
        if faults is not None:
            out = faults.transform(out)
        self.link.incoming.extend(self.downlink.carry(self._answer_ground_station(out)))
        while self._scheduled and self._scheduled[0][0] <= t + 1e-9:
            _, action = self._scheduled.pop(0)
            action(self)
        for observer in self.observers:
            observer(self)
        if self._stop_when is not None and self._stop_when():
            raise _Stopped

    def send_from_ground_station(self, msg: MAVLinkMessage) -> None:
        """A ground station's message reaches the autopilot now, on a link of its own.

        The firmware answers a command on the channel it came on (ArduPilot's GCS_MAVLINK::handle_command_*; PX4's
        acks go to a component its link has heard, mavlink_main.cpp handleAndGetCurrentCommandAck): its COMMAND_ACK
        goes to the ground station (:attr:`ground_station_heard`), what else it sends reaches the executive as usual.
        """
        replies = [r for m in self.ground_station.carry([msg]) for r in self.autopilot.handle(m)]
        self.link.incoming.extend(self.downlink.carry(self._answer_ground_station(replies)))

    def _answer_ground_station(self, messages: list[MAVLinkMessage]) -> list[MAVLinkMessage]:
        """The autopilot's COMMAND_ACKs to the ground station kept for it (:attr:`ground_station_heard`); the rest, for the executive."""
        ours: list[MAVLinkMessage] = []
        for m in messages:  # one pass: this runs at every step of the world
            if m.id == _COMMAND_ACK and m.target_system == GROUND_STATION[0]:
                self.ground_station_heard.append(m)
            else:
                ours.append(m)
        return ours

    def step(self, dt: float) -> None:
        """Move the world ``dt`` seconds without ticking the runtime (before it connects, between runs)."""
        self.clock.sleep_until(self.clock.now() + dt)

    def at(self, t_s: float, action: Callable[[Lockstep], object]) -> None:
        """Call ``action(self)`` at ``t_s`` seconds of vehicle time (an operator's request, a camera's scan...)."""
        self._scheduled.append((t_s, action))
        self._scheduled.sort(key=lambda entry: entry[0])

    def send_obstacles(self, scan: dict[str, Any] | bytes) -> None:
        """The camera sends one datagram: a scan (the JSON object of docs/running.md's ``--obstacles``), or raw bytes; needs ``obstacles=True``."""
        if self._camera is None:
            raise RuntimeError("this simulation has no camera: Lockstep(..., obstacles=True)")
        self._camera.send(scan if isinstance(scan, bytes) else json.dumps(scan).encode())

    # -- running --------------------------------------------------------------------------------
    def connect(self, limit_s: float = 10.0) -> None:
        """Until the runtime has heard the autopilot (VehicleTimeLimit after ``limit_s`` of vehicle time)."""
        if self.runtime.link.reader.autopilot is None and not self.runtime.link.connect(limit_s):
            raise VehicleTimeLimit(f"no heartbeat from the simulated autopilot within {limit_s:g} s")

    def run(
        self, limit_s: float = 600.0, *, until: Callable[[], bool] | None = None, serve: bool = False, resume: ResumePoint | None = None
    ) -> RunOutcome | None:
        """Connect, start the mission (the first time) and run the runtime's own loop until the mission ends.

        Returns its :class:`RunOutcome`; or None as soon as ``until()`` is true after a step (call
        :meth:`run` again to go on). VehicleTimeLimit when ``limit_s`` more seconds of vehicle time
        pass first. ``serve``: the runtime's ``--wait`` loop (ends only when stopped). ``resume``:
        a journal's unfinished run to continue (as ``executive run --resume``).
        """
        self.clock.deadline = self.clock.now() + limit_s
        self._stop_when = until
        try:
            self.connect(limit_s)
            start, self._started = not self._started, True
            return self.runtime.run(start=start and not serve, serve=serve, resume=resume)
        except _Stopped:
            return None
        finally:
            self.clock.deadline = None
            self._stop_when = None

    def run_to_end(self, limit_s: float = 600.0) -> RunOutcome:
        """:meth:`run`, asserting the mission ended (COMPLETED or not) within ``limit_s`` of vehicle time."""
        outcome = self.run(limit_s)
        assert outcome is not None
        return outcome

    @property
    def status(self) -> MissionStatus:
        """The mission's status now."""
        return self.runtime.mission_state.status


class _Stopped(Exception):
    """``until()`` came true: unwinds the runtime's loop to :meth:`Lockstep.run`."""
