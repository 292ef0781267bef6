"""The journal: what each run did, in SQLite, so that a crash or a power cut loses nothing.

One row per run; its lifecycle transitions, leg progress, samples and events. The database is in
WAL mode with full sync, and every state change and sample is committed at once: once the
executive has said it, it is on the disk. ``executive run --resume`` reads the last unfinished run
of the same mission back: the leg to continue from, the samples already taken and the route as
the operator last edited it (RC switches, ``ctl route``).

A run is continued by another (``resumed_from``) after a crash, or when the operator replaced its
mission while paused (hot reload: it ends as REPLACED, and the new mission's run begins with the
samples kept, renumbered to its legs). ``--resume`` follows these to the last of them: given the
mission file it started with, it continues on the mission that replaced it.
"""

from __future__ import annotations

import hashlib
import json
import logging
import sqlite3
import time
from collections import deque
from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Any

from executive.io.storage import Storage
from executive.mission.events import RouteChanged, SampleTaken, Stage, Transition
from executive.mission.lifecycle import MissionState, MissionStatus
from executive.mission.model import Home, Mission, Waypoint, mission_model
from executive.mission.reload import REPLACED
from executive.mission.resume import ResumePoint
from executive.mission.route import Route
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import SampleRead, SampleRecord

SCHEMA = """
CREATE TABLE IF NOT EXISTS runs (
    id INTEGER PRIMARY KEY, mission TEXT NOT NULL, mission_hash TEXT NOT NULL, mission_json TEXT NOT NULL,
    vehicle TEXT NOT NULL, started REAL NOT NULL, ended REAL, outcome TEXT, reason TEXT, resumed_from INTEGER
);
CREATE TABLE IF NOT EXISTS transitions (
    run INTEGER NOT NULL REFERENCES runs(id), t REAL NOT NULL, wall REAL NOT NULL, before TEXT NOT NULL, after TEXT NOT NULL, reason TEXT
);
CREATE TABLE IF NOT EXISTS legs (
    run INTEGER NOT NULL REFERENCES runs(id), t REAL NOT NULL, wall REAL NOT NULL, leg INTEGER NOT NULL, lat REAL, lon REAL
);
CREATE TABLE IF NOT EXISTS samples (
    run INTEGER NOT NULL REFERENCES runs(id), leg INTEGER NOT NULL, lat REAL, lon REAL, started REAL, finished REAL, reads TEXT NOT NULL,
    instrument TEXT NOT NULL DEFAULT '', missing TEXT NOT NULL DEFAULT '[]', partial INTEGER NOT NULL DEFAULT 0, UNIQUE (run, leg)
);
CREATE TABLE IF NOT EXISTS events (
    run INTEGER NOT NULL REFERENCES runs(id), t REAL NOT NULL, wall REAL NOT NULL, kind TEXT NOT NULL, text TEXT NOT NULL
);
CREATE TABLE IF NOT EXISTS routes (
    run INTEGER NOT NULL REFERENCES runs(id), t REAL NOT NULL, wall REAL NOT NULL, leg INTEGER NOT NULL, home TEXT,
    waypoints TEXT NOT NULL, reason TEXT NOT NULL
);
"""

if TYPE_CHECKING:
    import py_trees

    from executive.runtime.assembly import Plug, Wiring


#: While the disk refuses the journal's writes, how often (clock seconds) they are tried again when nothing new comes.
RETRY_EVERY_S = 1.0

#: Columns of ``samples`` a journal written by an older executive lacks: name -> declaration.
_ADDED_SAMPLE_COLUMNS = {"instrument": "TEXT NOT NULL DEFAULT ''", "missing": "TEXT NOT NULL DEFAULT '[]'", "partial": "INTEGER NOT NULL DEFAULT 0"}


def mission_hash(mission: Mission) -> str:
    """Identifies a mission's content (a resumed run must be the same mission)."""
    return hashlib.sha256(mission.model_dump_json().encode()).hexdigest()[:16]


