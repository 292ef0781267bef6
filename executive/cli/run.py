"""``executive run MISSION``: the onboard runtime, against a vehicle or the built-in simulator."""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import signal
import sqlite3
import sys
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

from executive.autopilot_link import SURVEY_S, SeveralAutopilots
from executive.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_INTERRUPTED, EXIT_NO_VEHICLE, EXIT_OK, BadInput, NoVehicle
from executive.cli.common import load_or_report
from executive.cli.run_checks import check_run
from executive.io.control import default_socket_path, socket_alive
from executive.io.mavlink.endpoint import Unreachable
from executive.io.mavlink.link import PymavlinkLink
from executive.io.storage import Storage
from executive.io.systemd import Notifier, Watchdog, watchdog_period_s
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Mission, SimulatorOptions
from executive.mission.resume import ResumePoint
from executive.observers.journal import Journal, JournalLogHandler, journal_recorder
from executive.observers.snapshots import SnapshotRecorder, snapshot_recorder
from executive.operator.logs import attach_live_line, setup_logging, use_clock
from executive.operator.progress import Progress
from executive.runtime.assembly import Plug, build_runtime, can_base, control_socket, ground_stations, obstacle_camera, service_manager
from executive.runtime.loop import RunOutcome
from executive.runtime.pacing import SpeedGovernor, keeping_time
from executive.world.clock import ScaledClock

if TYPE_CHECKING:
    import socket

    import can

    from executive.observers.foxglove.live import FoxgloveSink
    from executive.observers.web.server import WebServer
    from executive.sim.faults import FaultInjector


@contextlib.contextmanager
def _vehicle_link(
    args: argparse.Namespace, mission: Mission, clock: ScaledClock, faults: FaultInjector | None, signing_key: bytes | None, storage: Storage
) -> Iterator[PymavlinkLink]:
    """A link to the vehicle named by --mavlink, or to a simulated one started here."""
    options = {"system_id": args.sysid, "signing_key": signing_key, "tlog": args.tlog, "clock": clock, "storage": storage}
    if args.mavlink:
        link = _open_link("--mavlink", args.mavlink, **options)
        try:
            yield link
        finally:
            link.close()
        return
    from executive.sim import SimServer
    from executive.sim.options import firmware_options, simulated_home, where_it_starts

    sim_options = mission.simulator or SimulatorOptions()
    model = sim_options.model or mission.vehicle
    firmware = args.autopilot or mission.autopilot or "ardupilot"
    base_bus = _open_can(args.can) if args.can and model == "bunker" else None  # the simulated base's end of the bus
    try:
        with SimServer(
            model,
            clock=clock,
            home=simulated_home(mission),
            faults=faults,
            signing_key=signing_key,
            ekf_ready_after_s=sim_options.ekf_ready_after_s,
            can_bus=base_bus,
            autopilot=firmware,
            **(firmware_options(mission) if firmware == "ardupilot" else {}),  # q_guided_mode is ArduPlane's
        ) as sim:
            on = "" if firmware == "ardupilot" else f" ({firmware})"
            start = where_it_starts(mission)
            print(f"executive: run: simulated {model}{on} on {sim.url_for_client} (speed-up {clock.speedup:g}x){start}", file=sys.stderr)
            link = PymavlinkLink(sim.url_for_client, **options)
            try:
                yield link
            finally:
                link.close()
    finally:
        if base_bus is not None:
            base_bus.shutdown()


def _open_link(option: str, url: str, **options: Any) -> PymavlinkLink:
    """The link of ``option`` (its URL checked already); NoVehicle when it cannot be opened."""
    try:
        return PymavlinkLink(url, **options)
    except Unreachable as exc:
        raise NoVehicle(f"{option} {exc}") from exc


