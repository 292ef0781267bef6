"""Test helpers of our own suite (the rest is the public kit, :mod:`executive.testing`): a runtime over a real socket, a line mission,
a mission out of reach run to its refusal, the time a thread waited for a CPU, ``executive run`` in lock-step with its built-in simulator,
``executive`` as a process of its own, a sub's survey on the simulated ArduSub leg by leg."""

from __future__ import annotations

import fcntl
import os
import shutil
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import py_trees
import pytest

from executive.io.mavlink.link import PymavlinkLink
from executive.mission.model import Mission, Waypoint
from executive.operator.status import status_line
from executive.runtime.assembly import Wiring, build_runtime
from executive.runtime.loop import RunOutcome, Runtime
from executive.runtime.pacing import SpeedGovernor
from executive.sim import SimServer
from executive.sim.faults import FaultInjector
from executive.testing import Lockstep
from executive.world import blackboard
from executive.world.clock import ManualClock, ScaledClock
from executive.world.dialect import MAVLinkMessage, mavlink
from executive.world.geo import destination

ROOT = Path(__file__).resolve().parents[1]
#: Home of the line missions: ArduPilot SITL's default location.
LINE_HOME = (-35.363261, 149.165230)
#: EKF ready 2 s after boot in the line missions' simulator.
LINE_EKF_READY_S = 2.0


class SteppedClock(ManualClock):
    """``executive run``'s clock made lock-step (:func:`run_in_lockstep`): time moves only when the runtime waits, and the
    simulators served in-process (their threads never started) step with it, every :attr:`STEP_S` of vehicle time.

    Over loopback UDP a datagram is in the peer's socket when ``sendto`` returns (Linux delivers it in the sender's
    system call, save when its soft interrupts are deferred: then a tick later): the runtime reads at its next tick
    what the simulator said at this instant, however busy the machine. :attr:`speedup` is the one asked for (kept for
    what ``run`` derives from it), never the pace: a run takes the CPU time it needs, not its vehicle time over the speed-up.
    """

    STEP_S = 0.05

    def __init__(self, speedup: float = 1.0) -> None:
        super().__init__(0.0)
        self.speedup = speedup
        self.servers: list[SimServer] = []

    def set_speedup(self, speedup: float) -> None:
        self.speedup = speedup

    def sleep_until(self, t: float) -> None:
        while self.now() < t:
            ManualClock.sleep_until(self, min(t, self.now() + self.STEP_S))
            for server in self.servers:
                server.step()


def run_in_lockstep(monkeypatch: pytest.MonkeyPatch) -> None:
    """From now on in this test ``executive run`` (in-process, its built-in simulator) runs lock-step on a :class:`SteppedClock`."""

    def serve_in_step(server: SimServer) -> SimServer:
        assert isinstance(server.clock, SteppedClock), "run_in_lockstep: a simulator on another clock"
        server.clock.servers.append(server)
        return server

    monkeypatch.setattr("executive.cli.run.ScaledClock", SteppedClock)
    monkeypatch.setattr(SimServer, "start", serve_in_step)


def executive_process(
    *args: str,
    stdout: int | None = subprocess.DEVNULL,
    cwd: Path = ROOT,
    env: dict[str, str] | None = None,
    via: Sequence[str] = (),
    **popen: Any,
) -> subprocess.Popen[str]:
    """``python -m executive ARGS`` in a process of its own, from the checkout, text pipes: its stderr kept (a pipe), its stdout
    dropped unless ``stdout`` says otherwise (``subprocess.PIPE`` for the status lines); ``env`` is added to this environment.
    ``via`` names a script of tests/ and its own arguments, run in place of ``-m executive`` (``python tests/SCRIPT VIA... -- ARGS``):
    the executive under a test's clock (``stepped_wall_clock.py``, ``held_clock.py``).

    For what only a process shows (signals, exit codes, a second process on the same socket, an interpreter's start): where the
    process boundary is not what a test checks, run ``main([...])`` in the test's own process (an interpreter's start is ~1 s of CPU).
    """
    command = [sys.executable, "-m", "executive", *args]
    if via:
        command = [sys.executable, str(ROOT / "tests" / via[0]), *via[1:], "--", *args]
        env = {"PYTHONPATH": os.pathsep.join([str(ROOT), str(ROOT / "tests")]), **(env or {})}
    environment = None if env is None else {**os.environ, **env}
    return subprocess.Popen(command, cwd=cwd, stdout=stdout, stderr=popen.pop("stderr", subprocess.PIPE), env=environment, text=True, **popen)