class Journal:
    """An SQLite journal of runs; :meth:`attach` it to a run's mission state."""

    def __init__(self, path: str | Path, clock: Clock, storage: Storage | None = None) -> None:
        """Open (or create) the journal; sqlite3.Error when it cannot be (a directory that does not exist, a read-only disk)."""
        self.path = str(path)
        self._clock = clock
        self.storage = storage or Storage()
        #: Statements the disk did not take (full, read-only): tried again, in order, before the next and every RETRY_EVERY_S.
        self._pending: deque[tuple[str, tuple[Any, ...]]] = deque()
        self._next_try = 0.0
        self._flushing = False
        self._db = sqlite3.connect(self.path, isolation_level=None)  # autocommit: every statement is durable on return
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute("PRAGMA synchronous=FULL")
        self._db.executescript(SCHEMA)
        columns = {row[1] for row in self._db.execute("PRAGMA table_info(samples)")}
        for column, declared in _ADDED_SAMPLE_COLUMNS.items():  # a journal from before them
            if column not in columns:
                self._db.execute(f"ALTER TABLE samples ADD COLUMN {column} {declared}")
        self.run: int | None = None
        self._leg: int | None = None
        self._next_run = int(self._db.execute("SELECT COALESCE(MAX(id), 0) FROM runs").fetchone()[0]) + 1  # known even if its row waits

    # -- writing -------------------------------------------------------------------------------
    def begin_run(self, mission: Mission, resumed_from: int | None = None) -> int:
        self.run, self._next_run = self._next_run, self._next_run + 1
        self._execute(
            "INSERT INTO runs (id, mission, mission_hash, mission_json, vehicle, started, resumed_from) VALUES (?, ?, ?, ?, ?, ?, ?)",
            (self.run, mission.name, mission_hash(mission), mission.model_dump_json(), mission.vehicle, time.time(), resumed_from),
        )
        self._leg = None
        return self.run

    def attach(self, state: MissionState) -> None:
        """Record the state's transitions, samples and route edits as they happen."""
        state.events.subscribe(Transition, self._on_transition, Stage.RECORDING)
        state.events.subscribe(SampleTaken, self._on_sample, Stage.RECORDING)
        state.events.subscribe(RouteChanged, self._on_route, Stage.RECORDING)

    def carry_samples(self, samples: tuple[SampleRecord, ...]) -> None:
        """Record in this run the samples a run it continues had taken (a replaced mission's, renumbered to this one's legs)."""
        for sample in samples:
            self._on_sample(sample)

    def observe_leg(self, state: MissionState, lat: float | None, lon: float | None) -> None:
        """Called every tick: records the leg when it changes (with where the vehicle is)."""
        if self._pending and self._clock.now() >= self._next_try:
            self._flush()  # the disk may have room again
        if self.run is None or state.status not in (MissionStatus.RUNNING, MissionStatus.PAUSED) or state.legs.leg_index == self._leg:
            return
        self._leg = state.legs.leg_index
        self._insert("legs", run=self.run, t=self._clock.now(), wall=time.time(), leg=state.legs.leg_index, lat=lat, lon=lon)

    def event(self, kind: str, text: str) -> None:
        if self.run is not None:
            self._insert("events", run=self.run, t=self._clock.now(), wall=time.time(), kind=kind, text=text)

    def end_run(self, outcome: str, reason: str) -> None:
        """The run is over: its outcome recorded; what happens until the next run begins (another mission uploaded...) is none of its business."""
        if self.run is not None:
            self._execute("UPDATE runs SET ended = ?, outcome = ?, reason = ? WHERE id = ?", (time.time(), outcome, reason, self.run))
        self.run = None

    def close(self) -> None:
        self._flush()  # a last try
        if self._pending:
            logging.getLogger("executive.storage").error("journal: %d record(s) lost: the disk would not take them", len(self._pending))
        self._db.close()

    # -- reading -------------------------------------------------------------------------------
    def resume_point(self, mission: Mission) -> ResumePoint | None:
        """The last run of this very mission, or the last of the runs continuing it, if that one never ended (a crash, kill -9, power cut)."""
        wanted = mission_hash(mission)
        row = self._db.execute("SELECT id FROM runs WHERE mission_hash = ? ORDER BY id DESC LIMIT 1", (wanted,)).fetchone()
        if row is None:
            return None
        run = row[0]
        while (child := self._db.execute("SELECT MAX(id) FROM runs WHERE resumed_from = ?", (run,)).fetchone()[0]) is not None:
            run = child  # resumed after a crash, or the run of the mission that replaced it
        ended, hashed, mission_json = self._db.execute("SELECT ended, mission_hash, mission_json FROM runs WHERE id = ?", (run,)).fetchone()
        if ended is not None:
            return None
        # the latest word on the leg: a leg change, or a route edit (which may renumber the legs)
        latest = self._db.execute(
            "SELECT leg FROM (SELECT t, leg, 0 AS edit, rowid AS n FROM legs WHERE run = ? "
            "UNION ALL SELECT t, leg, 1 AS edit, rowid AS n FROM routes WHERE run = ?) ORDER BY t DESC, edit ASC, n DESC LIMIT 1",
            (run, run),
        ).fetchone()
        replacement = None if hashed == wanted else mission_model(json.loads(mission_json)).model_validate_json(mission_json)
        return ResumePoint(run, latest[0] if latest else 0, self.samples(run), self.route(run), replacement)

    def route(self, run: int) -> Route | None:
        """The run's route as last edited (None: never edited)."""
        row = self._db.execute("SELECT leg, home, waypoints FROM routes WHERE run = ? ORDER BY rowid DESC LIMIT 1", (run,)).fetchone()
        if row is None:
            return None
        leg, home, waypoints = row
        return Route(tuple(Waypoint.model_validate(w) for w in json.loads(waypoints)), leg, Home.model_validate_json(home) if home else None)

    def samples(self, run: int) -> tuple[SampleRecord, ...]:
        """The samples of ``run``, partial ones (a named sensor gave no reading) included, by leg."""
        rows = self._db.execute(
            "SELECT leg, lat, lon, started, finished, reads, instrument, missing, partial FROM samples WHERE run = ? ORDER BY leg", (run,)
        )
        return tuple(
            SampleRecord(
                leg,
                lat,
                lon,
                tuple(SampleRead(**r) for r in json.loads(reads)),
                started,
                finished,
                instrument,
                tuple(json.loads(missing)),
                bool(partial),
            )
            for leg, lat, lon, started, finished, reads, instrument, missing, partial in rows
        )

    def report(self, run: int | None = None) -> dict[str, Any]:
        """Everything about one run (the last by default), as plain data.

        Waypoints are numbered from 1, as the status line and ``ctl`` number them: each leg row
        and route edit says the ``waypoint`` the vehicle headed for then (None once past the last),
        its ``name`` (None: unnamed) and the route's ``waypoints`` then; each sample the ``waypoint`` it was taken at.
        """
        if run is None:
            row = self._db.execute("SELECT MAX(id) FROM runs").fetchone()
            run = row[0] if row else None
        if run is None:
            raise LookupError(f"{self.path}: no run recorded")
        columns = ("id", "mission", "vehicle", "started", "ended", "outcome", "reason", "resumed_from")
        head = self._db.execute(f"SELECT {', '.join(columns)} FROM runs WHERE id = ?", (run,)).fetchone()
        if head is None:
            raise LookupError(f"{self.path}: no run {run}")
        (mission_json,) = self._db.execute("SELECT mission_json FROM runs WHERE id = ?", (run,)).fetchone()
        edits = [
            {"t": r["t"], "leg": r["leg"], "names": [w.get("name") for w in json.loads(r["waypoints"])], "reason": r["reason"]}
            for r in self._rows("SELECT t, leg, waypoints, reason FROM routes WHERE run = ? ORDER BY rowid", run)
        ]
        planned = [w.get("name") for w in json.loads(mission_json).get("waypoints", [])]

        def route_names(t: float) -> list[str | None]:
            """The names of the route's waypoints driven at ``t``: the mission's, or its last edit's before then."""
            return next((edit["names"] for edit in reversed(edits) if edit["t"] <= t), planned)

        def heading_for(leg: int, t: float, names: list[str | None] | None = None) -> dict[str, Any]:
            names = route_names(t) if names is None else names
            here = leg < len(names)
            return {"waypoint": leg + 1 if here else None, "waypoints": len(names), "name": names[leg] if here else None}

        samples = []
        for sample in self.samples(run):
            fields = asdict(sample)
            samples.append({"waypoint": fields.pop("leg_index") + 1, **fields})
        return {
            **dict(zip(columns, head, strict=True)),
            "transitions": self._rows("SELECT t, before, after, reason FROM transitions WHERE run = ? ORDER BY rowid", run),
            "legs": [
                {"t": r["t"], **heading_for(r["leg"], r["t"]), "lat": r["lat"], "lon": r["lon"]}
                for r in self._rows("SELECT t, leg, lat, lon FROM legs WHERE run = ? ORDER BY rowid", run)
            ],
            "samples": samples,
            "events": self._rows("SELECT t, kind, text FROM events WHERE run = ? ORDER BY rowid", run),
            "routes": [{"t": e["t"], **heading_for(e["leg"], e["t"], e["names"]), "reason": e["reason"]} for e in edits],
        }

    def runs(self) -> list[int]:
        return [r[0] for r in self._db.execute("SELECT id FROM runs ORDER BY id")]

    # -- internals -------------------------------------------------------------------------------
    def _on_transition(self, before: MissionStatus, after: MissionStatus, reason: str) -> None:
        if self.run is not None:
            self._insert("transitions", run=self.run, t=self._clock.now(), wall=time.time(), before=str(before), after=str(after), reason=reason)

    def _on_sample(self, sample: SampleRecord) -> None:
        if self.run is not None:
            reads = json.dumps([asdict(r) for r in sample.reads])
            row = {"run": self.run, "leg": sample.leg_index, "lat": sample.lat, "lon": sample.lon, "started": sample.started}
            what = {"reads": reads, "instrument": sample.instrument, "missing": json.dumps(sample.missing), "partial": int(sample.partial)}
            self._insert("samples", **row, finished=sample.finished, **what)

    def _on_route(self, route: Route, reason: str) -> None:
        if self.run is not None:
            waypoints = json.dumps([w.model_dump(mode="json", exclude_defaults=True) for w in route.waypoints])
            home = route.home.model_dump_json() if route.home is not None else None
            row = {"run": self.run, "t": self._clock.now(), "wall": time.time(), "leg": route.current}
            self._insert("routes", **row, home=home, waypoints=waypoints, reason=reason)

    def _insert(self, table: str, **row: Any) -> None:
        names = ", ".join(row)
        self._execute(f"INSERT INTO {table} ({names}) VALUES ({', '.join('?' * len(row))})", tuple(row.values()))

    def _execute(self, sql: str, params: tuple[Any, ...]) -> None:
        """Write now, after what waits; what the disk refuses waits (a full or read-only disk never takes the mission down)."""
        self._pending.append((sql, params))
        self._flush()

    def _flush(self) -> None:
        if self._flushing:  # the loss's own log line, journalled as an event: it waits its turn
            return
        self._flushing = True
        batch = list(self._pending)
        try:
            if len(batch) > 1:
                self._db.execute("BEGIN")  # what waited, in one transaction: all of it or none, and one commit's pages
            for statement in batch:
                self._db.execute(*statement)
            if len(batch) > 1:
                self._db.execute("COMMIT")
        except sqlite3.OperationalError as exc:  # full, read-only, I/O error: SQLite rolls back, the file stays whole
            if self._db.in_transaction:
                self._db.execute("ROLLBACK")
            self._next_try = self._clock.now() + RETRY_EVERY_S
            self.storage.failed("journal", "progress will not survive a restart", exc)
            return
        except sqlite3.Error:  # not the disk (a sample recorded twice): the newest statement will never go in; the caller hears it
            if self._db.in_transaction:
                self._db.execute("ROLLBACK")
            self._pending.pop()
            raise
        finally:
            self._flushing = False
        for _ in batch:
            self._pending.popleft()
        self.storage.wrote("journal")

    def _rows(self, sql: str, run: int) -> list[dict[str, Any]]:
        cursor = self._db.execute(sql, (run,))
        names = [column[0] for column in cursor.description]
        return [dict(zip(names, r, strict=True)) for r in cursor]