@contextlib.contextmanager
def _gcs_link(url: str | None, system_id: int) -> Iterator[PymavlinkLink | None]:
    """The ground stations' own endpoint, if asked for (we speak there as the onboard computer of system ``system_id``)."""
    if url is None:
        yield None
        return
    link = _open_link("--gcs", url, system_id=system_id)
    try:
        yield link
    finally:
        link.close()


def _control_socket_path(asked: str | None) -> str | None:
    """The control socket to serve: ``--socket`` (BadInput when another executive serves it), else the default, else one of our own.

    A second executive on the default path would leave ``executive ctl`` reaching the first: it
    takes a path with its process id instead, and says so.
    """
    if asked is not None:
        if asked.lower() == "none":
            return None
        if os.path.exists(asked) and socket_alive(asked):
            raise BadInput(f"--socket {asked}: another executive is listening there (stop it, or choose another path)")
        return asked
    path = default_socket_path()
    if os.path.exists(path) and socket_alive(path):
        own = default_socket_path(os.getpid())
        print(
            f"executive: run: another executive serves {path}; this one listens on {own} (executive ctl --socket {own} ...)",
            file=sys.stderr,
        )
        return own
    return path


def _recorders(
    args: argparse.Namespace, clock: ScaledClock, stack: contextlib.ExitStack, storage: Storage, live: FoxgloveSink | None = None
) -> tuple[Journal | None, SnapshotRecorder | None]:
    """The journal (with the log's warnings as its events) and the snapshot recorder asked for, closed with ``stack``.

    BadInput when one cannot be created (a directory that does not exist, a read-only or full disk): refused before the run.
    """
    journal = snapshots = None
    if args.tlog:  # opened with the link: checked here, before anything is
        try:
            with open(args.tlog, "ab"):
                pass
        except OSError as exc:
            raise BadInput(f"--tlog {args.tlog}: cannot be created: {exc.strerror or exc}") from exc
    if args.journal:
        try:
            journal = Journal(args.journal, clock, storage)
        except (sqlite3.Error, OSError) as exc:
            raise BadInput(f"--journal {args.journal}: cannot be created or written: {exc}") from exc
        stack.callback(journal.close)
        handler = JournalLogHandler(journal)
        logging.getLogger("executive").addHandler(handler)
        stack.callback(logging.getLogger("executive").removeHandler, handler)
    if args.snapshots:
        try:
            size = round(args.snapshots_rotate_mb * (1 << 20))
            snapshots = SnapshotRecorder(args.snapshots, storage=storage, clock=clock, max_bytes=size, live=live)
        except OSError as exc:
            raise BadInput(f"--snapshots {args.snapshots}: cannot be created: {exc.strerror or exc}") from exc
        stack.callback(snapshots.close)
    return journal, snapshots


def _can_bus(args: argparse.Namespace, stack: contextlib.ExitStack) -> can.BusABC | None:
    """The bus of --can (recorded with --can-log), shut down with ``stack``; BadInput / NoBus when it cannot be had."""
    if args.can is None:
        if args.can_log:
            raise BadInput("--can-log needs --can IFACE:CHANNEL")
        return None
    from executive.io.can.recording import RecordingBus

    bus = _open_can(args.can)
    if args.can_log:
        bus = RecordingBus(bus, args.can_log)
    stack.callback(bus.shutdown)
    return bus


def _open_can(spec: str) -> can.BusABC:
    from executive.io.can import CanOpenError, CanSpecError, open_can

    try:
        return open_can(spec)
    except CanSpecError as exc:
        raise BadInput(f"--can: {exc}") from exc
    except CanOpenError as exc:
        raise NoVehicle(f"--can: {exc}") from exc


def _obstacle_socket(spec: str | None, stack: contextlib.ExitStack) -> socket.socket | None:
    """The bound socket of --obstacles (its URL checked already), closed with ``stack``; NoVehicle when it cannot be bound."""
    if spec is None:
        return None
    from executive.io.obstacles import open_endpoint

    try:
        sock = open_endpoint(spec)
    except OSError as exc:
        raise NoVehicle(f"--obstacles: cannot listen on {spec}: {exc}") from exc
    stack.callback(sock.close)
    return sock