def line_mission(name: str, **changes: Any) -> Mission:
    """A rover driving 4 waypoints 25 m apart due north of :data:`LINE_HOME` (radius 1.5 m, leg 60 s, link 3 s, recovery 30 s)."""
    fields: dict[str, Any] = {
        "version": 1,
        "name": name,
        "vehicle": "rover",
        "auto_arm": True,
        "home": {"lat": LINE_HOME[0], "lon": LINE_HOME[1], "heading_deg": 0.0},
        "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 60, "link_timeout_s": 3, "recovery_timeout_s": 30},
        "simulator": {"ekf_ready_after_s": LINE_EKF_READY_S},
        "waypoints": [{"lat": LINE_HOME[0] + 0.0002248 * n, "lon": LINE_HOME[1]} for n in range(1, 5)],
    }
    return Mission.model_validate(fields | changes)


def mission_text(name: str, *waypoints: str, simulator: str = "{ekf_ready_after_s: 2}", limits: str | None = None) -> str:
    """A rover mission file's text at :data:`LINE_HOME`, armed by the executive: ``simulator`` and ``limits`` as flow mappings,
    each waypoint a line of its own (``"{lat: -35.36, lon: 149.16}  # a comment"``)."""
    lines = ["version: 1", f"name: {name}", "vehicle: rover", "auto_arm: true", f"home: {{lat: {LINE_HOME[0]}, lon: {LINE_HOME[1]:.6f}}}"]
    lines += [f"simulator: {simulator}", *([f"limits: {limits}"] if limits else []), "waypoints:", *(f"  - {w}" for w in waypoints)]
    return "\n".join(lines) + "\n"


def run_over(url: str, mission: Mission, clock: ScaledClock, **options: Any) -> tuple[Runtime, RunOutcome]:
    """A runtime on a real link to ``url`` (a simulator), connected and run to the mission's end; the link closed after.

    ``options`` go to :func:`~executive.runtime.assembly.build_runtime` (progress, plugs...).
    """
    link = PymavlinkLink(url)
    try:
        runtime = build_runtime(mission, link, clock, **options)
        runtime.pacer.listeners.append(SpeedGovernor(clock))  # as `executive run` does: a busy machine slows the world, not the verdict
        assert runtime.link.connect(10.0 * clock.speedup)
        return runtime, runtime.run()
    finally:
        link.close()


#: What the executive may say to an autopilot before any tree runs: who it is, what to stream, which parameter it needs, and
#: its reports to ground stations (the mission's state).
HARMLESS = {"HEARTBEAT", "REQUEST_DATA_STREAM", "PARAM_REQUEST_READ", "STATUSTEXT", "NAMED_VALUE_FLOAT"}
HARMLESS_COMMANDS = {mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, mavlink.MAV_CMD_REQUEST_MESSAGE}


def with_far_waypoint(mission: Mission, metres: float, **changes: object) -> tuple[Mission, tuple[float, float, float]]:
    """``mission`` without its home (validate would refuse it), a waypoint ``metres`` north of its start appended; and where its vehicle boots.

    Its ``limits.leg_timeout_s`` is a day, so that the far leg is refused for its distance, not for the time it takes (issue 40).
    """
    start = mission.home or mission.waypoints[0]
    lat, lon = destination(start.lat, start.lon, 0.0, metres)
    far = Waypoint(lat=lat, lon=lon, name="far")
    limits = mission.limits.model_copy(update={"leg_timeout_s": 86400.0})
    edited = mission.model_copy(update={"home": None, "waypoints": [*mission.waypoints, far], "limits": limits, **changes})
    return edited, (start.lat, start.lon, 0.0)


def run_recording(mission: Mission, boots_at: tuple[float, float, float], **options: Any) -> tuple[RunOutcome, Lockstep, list[MAVLinkMessage]]:
    """The mission on the lock-step simulator (vehicle booted at ``boots_at``) until it ends: how, the simulation, what its autopilot received.

    ``options`` go to :class:`~executive.testing.Lockstep` (``mission_dir=`` for the mission's own event file...).
    """
    received: list[MAVLinkMessage] = []
    with Lockstep(mission, home=boots_at, **options) as sim:
        handle = sim.autopilot.handle

        def record(msg: MAVLinkMessage) -> list[MAVLinkMessage]:
            received.append(msg)
            return handle(msg)

        sim.autopilot.handle = record  # type: ignore[method-assign]
        outcome = sim.run_to_end(limit_s=300)
    return outcome, sim, received


def acting(received: list[MAVLinkMessage]) -> list[str]:
    """What of ``received`` would change the vehicle: a command, a mode, a target, a route."""
    found = []
    for msg in received:
        kind = msg.get_type()
        if kind in ("COMMAND_LONG", "COMMAND_INT"):
            if msg.command not in HARMLESS_COMMANDS:
                found.append(f"{kind} {msg.command}")
        elif kind not in HARMLESS:
            found.append(kind)
    return found


