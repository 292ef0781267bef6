"""The simulated vehicles' battery: a pack drained by a physical model of each kind, reported as its firmware reports it.

Current is drawn from the throttle (a rover's or a boat's drive, a sub's thrusters, a VTOL's lift
motors or pusher: each firmware's ``_throttle`` says how hard the vehicle works for its speed or
thrust), on top of the electronics' own draw; a fault may raise it (a headwind, a current: the
vehicle works harder for the same way made good). The pack's voltage follows a Li-ion/LiPo cell's
open-circuit curve over its state of charge, less the sag of its internal resistance under load.

What is reported, per firmware (both fill SYS_STATUS's battery fields from the same monitor):

- ArduPilot (``libraries/GCS_MAVLink/GCS_Common.cpp`` send_battery_status, an analog voltage and
  current monitor, BATT_MONITOR 4): ``current_consumed`` mAh and ``energy_consumed`` hJ (consumed_wh * 36)
  counted since boot, ``battery_remaining`` from BATT_CAPACITY less the mAh consumed, no cell
  voltages (the pack's voltage in cell 0, the rest UINT16_MAX), ``time_remaining`` 0 (not estimated).
- PX4 (``src/modules/mavlink/streams/BATTERY_STATUS.hpp``): ``current_consumed`` mAh,
  ``energy_consumed`` always -1, ``battery_remaining`` from its estimator (``src/lib/battery/battery.cpp``
  starts it from the voltage at rest: a pack not fully charged reads so), ``id`` battery 1 - 1 = 0.

A weak battery (fault ``weak_battery``) holds only a share of its rated charge at the start; ArduPilot
cannot tell (its counter starts full at boot: ``AP_BattMonitor_Analog``), PX4 reads it from the voltage.
"""

from __future__ import annotations

import itertools
from bisect import bisect_left
from dataclasses import dataclass

#: A cell's open-circuit voltage over its state of charge (0..1), a LiPo's typical curve (4.2 V full, 3.3 V empty).
_OCV_CURVE = ((0.0, 3.30), (0.05, 3.50), (0.10, 3.60), (0.20, 3.68), (0.50, 3.80), (0.80, 3.98), (0.95, 4.13), (1.0, 4.20))
# the curve's spans and their upper ends, for the look-up at every step of the simulated firmware
_OCV_SPANS = tuple(itertools.pairwise(_OCV_CURVE))
_OCV_SPAN_ENDS = tuple(c1 for _, (c1, _) in _OCV_SPANS)


def cell_voltage(charge: float) -> float:
    """A cell's open-circuit voltage at ``charge`` (0..1 of its capacity)."""
    charge = charge if charge > 0.0 else 0.0  # min(1, max(0, charge)) without the builtins: every step of the simulated firmware
    charge = charge if charge < 1.0 else 1.0
    index = bisect_left(_OCV_SPAN_ENDS, charge)  # the first span that reaches the charge
    if index == len(_OCV_SPANS):
        return _OCV_CURVE[-1][1]
    (c0, v0), (c1, v1) = _OCV_SPANS[index]
    return v0 + (v1 - v0) * (charge - c0) / (c1 - c0)


@dataclass(frozen=True, slots=True)
class BatterySpec:
    """One kind's pack and load: ``cells`` in series, ``capacity_mah``, ``internal_ohm`` for the pack; ``idle_a`` the
    electronics' draw, ``armed_a`` more when armed and at rest, ``full_a`` more at full throttle (current grows as
    throttle^1.5: thrust, and drag, grow faster than speed)."""

    cells: int
    capacity_mah: float
    internal_ohm: float
    idle_a: float
    armed_a: float
    full_a: float

    @property
    def capacity_wh(self) -> float:
        """The rated energy at the cells' nominal 3.7 V."""
        return self.capacity_mah / 1000.0 * self.cells * 3.7


#: Per simulated kind. A 3S 10 Ah pack for the ground and surface vehicles, a 4S 18 Ah
#: pack for the sub, a 6S 16 Ah pack for the VTOL whose hover draws ~45 A and cruise ~15 A.
SPECS: dict[str, BatterySpec] = {
    "rover": BatterySpec(3, 10000.0, 0.02, 0.5, 2.0, 10.0),
    "bunker": BatterySpec(3, 10000.0, 0.02, 0.5, 2.0, 10.0),
    "boat": BatterySpec(3, 10000.0, 0.02, 0.5, 2.0, 10.0),
    "sub": BatterySpec(4, 18000.0, 0.02, 1.0, 3.0, 20.0),
    "vtol": BatterySpec(6, 16000.0, 0.015, 0.5, 1.5, 60.0),
}


class SimBattery:
    """The pack: drained by :meth:`draw`, read by the firmware's SYS_STATUS and BATTERY_STATUS."""

    def __init__(self, spec: BatterySpec, charge: float = 1.0) -> None:
        """``charge``: the share of its capacity it holds at the start (a weak battery: less than 1)."""
        self.spec = spec
        self.start_charge = charge
        self.consumed_mah = 0.0  # since boot, as both firmwares count it
        self.consumed_wh = 0.0
        self.current_a = spec.idle_a

    def load_a(self, throttle: float, armed: bool, factor: float = 1.0) -> float:
        """The current drawn at ``throttle`` (0..1); ``factor`` scales the work (a headwind, a current)."""
        spec = self.spec
        if not armed:
            return spec.idle_a
        return spec.idle_a + (spec.armed_a + spec.full_a * (throttle if throttle > 0.0 else 0.0) ** 1.5) * factor

    def draw(self, current_a: float, dt: float) -> None:
        """``current_a`` for ``dt`` seconds."""
        self.current_a = current_a
        volts = self.voltage_v
        self.consumed_mah += current_a * dt / 3.6
        self.consumed_wh += current_a * volts * dt / 3600.0

    @property
    def charge(self) -> float:
        """The share of its capacity left (0..1)."""
        left = self.start_charge - self.consumed_mah / self.spec.capacity_mah
        return left if left > 0.0 else 0.0

    @property
    def voltage_v(self) -> float:
        """The pack's voltage under the present load."""
        volts = self.spec.cells * cell_voltage(self.charge) - self.current_a * self.spec.internal_ohm
        return volts if volts > 0.0 else 0.0

    def remaining_pct(self, counted_from_full: bool) -> int:
        """battery_remaining: ArduPilot counts from a full pack at boot (``counted_from_full``), PX4 knows the charge."""
        if counted_from_full:
            return max(0, round(100.0 * (1.0 - self.consumed_mah / self.spec.capacity_mah)))
        return max(0, round(100.0 * self.charge))