def _service_manager(stack: contextlib.ExitStack) -> Watchdog | None:
    """Under systemd (``Type=notify``): the watchdog and status service, fed on the wall clock whatever the speed-up; else None."""
    notifier = Notifier.from_environment()
    if notifier is None:
        return None
    stack.callback(notifier.close)
    return Watchdog(notifier, ScaledClock(), watchdog_period_s())


def _web_server(args: argparse.Namespace, stack: contextlib.ExitStack) -> WebServer | None:
    """The live view's server of --web, bound (BadInput: a bad address or token file; NoVehicle: the port cannot be had), closed with ``stack``."""
    if args.web is None:
        if args.web_token_file:
            raise BadInput("--web-token-file needs --web [HOST:]PORT")
        return None
    from executive.observers.web.server import WebAddressError, open_server

    try:
        server, told = open_server(args.web, args.web_token_file)
    except WebAddressError as exc:
        raise BadInput(f"--web: {exc}") from exc
    except OSError as exc:
        raise NoVehicle(f"--web: cannot listen on {args.web}: {exc}") from exc
    stack.callback(server.close)
    print(f"executive: {told}", file=sys.stderr, flush=True)
    return server


def _foxglove(args: argparse.Namespace, stack: contextlib.ExitStack) -> FoxgloveSink | None:
    """The Foxglove server of --foxglove, listening (BadInput: a bad address, no SDK; NoVehicle: the port cannot be had), closed with ``stack``."""
    if args.foxglove is None:
        return None
    from executive.observers.foxglove.live import FoxgloveAddressError, FoxgloveSink, parse_address

    try:
        host, port = parse_address(args.foxglove)
        live = FoxgloveSink(host, port)
    except FoxgloveAddressError as exc:
        raise BadInput(f"--foxglove: {exc}") from exc
    except ImportError as exc:
        raise BadInput(f"--foxglove: the Foxglove SDK is not installed ({exc}): pip install foxglove-sdk") from exc
    except RuntimeError as exc:  # the SDK's: the port taken, an address not of this machine
        raise NoVehicle(f"--foxglove: cannot listen on {args.foxglove}: {exc}") from exc
    stack.callback(live.close)
    print(f"executive: Foxglove can connect to {live.url} (open connection, Foxglove WebSocket)", file=sys.stderr, flush=True)
    return live


def _groot2(args: argparse.Namespace, stack: contextlib.ExitStack) -> list[Plug]:
    """The Groot2 publisher of --groot2, listening (BadInput: a bad address; NoVehicle: the ports cannot be had), closed with ``stack``."""
    if args.groot2 is None:
        return []
    from executive.observers.groot2.live import groot2_monitor
    from executive.observers.groot2.server import Groot2AddressError, Groot2Server, parse_address
    from executive.observers.groot2.view import MonitorView

    try:
        address = parse_address(args.groot2)
    except Groot2AddressError as exc:
        raise BadInput(f"--groot2: {exc}") from exc
    view = MonitorView()
    try:
        server = Groot2Server(address, view)
    except OSError as exc:
        raise NoVehicle(f"--groot2: {exc}") from exc
    server.start()
    stack.callback(server.close)
    print(f"executive: Groot2 can connect to {address.host} port {address.port} (publisher {address.port + 1})", file=sys.stderr, flush=True)
    return [groot2_monitor(view)]


def _signing_hint(link: PymavlinkLink) -> str:
    """Why no heartbeat was heard when signing is the reason: every packet failed the signature check."""
    unsigned, other_key, accepted = link.signature_failures
    if accepted or not (unsigned or other_key):
        return ""
    return (
        f": every packet from the autopilot was unsigned or signed with another key ({unsigned} unsigned, {other_key} signed with another "
        "key): check --signing-key against the autopilot's key"
    )