def runqueue_wait_s(native_id: int | None = None) -> float:
    """Seconds the thread (this one, or the one with ``native_id``) has waited for a CPU while ready to run (Linux schedstat).

    A wall-clock duration less this wait is what the thread took itself, running or blocked: what a
    busy machine adds by not scheduling it is left out, so a bound on it needs no slack for the load.
    """
    path = "/proc/thread-self/schedstat" if native_id is None else f"/proc/self/task/{native_id}/schedstat"
    fd = os.open(path, os.O_RDONLY)  # not Path.read_text: a hostile test reads it 17 000 times (38 -> 8 us a read)
    try:
        return int(os.read(fd, 256).split()[1]) / 1e9
    finally:
        os.close(fd)


FOXGLOVE_JS = Path(__file__).resolve().parent / "observers" / "foxglove"


def foxglove_js(script: str, *args: str) -> list[str]:
    """``node tests/observers/foxglove/SCRIPT ARGS``: Foxglove's own npm packages driven by node; the test fails (not skips) without them.

    The packages are installed from the lock file at first use (one xdist worker at a time), so README's test command needs
    no step of its own; `.ci/run` installs node and npm where the machine has none."""
    if shutil.which("node") is None or shutil.which("npm") is None:
        pytest.fail("needs node and npm (Debian: apt-get install nodejs npm, as .ci/run does)")
    with open(FOXGLOVE_JS / "package-lock.json", encoding="utf-8") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (FOXGLOVE_JS / "node_modules" / "@mcap" / "core").is_dir():
            npm = ["npm", "ci", "--prefix", str(FOXGLOVE_JS), "--no-audit", "--no-fund", "--loglevel=error"]
            done = subprocess.run(npm, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=600, check=False)
            if done.returncode != 0:
                pytest.fail(f"npm ci --prefix tests/observers/foxglove failed: {done.stderr.strip()}")
    return ["node", str(FOXGLOVE_JS / script), *args]


def set_currents(sim: Lockstep) -> list[int]:
    """The MISSION_SET_CURRENT items the executive sends from now on (the list grows as the run goes)."""
    sent: list[int] = []
    send = sim.link.send

    def spy(msg: Any) -> None:
        if msg.get_type() == "MISSION_SET_CURRENT":
            sent.append(msg.seq)
        send(msg)

    sim.link.send = spy  # type: ignore[method-assign]
    return sent


class LinkCut(FaultInjector):
    """The link silent both ways while ``cut`` (the executive alive, its messages lost): a cable pulled and put back."""

    cut = False

    @property
    def receiving(self) -> bool:
        return not self.cut and super().receiving

    @property
    def sending(self) -> bool:
        return not self.cut and super().sending


@dataclass
class SubRun:
    """A sub's mission run to its end on the simulated ArduSub (:func:`sub_run`): how it ended, each leg's end, the vehicle at the end,
    the first energy estimate on the blackboard and the pack's draw (Wh) when it armed and at the end."""

    outcome: RunOutcome
    legs: list[dict[str, Any]] = field(default_factory=list)
    end: dict[str, Any] = field(default_factory=dict)
    first_estimate: Any = None
    armed_wh: float | None = None
    end_wh: float = 0.0


def sub_run(mission: Mission, home: tuple[float, float, float]) -> SubRun:
    """``mission`` on the lock-step simulated ArduSub booted at ``home``, to its end (600 s at most); what each leg ended with (depth,
    altitude, metres off its waypoint, the time, the status line) noted as the leg is advanced. Watching changes nothing in the run."""
    with Lockstep(mission, home=home) as sim:
        runtime = sim.runtime
        run = SubRun(outcome=None)  # type: ignore[arg-type]
        advance = runtime.mission_state.advance_leg

        def note_and_advance() -> None:
            wp = mission.waypoints[runtime.mission_state.legs.leg_index]
            v = sim.autopilot.vehicle
            run.legs.append({"depth": v.depth_m, "altitude": v.altitude_m, "off_m": v.distance_to(wp.lat, wp.lon), "t": sim.clock.now()})
            run.legs[-1]["status"] = status_line(runtime.status.snapshot())
            advance()

        runtime.mission_state.advance_leg = note_and_advance  # type: ignore[method-assign]
        energy = blackboard.reader("sub run", ["/energy/estimate"])

        def watch(s: Lockstep) -> None:
            if run.first_estimate is None and (estimate := energy.get("/energy/estimate")):
                run.first_estimate = estimate
            if run.armed_wh is None and s.autopilot.armed:
                run.armed_wh = s.autopilot.battery.consumed_wh

        sim.observers.append(watch)
        sim.connect()
        started = sim.clock.now()
        run.outcome = sim.run_to_end(limit_s=600)
        ap = sim.autopilot
        run.end = {"mode": ap.mode, "armed": ap.armed, "depth": ap.vehicle.depth_m, "moved_m": ap.vehicle.distance_to(home[0], home[1])}
        run.end["vehicle_s"] = sim.clock.now() - started
        run.end_wh = ap.battery.consumed_wh
    return run


