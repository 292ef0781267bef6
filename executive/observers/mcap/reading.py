"""An MCAP recording (:mod:`executive.observers.mcap.recording`) read back as the snapshot file's lines, seeking through its index.

The lines are the JSON-lines snapshot file's: ``{"tree": nodes}``, then each tick's (``tick``,
``t``, ``key``, ``end``, ``s``, ``f``, ``bb``), so :mod:`executive.observers.snapshots` replays either file
the same way. A finished file's ``executive.keyframes`` metadata says when each keyframe was
written: a tick is found by seeking to the keyframe before it, not by reading from the start.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

TICK_TOPICS = ("/tree", "/tree/tick", "/blackboard")


def keyframes(reader: Any) -> list[tuple[int, int, int]] | None:
    """Each keyframe's (tick, log time ns, its tree's log time ns); None for a file cut short (no summary to seek with)."""
    try:
        return [tuple(k) for record in reader.iter_metadata() if record.name == "executive.keyframes" for k in json.loads(record.metadata["ticks"])]
    except Exception:  # a file cut by a crash has no summary: read from the start
        return None


def _seek(reader: Any, tick: int) -> tuple[int, dict[str, Any]] | None:
    """The time of the last keyframe before ``tick`` and the tree line it belongs to; None without (an unfinished file).

    Before, not at: a keyframe's own changes are told against the tick before it.
    """
    before = [(ns, tree_ns) for key, ns, tree_ns in keyframes(reader) or () if key < tick]
    if not before:
        return None
    ns, tree_ns = before[-1]
    trees = [json.loads(m.data) for _, _, m in reader.iter_messages(topics=["/tree"], starting_at=tree_ns, ending_at=tree_ns)]
    return (ns, {"tree": trees[-1]["nodes"]}) if trees else None


def timed_lines(part: Path, starting_at: int | None = None) -> Iterator[tuple[int, dict[str, Any]]]:
    """Each line with its log time (ns), in the order written; from log time ``starting_at`` on (through the index) when given."""
    from mcap.reader import make_reader

    pending: tuple[int, dict[str, Any]] | None = None
    window = {"starting_at": starting_at} if starting_at is not None else {}
    with part.open("rb") as f:
        for _, channel, message in make_reader(f).iter_messages(topics=TICK_TOPICS, **window):
            body = json.loads(message.data)
            if channel.topic == "/blackboard" and pending is not None:
                pending[1]["bb"] = body["bb"]  # a tick's blackboard follows its /tree/tick message
                continue
            if pending is not None:
                yield pending
            if channel.topic == "/tree":
                pending = None
                yield message.log_time, {"tree": body["nodes"]}
            else:
                pending = (message.log_time, {**body, "t": round(message.log_time / 1e9, 3)})
    if pending is not None:
        yield pending


def tick_lines(part: Path, near: int | None = None) -> Iterator[dict[str, Any]]:
    """An MCAP recording as the JSON-lines file's lines, in the order written.

    With ``near``: from the last keyframe before tick ``near`` (its tree line first), found through the index.
    """
    from mcap.reader import make_reader

    start = None
    if near is not None:
        with part.open("rb") as f:
            start = _seek(make_reader(f), near)
    if start is not None:
        yield start[1]
    for _, line in timed_lines(part, start[0] if start is not None else None):
        yield line
