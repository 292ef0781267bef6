"""``executive service install MISSION``: run a mission under systemd on the companion computer.

Writes a unit file (``/etc/systemd/system/executive-NAME.service``, or ``--print`` it) whose
``ExecStart`` is ``executive run MISSION --journal DB --resume ...``. What each directive is for
is written in the unit itself (:func:`unit_file`); in short:

- ``Type=notify``: the executive says READY=1 once the autopilot answers, and its status line as
  STATUS= (``systemctl status executive-NAME``); :mod:`executive.io.systemd`.
- ``WatchdogSec=``: WATCHDOG=1 is sent from the tick loop every half of it; a loop stuck that long
  is killed (SIGABRT) and, by ``Restart=on-failure``, started again.
- ``--journal`` and ``--resume``: a restart after a crash, a kill or a power cut continues the
  unfinished run at its first unfinished leg, on its route as last edited, no sample taken twice.
- ``RestartPreventExitStatus=1 2``: a mission that ended ABORTED or FAILED (the vehicle made safe)
  or a refused mission file is never started again by itself; exit 3 (no autopilot yet) is retried.
- Logs: stdout (status JSON lines on changes) and stderr (log records with their syslog priority)
  go to the system journal: ``journalctl -u executive-NAME``.
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import sys
from pathlib import Path

from executive import __version__
from executive.cli import EXIT_BAD_INPUT, EXIT_FAILED, EXIT_OK, BadInput, number
from executive.cli.common import load_or_report
from executive.cli.examples import mission_file

UNIT_DIR = "/etc/systemd/system"
#: Where the service's state lives (systemd's StateDirectory=executive): the journals.
STATE_DIR = "/var/lib/executive"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("service", help="run a mission as a systemd service on the companion computer (install the unit)")
    actions = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    install = actions.add_parser(
        "install",
        help="write the systemd unit that runs MISSION (Type=notify, watchdog, restart and resume from the journal)",
        description="Write the systemd unit that runs MISSION: Type=notify, WatchdogSec fed from the tick loop, Restart=on-failure with "
        "--journal and --resume so a restart continues the mission, logs in the system journal.",
    )
    install.add_argument("mission", type=mission_file, help="mission YAML file (checked now; the unit names it by its absolute path)")
    install.add_argument("--mavlink", metavar="URL", help="the autopilot link (/dev/ttyACM0,921600, udpin:0.0.0.0:14550...); none: the simulator")
    install.add_argument("--journal", metavar="DB", help=f"the run's journal, for --resume (default {STATE_DIR}/NAME.db)")
    install.add_argument(
        "--record",
        metavar="FILE",
        help="record every tick as `run --snapshots FILE` does (FILE.mcap: MCAP, for Foxglove); rotated past --record-rotate-mb",
    )
    install.add_argument("--record-rotate-mb", type=number(at_least=0.01), metavar="MB", help="as `run --snapshots-rotate-mb` (default 50)")
    install.add_argument("--name", help="the unit is executive-NAME.service (default: the mission file's name)")
    install.add_argument("--user", help="run as this user (in group dialout for a serial autopilot); default root")
    install.add_argument("--watchdog-sec", type=number(at_least=2.0), default=20.0, metavar="S", help="WatchdogSec (default 20; pinged every S/2)")
    install.add_argument(
        "--start-at-boot",
        action="store_true",
        help="start the mission as soon as the service starts, at every boot (default: load it READY and wait for `ctl start` or a "
        "ground station's MISSION_START; an unfinished run resumes at once either way)",
    )
    install.add_argument("--unit-dir", default=UNIT_DIR, metavar="DIR", help="where to write the unit (default %(default)s)")
    install.add_argument("--print", action="store_true", dest="print_only", help="print the unit instead of writing it")
    more = "more `executive run` options, after = and quoted: --run-options='--gcs udpin:0.0.0.0:14551'"
    install.add_argument("--run-options", type=shlex.split, default=[], metavar="'OPTIONS'", help=more)
    p.set_defaults(func=main)


def exec_quote(arg: str) -> str:
    """One argument of an ExecStart= line, as systemd reads it back (systemd.service(5): quoting, ``%`` specifiers, ``$`` variables)."""
    arg = arg.replace("%", "%%").replace("$", "$$")
    if arg and not re.search(r'[\s"\'\\;]', arg):
        return arg
    return '"' + arg.replace("\\", "\\\\").replace('"', '\\"') + '"'


def unit_name(mission: Path, name: str | None) -> str:
    """``executive-NAME``: from ``name``, else the mission file's stem, as a unit name allows."""
    base = re.sub(r"[^A-Za-z0-9_.-]", "-", name or mission.stem).strip("-.") or "mission"
    return f"executive-{base}"