class JournalLogHandler(logging.Handler):
    """Puts the executive's warnings and errors (link lost, guards failing, refusals, crashes) in the journal as events."""

    #: Loggers whose notes (INFO) are kept too: the energy estimate of every leg (``report`` tells where the energy went).
    NOTED = frozenset({"executive.energy"})

    def __init__(self, journal: Journal, level: int = logging.WARNING) -> None:
        super().__init__(min(level, logging.INFO))
        self._level = level
        self._journal = journal

    def emit(self, record: logging.LogRecord) -> None:
        if record.levelno < self._level and record.name not in self.NOTED:
            return
        try:
            self._journal.event(record.name.rsplit(".", 1)[-1], record.getMessage())
        except Exception:  # the journal must never take the executive down with it
            self.handleError(record)


class _JournalRuns:
    """The journal's part in a run: the run begun and ended, each leg recorded (with where the vehicle was) as it changes.

    A run ended as REPLACED (hot reload) is continued by the next, the new mission's: it begins
    with the event, the samples kept (renumbered to its legs) and its leg, so that ``--resume``
    after a crash finds them there.
    """

    def __init__(self, journal: Journal, state: MissionState) -> None:
        self._journal = journal
        self._state = state
        self._bb = blackboard.reader("journal", ["/vehicle/position"])
        self._replaced: tuple[int, str] | None = None  # the run a replacement ended, and why

    def begin(self, mission: Mission, root: py_trees.behaviour.Behaviour, resumed_from: int | None) -> None:
        replaced, self._replaced = self._replaced, None
        if replaced is None:
            self._journal.begin_run(mission, resumed_from=resumed_from)
            return
        self._journal.begin_run(mission, resumed_from=replaced[0])
        self._journal.event("mission", replaced[1])
        self._journal.carry_samples(self._state.sample_log.taken)
        self.ticked(0, 0.0)

    def ticked(self, tick: int, now: float) -> None:
        position = self._bb.get("/vehicle/position")
        self._journal.observe_leg(self._state, *((position.lat, position.lon) if position else (None, None)))

    def end(self, status: str, reason: str) -> None:
        if status == REPLACED and self._journal.run is not None:
            self._journal.event("mission", reason)
            self._replaced = (self._journal.run, reason)
        self._journal.end_run(status, reason)


def journal_recorder(journal: Journal) -> Plug:
    """Record the run in ``journal``: transitions, legs, samples, route edits, the outcome."""

    def plug(w: Wiring) -> None:
        journal.attach(w.mission_state)
        w.observers.append(_JournalRuns(journal, w.mission_state))

    return plug