def _serial_hint(link: PymavlinkLink, bad_data: int) -> str:
    """Why no heartbeat was heard on a serial device that sent bytes: not an autopilot's port, or not at its baud rate."""
    if link.device is None or not bad_data:
        return ""
    return (
        f": bytes that are not MAVLink came in ({bad_data} undecodable runs): is it the autopilot's port, and is it at the autopilot's "
        "baud rate (,BAUD after the device; ArduPilot's SERIALn_BAUD)? the wrong baud rate garbles every byte"
    )


def _resume_text(resume: ResumePoint | None) -> str:
    if resume is None:
        return "nothing to resume: the journal has no unfinished run of this mission; starting from the first waypoint"
    edited = f", on its route as last edited ({len(resume.route)} waypoints)" if resume.route is not None else ""
    replaced = f", on mission {resume.mission.name!r} that replaced it" if resume.mission is not None else ""
    taken = f"with {len(resume.samples)} sample(s) already taken"
    return f"resuming run {resume.run} at waypoint {resume.leg_index + 1} {taken}{replaced}{edited}"


def _plugs(
    args: argparse.Namespace,
    journal: Journal | None,
    snapshots: SnapshotRecorder | None,
    can_bus: can.BusABC | None,
    obstacle_socket: socket.socket | None,
    gcs_link: PymavlinkLink | None,
    socket_path: str | None,
    web: WebServer | None = None,
) -> list[Plug]:
    """The optional parts of this run, as the command line asks for them."""
    plugs = []
    if gcs_link is not None:
        plugs.append(ground_stations(gcs_link, args.gcs_sysid or (255,)))
    if socket_path is not None:
        plugs.append(control_socket(socket_path))
    if journal is not None:
        plugs.append(journal_recorder(journal))
    if snapshots is not None:
        plugs.append(snapshot_recorder(snapshots))
    if can_bus is not None:
        plugs.append(can_base(can_bus))
    if obstacle_socket is not None:
        plugs.append(obstacle_camera(obstacle_socket))
    if web is not None:
        from executive.observers.web.plug import live_view  # the live view's modules only with --web

        plugs.append(live_view(web))
    return plugs


def _open_instrument(mission: Mission, *, simulator: bool) -> None:
    """Before anything moves: the mission's instrument answers (NoVehicle); whether its samples can be real here is check_run's."""
    from executive.instruments.backends import open_sampler
    from executive.instruments.sampler import InstrumentError

    try:
        sampler = open_sampler(mission, ScaledClock(), simulator=simulator)
    except InstrumentError as exc:
        raise NoVehicle(str(exc)) from exc
    if sampler is not None:
        sampler.close()  # the runtime opens it again when the mission starts