def run_arguments(args: argparse.Namespace, mission: Path, unit: str) -> list[str]:
    """The ``executive run`` arguments the unit starts the service with (after ``run``)."""
    journal = args.journal or f"{STATE_DIR}/{unit.removeprefix('executive-')}.db"
    run = [str(mission), "--journal", journal, "--resume", "--socket", f"/run/{unit}/control.sock"]
    if args.mavlink:
        run += ["--mavlink", args.mavlink]
    if args.record:
        run += ["--snapshots", str(Path(args.record).absolute())]
        if args.record_rotate_mb is not None:
            run += ["--snapshots-rotate-mb", f"{args.record_rotate_mb:g}"]
    if not args.start_at_boot:  # a reboot, or the last run's end, must not set the vehicle off on its own
        run.append("--wait")
    return [*run, *args.run_options]


def unit_file(args: argparse.Namespace, mission: Path, unit: str, python: str = sys.executable) -> str:
    """The unit's text, each directive with why it is there."""
    run = [python, "-m", "executive", "run", *run_arguments(args, mission, unit)]
    half = args.watchdog_sec / 2
    user = f"User={args.user}\nSupplementaryGroups=dialout\n" if args.user else ""
    vehicle = "" if args.mavlink else "# No --mavlink: the built-in simulated vehicle (a dry run of the service).\n"
    return f"""\
# {unit}.service: runs the mission {mission} with the executive (written by `executive service install`, executive {__version__}).
# Install: systemctl daemon-reload && systemctl enable --now {unit}
# Follow:  systemctl status {unit}; journalctl -u {unit} -f; executive ctl --socket /run/{unit}/control.sock status
{vehicle}
[Unit]
Description=executive: mission {mission.name}
Wants=network-online.target
After=network-online.target
# exit 3 (no autopilot yet: it boots slower than we do) is retried for as long as it takes
StartLimitIntervalSec=0

[Service]
# READY=1 once the autopilot's heartbeat is heard; STATUS= is the status line (systemctl status)
Type=notify
NotifyAccess=main
ExecStart={" ".join(exec_quote(arg) for arg in run)}
# WATCHDOG=1 from the tick loop every {half:g} s: a loop stuck for {args.watchdog_sec:g} s is killed (SIGABRT) and restarted.
# Longer than the 5 s the executive may wait for the vehicle to confirm its safe mode.
WatchdogSec={args.watchdog_sec:g}
# a crash (exit 70), a watchdog kill, a signal or no autopilot (exit 3): start again; --resume goes on with the unfinished run
Restart=on-failure
RestartSec=5
# the mission ended ABORTED or FAILED (the vehicle is safe: a person looks first) or the mission file was refused: never again by itself
RestartPreventExitStatus=1 2
# --connect-timeout (30 s) to hear the autopilot, then READY=1
TimeoutStartSec=60
# SIGTERM (systemctl stop) aborts the mission and waits up to 5 s for the vehicle's safe mode
TimeoutStopSec=30
{user}StateDirectory=executive
RuntimeDirectory={unit}
Environment=PYTHONUNBUFFERED=1
# stdout (status lines) and stderr (log records with their syslog priority) go to the system journal
StandardOutput=journal
StandardError=journal
SyslogIdentifier={unit}

[Install]
WantedBy=multi-user.target
"""


def main(args: argparse.Namespace) -> int:
    mission = load_or_report(args.mission)
    if mission is None:
        return EXIT_BAD_INPUT
    from executive.cli import build_parser
    from executive.cli.run_checks import check_run

    if args.record_rotate_mb is not None and not args.record:
        raise BadInput("--record-rotate-mb: there is no --record to rotate")
    path = Path(args.mission).resolve()
    unit = unit_name(path, args.name)
    try:  # the very command line the unit runs, checked now as `run` checks it, not at the vehicle's next boot
        run_args = build_parser("run").parse_args(["run", *run_arguments(args, path, unit)])
    except SystemExit as exc:
        raise BadInput(f"--run-options: not `executive run` options: {shlex.join(args.run_options)}") from exc
    try:
        check_run(run_args, mission)  # exit 2 there would be RestartPreventExitStatus: a service that fails once and stays down
    except BadInput as exc:
        raise BadInput(f"`executive run` would refuse it (exit 2, never restarted): {exc}") from exc
    text = unit_file(args, path, unit)
    if args.print_only:
        sys.stdout.write(text)
        return EXIT_OK
    target = Path(args.unit_dir) / f"{unit}.service"
    try:
        target.write_text(text, encoding="utf-8")
    except OSError as exc:
        print(f"executive: service: cannot write {target}: {exc} (as root: sudo; or --print, or --unit-dir)", file=sys.stderr)
        return EXIT_FAILED
    os.chmod(target, 0o644)
    print(f"executive: service: wrote {target}")
    print(f"  systemctl daemon-reload && systemctl enable --now {unit}")
    return EXIT_OK
