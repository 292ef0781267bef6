"""The CAN reader: drains the bus each tick and writes what the AgileX base says on the blackboard.

RC (``rc=True``, for ``rc.source: can``): /rc/switches and /rc/sticks when they change, and
/rc/last_update only when a 0x241 frame brings a NEW rolling counter value. In CAN command mode
the base keeps repeating its last 0x241 frame after the transmitter is lost, and reports no fault
(the thesis's field finding): a frozen counter is the only sign, and the RC reader turns the
stalled /rc/last_update into /rc/fresh False after ``rc.fresh_timeout_s``. While the base reports
RC signal loss (0x211) the counter does not count either.

The base: /base/system, /base/faults, /base/motion, /base/odometry, /base/last_update and /base/up.
Frames that cannot be used are counted (/base/bad_frames, /base/other_frames) and never crash it;
neither does a bus error (/base/bus_errors): the reader tries again next tick.
"""

from __future__ import annotations

import logging
from typing import Any

import can

from executive.io.can.agilex import CONTROL_MODES, VEHICLE_STATES, FrameStats, MotionState, Odometry, RcState, SystemState, decode
from executive.io.can.state import BaseMotion, BaseOdometry, BaseSystem, RcSticks
from executive.world import blackboard
from executive.world.clock import Clock
from executive.world.state import RcSwitches

log = logging.getLogger(__name__)

_RC_KEYS = ("/rc/switches", "/rc/sticks", "/rc/last_update")
_DRIVE_KEYS = ("/base/drive", "/base/send_errors")


class CanReader:
    """Drains a python-can bus (non-blocking) and keeps ``/base`` and, with ``rc``, the CAN side of ``/rc``."""

    def __init__(self, bus: can.BusABC, clock: Clock, *, rc: bool = True, base_timeout_s: float = 1.0) -> None:
        self._bus = bus
        self._clock = clock
        self.rc = rc
        self.base_timeout_s = base_timeout_s
        keys = [k for k in blackboard.keys_under("/base/") if k not in _DRIVE_KEYS] + (list(_RC_KEYS) if rc else [])
        self._bb = blackboard.writer("can reader", keys)
        self.stats = FrameStats()
        self.rc_counter: int | None = None  # the last 0x241 rolling counter seen
        self.rc_counter_repeats = 0
        self.bus_errors = 0
        self._rc_signal_lost = False
        self._last_frame: float | None = None

    def drain(self, max_frames: int = 10_000) -> int:
        """Handle every frame waiting on the bus (at most ``max_frames``); returns how many."""
        now = self._clock.now()
        count = 0
        latest: dict[type, Any] = {}
        new_rc_counter = False
        while count < max_frames:
            try:
                msg = self._bus.recv(0.0)
            except Exception as exc:  # a bus going down raises CanOperationError or OSError; try again next tick
                self._bus_error(exc)
                break
            if msg is None:
                break
            count += 1
            frame = decode(msg)
            if not self.stats.record(msg, frame):
                continue
            if isinstance(frame, RcState):
                new_rc_counter |= self._on_rc_counter(frame.counter)
            elif isinstance(frame, SystemState):
                self._rc_signal_lost = frame.rc_signal_lost
            if isinstance(frame, RcState | SystemState | MotionState | Odometry):
                latest[type(frame)] = frame
                self._last_frame = now
        if count:
            self._write_counts()
        self._write_frames(latest, now, new_rc_counter)
        self._base_up(self._last_frame is not None and now - self._last_frame <= self.base_timeout_s, now)
        return count

    def _base_up(self, up: bool, now: float) -> None:
        """``/base/up``, and a word when the base is found or lost (the operator reads it; a run with --can says what it found)."""
        if self._bb.get("/base/up") == up:
            return
        self._bb.set("/base/up", up)
        system: BaseSystem | None = self._bb.get("/base/system")
        if up:
            said = "" if system is None else f": {system.vehicle_state}, {system.control_mode} command mode, {system.battery_v:.1f} V"
            log.info("AgileX base heard on the CAN bus%s", said)
        elif self._last_frame is not None:
            log.warning("AgileX base not heard on the CAN bus for %.1f s", now - self._last_frame)

    def _on_rc_counter(self, counter: int) -> bool:
        """True when ``counter`` moved (and the base does not report RC signal loss)."""
        if counter == self.rc_counter:
            self.rc_counter_repeats += 1
            return False
        self.rc_counter = counter
        return not self._rc_signal_lost

    def _write_frames(self, latest: dict[type, Any], now: float, new_rc_counter: bool) -> None:
        if latest:
            self._bb.set("/base/last_update", now)
        system: SystemState | None = latest.get(SystemState)
        if system is not None:
            value = BaseSystem(
                VEHICLE_STATES[system.vehicle_state], CONTROL_MODES[system.control_mode], system.battery_v, system.fault_code, system.faults, now
            )
            self._bb.set("/base/system", value)
            self._set_if_changed("/base/faults", value.faults)
        motion: MotionState | None = latest.get(MotionState)
        if motion is not None:
            self._bb.set("/base/motion", BaseMotion(motion.linear_m_s, motion.angular_rad_s, now))
        odometry: Odometry | None = latest.get(Odometry)
        if odometry is not None:
            self._bb.set("/base/odometry", BaseOdometry(odometry.left_mm / 1000.0, odometry.right_mm / 1000.0, now))
        rc: RcState | None = latest.get(RcState)
        if self.rc and rc is not None:
            self._write_rc(rc, now, new_rc_counter)

    def _write_rc(self, rc: RcState, now: float, new_counter: bool) -> None:
        switches: RcSwitches | None = self._bb.get("/rc/switches")
        if switches is None or (switches.swa, switches.swb, switches.swc, switches.swd, switches.knob) != (rc.swa, rc.swb, rc.swc, rc.swd, rc.knob):
            self._bb.set("/rc/switches", RcSwitches(rc.swa, rc.swb, rc.swc, rc.swd, rc.knob, now))
        sticks: RcSticks | None = self._bb.get("/rc/sticks")
        if sticks is None or (sticks.right_lr, sticks.right_ud, sticks.left_lr, sticks.left_ud) != (rc.right_lr, rc.right_ud, rc.left_lr, rc.left_ud):
            self._bb.set("/rc/sticks", RcSticks(rc.right_lr, rc.right_ud, rc.left_lr, rc.left_ud, now))
        if new_counter:
            self._bb.set("/rc/last_update", now)

    def _write_counts(self) -> None:
        self._set_if_changed("/base/frames", self.stats.frames)
        self._set_if_changed("/base/bad_frames", self.stats.bad)
        self._set_if_changed("/base/other_frames", self.stats.other)
        self._set_if_changed("/base/rc_counter_repeats", self.rc_counter_repeats)

    def _bus_error(self, exc: Exception) -> None:
        self.bus_errors += 1
        if self.bus_errors == 1 or self.bus_errors % 100 == 0:
            log.warning("CAN bus read failed (%d so far): %s", self.bus_errors, exc)
        self._bb.set("/base/bus_errors", self.bus_errors)

    def _set_if_changed(self, key: str, value: object) -> None:
        if self._bb.get(key) != value:
            self._bb.set(key, value)