def main(args: argparse.Namespace) -> int:
    setup_logging(args.verbose)
    mission = load_or_report(args.mission)
    if mission is None:
        return EXIT_BAD_INPUT
    checked = check_run(args, mission)  # what run refuses, before anything is opened (service install runs the same)
    for note in checked.notes:
        print(f"executive: run: {note}", file=sys.stderr)
    clock = ScaledClock(args.speedup)
    use_clock(clock.now)  # the log's t=: the journal's and the status line's time, whatever the wall clock does
    faults = None
    if checked.faults:
        from executive.sim.faults import FaultInjector

        faults = FaultInjector(list(checked.faults), clock)
    socket_path = _control_socket_path(args.socket)
    signing_key = checked.signing_key
    _open_instrument(mission, simulator=not args.mavlink)
    with contextlib.ExitStack() as stack:
        stop = StopSignals()
        stack.callback(stop.release)  # the last thing undone: a Ctrl-C anywhere in the shutdown finds our handler
        obstacle_socket = _obstacle_socket(args.obstacles, stack)  # before the vehicle: a port in use stops us first
        web = _web_server(args, stack)
        groot2 = _groot2(args, stack)
        live = _foxglove(args, stack)
        storage = Storage()  # the journal, snapshots and tlog on a disk that may fill up: said once, retried
        journal, snapshots = _recorders(args, clock, stack, storage, live)  # before the vehicle: one that cannot be created is refused first
        link = stack.enter_context(_vehicle_link(args, mission, clock, faults, signing_key, storage))
        gcs_link = stack.enter_context(_gcs_link(args.gcs, args.sysid))
        can_bus = _can_bus(args, stack)
        resume = None
        if journal is not None and args.resume:
            resume = journal.resume_point(mission)
            print(f"executive: run: {_resume_text(resume)}", file=sys.stderr)
            if resume is not None and resume.mission is not None:  # replaced while paused (ctl upload): the run goes on with that one
                mission = resume.mission
        watchdog = _service_manager(stack)
        progress = Progress(sys.stdout, clock, quiet=watchdog is not None)  # under systemd: status lines on changes, into the journal
        attach_live_line(progress)  # a log record clears the live line first
        stack.callback(attach_live_line, None)
        plugs = _plugs(args, journal, snapshots, can_bus, obstacle_socket, gcs_link, socket_path, web) + groot2
        if live is not None and (snapshots is None or snapshots.mavlink is None):  # not served with the MCAP file's messages
            served = SnapshotRecorder(None, clock=clock, live=live)
            stack.callback(served.close)
            plugs.append(snapshot_recorder(served))
        runtime = build_runtime(
            mission,
            link,
            clock,
            plugs=plugs if watchdog is None else [*plugs, service_manager(watchdog)],
            rate_hz=args.rate,
            system_id=args.sysid,
            target_system=args.target_system,
            target_component=args.target_component,
            progress=progress,
            autopilot=args.autopilot or mission.autopilot,
            simulated_vehicle=not args.mavlink,
        )
        stack.callback(runtime.close)
        storage.listeners.append(runtime.mission_state.announce)  # the ground station told (STATUSTEXT), as the log and the status line
        if not args.mavlink and clock.speedup > 1.0:  # the simulated world slows down to what the executive follows
            runtime.pacer.listeners.append(SpeedGovernor(clock))
        try:
            # the built-in simulator is alone on its link: no other autopilot to listen for
            connected = runtime.link.connect(args.connect_timeout * clock.speedup, survey_s=SURVEY_S if args.mavlink else 0.0)
        except SeveralAutopilots as exc:
            print(f"executive: run: {exc}", file=sys.stderr)
            return EXIT_NO_VEHICLE
        except KeyboardInterrupt:
            where = args.mavlink or "the simulated vehicle"
            print(f"executive: run: interrupted while waiting for the autopilot's first heartbeat on {where}: nothing was commanded", file=sys.stderr)
            return EXIT_INTERRUPTED
        if not connected:
            which = "an autopilot" if args.target_system is None else f"autopilot {args.target_system}/{args.target_component}"
            on = f" on {link.url}" if link.device is not None else ""
            hint = _signing_hint(link) or _serial_hint(link, runtime.link.reader.bad_data)
            print(f"executive: run: no heartbeat from {which} within {args.connect_timeout:g} s{on}{hint}", file=sys.stderr)
            return EXIT_NO_VEHICLE
        if watchdog is not None:
            watchdog.ready(f"autopilot {'/'.join(map(str, runtime.link.reader.autopilot or ()))} heard on {link.url}; mission {mission.name!r}")
        stop.install(runtime.request_stop)
        try:
            # with --wait, an unfinished run in the journal goes on at once (a restart after a crash); a new one waits for `ctl start`
            with keeping_time(runtime.pacer.late_after_s / clock.speedup):
                outcome = runtime.run(start=not args.wait or resume is not None, serve=args.wait, resume=resume)
        finally:
            if watchdog is not None:
                watchdog.stopping(f"mission {runtime.mission_state.status}: {runtime.mission_state.reason}")
    for line in last_words(outcome, runtime.mission_state):
        print(f"executive: {line}", file=sys.stderr)
    return exit_code(outcome)


