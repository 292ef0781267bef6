"""What the executive records on the companion computer's disk (the journal, the snapshots, the tlog), on a disk that may fail.

An SD card fills up, a file system turns read-only after an error: the mission goes on (the
vehicle's safety never depends on the disk). Each recording says its loss once, through
:class:`Storage` (a WARNING in the log, the status line, the ground station told by its listeners),
retries its writes, and keeps what it had written intact: :class:`AppendFile` cuts a record the
disk took only part of, so the file ends at its last complete record.
"""

from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable
from pathlib import Path

from executive.world import blackboard

log = logging.getLogger("executive.storage")


class Storage:
    """The recordings' writes, watched: which cannot write now, said once when it stops and once when it writes again.

    ``listeners`` hear the short text of each loss (``journal cannot write: progress will not
    survive a restart``): the runtime tells the ground station. ``/runtime/storage_lost`` holds
    every current loss for the status line (None: all write).
    """

    def __init__(self) -> None:
        self.lost: dict[str, str] = {}
        self._announced: set[str] = set()
        self.listeners: list[Callable[[str], object]] = []
        self._bb = blackboard.writer("storage", ["/runtime/storage_lost"])
        self._owner = threading.get_ident()  # the thread that ticks: the blackboard and the listeners are its alone
        #: Said by other threads, not yet told: for each recording, its loss (if any) and whether it wrote again after it.
        self._from_threads: dict[str, tuple[tuple[str, BaseException] | None, bool]] = {}
        self._lock = threading.Lock()

    def failed(self, what: str, consequence: str, error: BaseException) -> None:
        """A write of ``what`` failed with ``error``: announced the first time (``what cannot write: consequence``), then kept quiet.

        A disk that is nearly full takes a small record and refuses the next: after the first loss,
        the next ones (and the writes in between) are only logged at INFO. Said by another thread (the
        MCAP encoder's), it waits for :meth:`deliver` on the ticking thread.
        """
        if threading.get_ident() != self._owner:
            with self._lock:
                self._from_threads[what] = ((consequence, error), False)
            return
        self.deliver()
        self._failed(what, consequence, error)

    def wrote(self, what: str) -> None:
        """A write of ``what`` went through: a loss, if there was one, is over."""
        if threading.get_ident() != self._owner:
            with self._lock:
                loss, _ = self._from_threads.get(what, (None, False))
                if loss is not None or what in self.lost:
                    self._from_threads[what] = (loss, True)
            return
        self.deliver()
        self._wrote(what)

    def deliver(self) -> None:
        """What other threads' writes said (a loss, then writing again), told on this (the ticking) thread."""
        if not self._from_threads:
            return
        with self._lock:
            said, self._from_threads = self._from_threads, {}
        for what, (loss, wrote_after) in said.items():
            if loss is not None:
                self._failed(what, *loss)
            if wrote_after:
                self._wrote(what)

    def _failed(self, what: str, consequence: str, error: BaseException) -> None:
        if what in self.lost:
            return
        text = f"{what} cannot write: {consequence}"
        self.lost[what] = f"{text} ({error})"
        self._publish()
        if what in self._announced:
            log.info("%s (%s)", text, error)
            return
        self._announced.add(what)
        log.warning("%s (%s); retrying", text, error)
        for listener in self.listeners:
            listener(text)

    def _wrote(self, what: str) -> None:
        if self.lost.pop(what, None) is not None:
            log.info("%s writes again", what)
            self._publish()

    def _publish(self) -> None:
        self._bb.set("/runtime/storage_lost", "; ".join(self.lost.values()) or None)


class AppendFile:
    """A file written one whole record at a time, unbuffered: a record the disk refuses (full, read-only, too large) is lost,
    never half written; the loss is said through ``storage`` as ``what`` (``consequence``) and each next record tried again.
    """

    def __init__(self, path: str | os.PathLike[str], what: str, consequence: str, storage: Storage | None, *, append: bool = True) -> None:
        self.path = Path(path)
        self.what, self.consequence = what, consequence
        self.storage = storage or Storage()
        self._fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | (os.O_APPEND if append else os.O_TRUNC), 0o644)
        self._size = os.fstat(self._fd).st_size  # where the last complete record ends

    def write(self, record: bytes) -> bool:
        """Write ``record`` whole, or not at all (False: it was lost, and said)."""
        try:
            done = 0
            while done < len(record):
                done += os.write(self._fd, record[done:])
        except OSError as exc:  # ENOSPC, EROFS, EFBIG (a file-size limit), EIO
            if done:
                try:
                    os.ftruncate(self._fd, self._size)  # the file ends at its last complete record again
                except OSError:
                    log.debug("%s: cannot cut a partial record", self.path)
            self.storage.failed(self.what, self.consequence, exc)
            return False
        self._size += done
        self.storage.wrote(self.what)
        return True

    @property
    def size(self) -> int:
        return self._size

    def close(self) -> None:
        os.close(self._fd)
