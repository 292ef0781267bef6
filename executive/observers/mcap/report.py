"""``executive report FILE.mcap``: what a run did, read from an MCAP recording, in the journal's report's shape.

The journal stays the crash-proof store of a run's progress (samples, route edits); an MCAP file
holds what a person looks at: each run's mission (``/mission/run``), its transitions
(``/mission/events``), its legs (``/mission/state``, with the last fix), its warnings (``/log``).
Times are vehicle time; ``ended`` is not known (None), nor are samples and route edits (empty).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

#: What ends a run.
ENDS = ("COMPLETED", "ABORTED")
#: Log lines kept as events, as the journal keeps them: warnings and up, and each leg's energy estimate.
NOTED = frozenset({"executive.energy"})
_TOPICS = ("/mission/run", "/mission/events", "/mission/state", "/vehicle/location", "/log")


def _new_run(number: int, info: dict[str, Any] | None) -> dict[str, Any]:
    info = info or {}
    return {
        "id": number, "mission": info.get("mission", "?"), "vehicle": info.get("vehicle", "?"), "started": info.get("started"),
        "ended": None, "outcome": None, "reason": None, "resumed_from": info.get("resumed_from"),
        "transitions": [], "legs": [], "samples": [], "events": [], "routes": [],
        "_names": [w.get("name") for w in info.get("waypoints", [])], "_leg": None, "_before_run": not info,
    }  # fmt: skip


def runs(path: Path) -> list[dict[str, Any]]:
    """Every run the recording holds (its rotated ``FILE.1`` first), oldest first."""
    from mcap.reader import make_reader

    found: list[dict[str, Any]] = []
    fix: tuple[float, float] | None = None
    for part in (path.with_name(path.name + ".1"), path):
        if not part.exists():
            continue
        with part.open("rb") as f:
            for _, channel, message in make_reader(f).iter_messages(topics=_TOPICS):
                body, t = json.loads(message.data), round(message.log_time / 1e9, 3)
                topic = channel.topic
                if topic == "/mission/run":
                    if found and found[-1]["_before_run"]:
                        found.pop()  # what came before the first run began (loading the mission), as the journal leaves it out
                    if not found or (found[-1]["started"], found[-1]["mission"]) != (body.get("started"), body.get("mission")):
                        found.append(_new_run(len(found) + 1, body))  # else: the same run's, again at the top of a rotated file
                    continue
                if not found:
                    found.append(_new_run(1, None))  # a recording from before /mission/run (`executive convert`)
                run = found[-1]
                if topic == "/vehicle/location":
                    fix = (body["latitude"], body["longitude"])
                elif topic == "/mission/events":
                    run["transitions"].append({"t": t, "before": body["before"], "after": body["after"], "reason": body["reason"]})
                    if body["after"] in ENDS:
                        run["outcome"], run["reason"] = body["after"], body["reason"]
                elif topic == "/mission/state":
                    _leg(run, body, t, fix)
                elif topic == "/log" and (body["level"] >= 3 or body["name"] in NOTED):
                    run["events"].append({"t": t, "kind": body["name"].rsplit(".", 1)[-1], "text": body["message"]})
    for run in found:
        del run["_names"], run["_leg"], run["_before_run"]
    return found


def _leg(run: dict[str, Any], state: dict[str, Any], t: float, fix: tuple[float, float] | None) -> None:
    """A leg row when the leg changes while the mission runs (or is paused), as the journal records it."""
    leg = state.get("leg_index")
    if state.get("state") not in ("RUNNING", "PAUSED") or leg is None or leg == run["_leg"]:
        return
    run["_leg"] = leg
    names, count = run["_names"], state.get("leg_count") or len(run["_names"])
    here = leg < count
    name = names[leg] if here and leg < len(names) else None
    lat, lon = fix if fix is not None else (None, None)
    run["legs"].append({"t": t, "waypoint": leg + 1 if here else None, "waypoints": count, "name": name, "lat": lat, "lon": lon})


def report(path: Path, run: int | None = None) -> dict[str, Any]:
    """One run (the last by default) as :meth:`executive.observers.journal.Journal.report` gives it; LookupError naming the file."""
    found = runs(path)
    if not found:
        raise LookupError(f"{path}: no run recorded")
    if run is None:
        return found[-1]
    if not 1 <= run <= len(found):
        raise LookupError(f"{path}: no run {run} (runs 1 to {len(found)})")
    return found[run - 1]