#: The tests that share the example survey's run (the ``auv_survey_run`` fixture) go to one xdist worker: it is made once there.
AUV_SURVEY_RUN = pytest.mark.xdist_group("auv_survey_run")


class Ticks:
    """Each tick's number and vehicle time, and the position the blackboard held after it, as the runtime reports them."""

    def __init__(self) -> None:
        self.times: list[tuple[int, float]] = []

    def plug(self, wiring: Wiring) -> None:
        wiring.observers.append(self)

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        pass

    def ticked(self, tick: int, now: float) -> None:
        self.times.append((tick, now))

    def end(self, status: str, reason: str) -> None:
        pass


def record_rover_square(where: Path) -> tuple[Path, Path, Ticks, Any]:
    """rover_square to its end on the lock-step simulator, recorded twice from the same ticks, as MCAP and as JSON lines (in
    ``where``), with a journal and the executive's INFO log lines in it; the ticks as the runtime reported them, and how it ended."""
    import logging

    from executive.mission.loader import load_mission
    from executive.observers.journal import Journal, JournalLogHandler, journal_recorder
    from executive.observers.snapshots import SnapshotRecorder, snapshot_recorder

    missions = ROOT / "missions"
    ticks = Ticks()
    recorders: list[SnapshotRecorder] = []
    closers: list[Any] = []

    def plugs(clock: ManualClock) -> dict[str, Any]:
        recorders.extend([SnapshotRecorder(where / "run.mcap", clock=clock), SnapshotRecorder(where / "run.jsonl", clock=clock)])
        journal = Journal(where / "journal.db", clock)
        closers.append(journal.close)
        logging.getLogger("executive").addHandler(handler := JournalLogHandler(journal))
        closers.append(lambda: logging.getLogger("executive").removeHandler(handler))
        return {"plugs": [ticks.plug, *(snapshot_recorder(r) for r in recorders), journal_recorder(journal)]}

    log = logging.getLogger("executive")
    level = log.level  # a session fixture's run: the level the tests around it set is theirs again after it
    log.setLevel(logging.INFO)  # as `executive run` logs: the mission's transitions are INFO lines
    try:
        with Lockstep(load_mission(missions / "rover_square.yaml"), mission_dir=missions, options_for_clock=plugs) as sim:
            outcome = sim.run_to_end(limit_s=400)
    finally:
        log.setLevel(level)
    for close in [*(r.close for r in recorders), *closers]:
        close()
    return where / "run.mcap", where / "run.jsonl", ticks, outcome.status


class SharedEfficiencyRuns:
    """:mod:`benchmarks.efficiency`'s lock-step runs, each made once a process for the tests that share them (conftest's
    ``efficiency_runs``; its users are in ``xdist_group("leg_efficiency")``): the same mission run the same way is the same run,
    track and all (:class:`~executive.testing.Lockstep`), so a run is keyed by how it is timed and every field of its mission."""

    SHARED = ("time_executive", "time_auto")  # what the timings are made of: the executive's run, the autopilot's own AUTO

    def __init__(self) -> None:
        from benchmarks import efficiency

        self._efficiency = efficiency
        self._made = {name: getattr(efficiency, name) for name in self.SHARED}
        self._done: dict[tuple[Any, ...], Any] = {}

    def _once(self, name: str, how: Any, mission: Mission, *args: Any) -> Any:
        key = (name, mission.model_dump_json(), *args)
        if key not in self._done:
            self._done[key] = how(mission, *args)
        return self._done[key]

    def share(self, monkeypatch: pytest.MonkeyPatch) -> None:
        """From now on in this test, the benchmark's own calls of :data:`SHARED` are shared runs."""
        for name, how in self._made.items():
            monkeypatch.setattr(self._efficiency, name, lambda mission, *args, name=name, how=how: self._once(name, how, mission, *args))

    def timed(self, how: Any, mission: Mission) -> Any:
        """``how(mission)`` (``time_guided``, ``time_auto``, ``time_supervised_auto``...), shared."""
        with pytest.MonkeyPatch.context() as monkeypatch:
            self.share(monkeypatch)
            return self._once(how.__name__, how, mission)