class StopSignals:
    """SIGINT and SIGTERM ask the runtime to stop: the mission aborted, the vehicle made safe, the exit code the outcome's.

    A repeated one while it stops changes nothing: it is noted on stderr, the vehicle is made safe
    all the same. Once one has come, Python's own handler never comes back: it would turn a late
    Ctrl-C into a KeyboardInterrupt somewhere in the shutdown and exit 130 (issue 28: two SIGINTs
    10-50 ms apart exited 130, 1, 130, 130 for runs that all ended ABORTED, exit 1). The last
    moments (the last lines, the interpreter's exit, which puts SIG_DFL back for a Python handler:
    killed by SIGINT) ignore them.
    """

    SIGNALS = (signal.SIGINT, signal.SIGTERM)

    def __init__(self) -> None:
        self.received: list[str] = []
        self._stop: Callable[[str], None] | None = None
        self._previous: dict[int, Any] = {}

    def install(self, stop: Callable[[str], None]) -> None:
        """From now on a signal calls ``stop(name)`` (once; the next ones are noted)."""
        self._stop = stop
        for sig in self.SIGNALS:
            self._previous.setdefault(sig, signal.signal(sig, self._on_signal))

    def release(self) -> None:
        """Put the previous handlers back, unless a signal came: then the process is ending, and they are ignored from now on."""
        for sig, handler in self._previous.items():
            signal.signal(sig, signal.SIG_IGN if self.received else handler)
        self._previous = {}

    def _on_signal(self, signum: int, _frame: object) -> None:
        name = signal.Signals(signum).name
        self.received.append(name)
        if len(self.received) == 1 and self._stop is not None:
            self._stop(name)
            return
        # os.write: a signal handler may run in the middle of a write to sys.stderr (a log record), which must not be re-entered
        note = f"executive: run: {name} again: already stopping (the vehicle is made safe all the same; the exit code stays the mission's)\n"
        os.write(2, note.encode())


def exit_code(outcome: RunOutcome) -> int:
    """0 when the mission that ran COMPLETED, or none ran (``--wait``, stopped before any start); 1 when it ended otherwise.

    2 when a user's code (a plugin's tree or behaviour) failed as it started, before anything was commanded: bad input.
    """
    if outcome.users_code:
        return EXIT_BAD_INPUT
    return EXIT_OK if outcome.mission is None or outcome.status is MissionStatus.COMPLETED else EXIT_FAILED


def last_words(outcome: RunOutcome, state: MissionState) -> list[str]:
    """The run's last lines: a mission left loaded and never started, if one was; then the mission that ran, with its own outcome.

    With ``--wait`` the last mission that ran may not be the one loaded when the process stops (an
    upload after it ended): each is named for what it is. Before it, what making the vehicle safe came to, when it was
    (``the vehicle made safe: HOLD (confirmed)``, ``could not make the vehicle safe: ...``). The last line is always the outcome's.
    """
    loaded = f"mission {state.mission.name!r} READY: loaded, never started" if state.status is MissionStatus.READY and state.mission else None
    safe = [outcome.safe] if outcome.safe else []
    if outcome.mission is None:
        return [*safe, f"{loaded or f'no mission loaded ({state.status})'}; no mission ran ({outcome.ticks} ticks)"]
    lines = [loaded] if loaded else []
    if outcome.samples:
        lines.append(f"{outcome.samples} sample{'' if outcome.samples == 1 else 's'} recorded by mission {outcome.mission!r}")
    lines += safe
    return [*lines, f"mission {outcome.mission!r} {outcome.status}: {outcome.reason} ({outcome.ticks} ticks)"]
