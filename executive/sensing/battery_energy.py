"""The battery read as energy: what the pack holds, what has been drawn, and what is left above the mission's reserve.

From what the autopilot reports and the mission's ``energy:`` block, never a guess presented as a figure:

- **capacity**, Wh: ``energy.capacity_wh``; else the autopilot's capacity in mAh (ArduPilot BATT_CAPACITY,
  ``libraries/AP_BattMonitor/AP_BattMonitor_Params.cpp``; PX4 BAT1_CAPACITY, ``src/lib/battery/module.yaml``,
  -1 = unknown) times the pack's nominal voltage: ``energy.nominal_v``, or PX4's BAT1_N_CELLS x 3.7 V (a
  Li-ion/LiPo cell's nominal). ArduPilot has no cell count: without ``nominal_v`` the cells are counted from the
  pack's voltage at rest before arming, where only one count puts each cell within 3.65-4.25 V (a Li-ion/LiPo
  pack charged enough to start: 12.6 V is 3 cells); else its mAh are not Wh, and the rule says to set ``nominal_v``.
- **drawn**, Wh: BATTERY_STATUS ``energy_consumed`` (hJ; ArduPilot sends consumed_wh * 36, ``GCS_Common.cpp``
  send_battery_status); else ``current_consumed`` mAh times the pack's voltage (PX4 sends energy_consumed -1,
  ``src/modules/mavlink/streams/BATTERY_STATUS.hpp``). A monitor that measures no current (ArduPilot
  BATT_MONITOR 3, voltage only) reports both -1: the energy drawn cannot be counted, the rule refuses.
- **charge at the start**: ``battery_remaining`` when the mission starts (BATTERY_STATUS, else SYS_STATUS);
  -1 = not estimated: refused.

Left above the reserve = capacity x remaining at start - drawn since - capacity x (reserve + unusable share).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from dataclasses import dataclass

from executive.mission.model import EnergyConfig
from executive.world.state import Battery, BatteryStatus

#: A Li-ion/LiPo cell's nominal voltage: PX4's BAT1_N_CELLS turned into a pack voltage.
CELL_NOMINAL_V = 3.7

#: What each ArduPilot BATT_MONITOR kind can tell (AP_BattMonitor.h Type): the manual's table (docs/missions.md, Energy) says the same.
MONITOR_KINDS: dict[int, str] = {0: "none", 3: "voltage only (no current: nothing counted)", 4: "voltage and current"}


@dataclass(frozen=True, slots=True)
class Capacity:
    """The pack's energy and where the figure came from (for the refusal and the status)."""

    wh: float
    source: str


#: A resting Li-ion/LiPo cell charged enough to start a mission: the band the cells are counted by (3.65 V is ~15 % left).
CELL_AT_REST_V = (3.65, 4.25)


@dataclass(frozen=True, slots=True)
class NotJudged:
    """A vehicle whose battery cannot tell its energy, on a mission that did not ask for the rule: it runs, warned, unjudged."""

    why: str


@functools.lru_cache(maxsize=16)
def cells_at_rest(volts: float) -> int | None:
    """The pack's cells in series, from its voltage at rest: the one count that puts each cell in :data:`CELL_AT_REST_V`.

    Remembered: the capacity is judged again at each battery report with the same voltage at rest (30 divisions each time).
    """
    low, high = CELL_AT_REST_V
    counts = [n for n in range(1, 31) if low <= volts / n <= high]
    return counts[0] if len(counts) == 1 else None


def capacity_param(autopilot: str) -> str:
    """The autopilot's parameter holding the pack's capacity in mAh."""
    return "BAT1_CAPACITY" if autopilot == "px4" else "BATT_CAPACITY"


def capacity(config: EnergyConfig, params: Mapping[str, float], autopilot: str, rest_v: float | None = None) -> Capacity | str:
    """The pack's capacity in Wh, or why it cannot be told (naming what to set); ``rest_v``: the pack's voltage before arming."""
    if config.capacity_wh is not None:
        return Capacity(config.capacity_wh, f"energy.capacity_wh {config.capacity_wh:g} Wh")
    name = capacity_param(autopilot)
    mah = params.get(name)
    if mah is None:
        return f"{name} not read from the autopilot: set energy.capacity_wh"
    if mah <= 0:
        return f"{name} is {mah:g} (unknown): set it on the autopilot, or energy.capacity_wh"
    volts, said = config.nominal_v, "energy.nominal_v"
    if volts is None and autopilot == "px4" and params.get("BAT1_N_CELLS", 0) > 0:
        volts, said = params["BAT1_N_CELLS"] * CELL_NOMINAL_V, f"BAT1_N_CELLS {params['BAT1_N_CELLS']:g} x {CELL_NOMINAL_V} V"
    if volts is None and rest_v and (cells := cells_at_rest(rest_v)) is not None:
        volts, said = cells * CELL_NOMINAL_V, f"{cells} cells: {rest_v:.1f} V at rest; energy.nominal_v if not Li-ion/LiPo"
    if volts is None:
        seen = f" ({rest_v:.1f} V at rest: no one cell count)" if rest_v else ""
        return f"{name} {mah:g} mAh, but not the pack's voltage{seen}: set energy.nominal_v (11.1 for a 3S pack) or energy.capacity_wh"
    return Capacity(mah / 1000.0 * volts, f"{name} {mah:g} mAh x {volts:g} V ({said})")


def drawn_wh(status: BatteryStatus | None, battery: Battery | None) -> float | None:
    """Energy drawn since the autopilot booted, Wh; None when the monitor counts none (no current measured)."""
    if status is None:
        return None
    if status.consumed_wh is not None:
        return status.consumed_wh
    volts = status.voltage_v or (battery.voltage_v if battery is not None else None)
    if status.consumed_mah is not None and volts:
        return status.consumed_mah / 1000.0 * volts
    return None


def unknown_reading(status: BatteryStatus | None, battery: Battery | None, params: Mapping[str, float]) -> str | None:
    """Why the readings cannot be counted as energy (None: they can)."""
    if status is None:
        return "no BATTERY_STATUS from the autopilot yet"
    if remaining_pct(status, battery) is None:
        if drawn_wh(status, battery) is None:
            monitor = params.get("BATT_MONITOR")
            kind = f" (BATT_MONITOR {monitor:g}: {MONITOR_KINDS.get(int(monitor), 'see AP_BattMonitor.h')})" if monitor is not None else ""
            return f"the battery monitor counts no energy drawn{kind}: fit a current sensor (BATT_MONITOR 4) or set energy: {{check: off}}"
        return "the autopilot does not estimate the remaining charge (battery_remaining -1): set its battery capacity"
    return None


def judgeable(
    config: EnergyConfig,
    said: bool,
    status: BatteryStatus,
    battery: Battery | None,
    params: Mapping[str, float],
    autopilot: str,
    rest_v: float | None,
) -> Capacity | NotJudged | str:
    """The capacity when the battery can tell the mission's energy; else why: a :class:`NotJudged` when the mission did not ``said``
    the rule and the monitor measures no current (a voltage-only monitor: the energy is neither counted nor told by a capacity);
    else the refusal naming what to set (a current measured but no capacity, a mission's ``energy:`` the battery cannot serve)."""
    pack = capacity(config, params, autopilot, rest_v)
    unknown = unknown_reading(status, battery, params)
    measured = status.current_a is not None and status.current_a >= 0.0
    if not said and not measured and (unknown is not None or isinstance(pack, str)):
        return NotJudged(unknown or f"the battery monitor measures no current, and {pack}")
    if isinstance(pack, str):
        return pack + ("; or energy: {check: off}" if not said else "")
    return unknown if unknown is not None else pack


#: What :func:`judgeable` judges, in the order of its arguments.
JudgeInputs = tuple[EnergyConfig, bool, BatteryStatus, Battery | None, Mapping[str, float], str, float | None]


class JudgedCapacity:
    """:func:`judgeable`, judged again only when one of its inputs is another.

    The battery reports come at ~1 Hz and the energy watch asks every tick: between two reports the same
    objects (the reader writes a new one for each message, and a new parameters dict for each
    PARAM_VALUE) give the same verdict, whose capacity source is a formatted string.
    """

    def __init__(self) -> None:
        self._inputs: tuple[object, ...] = ()
        self._verdict: Capacity | NotJudged | str = ""

    def get(self, *inputs: *JudgeInputs) -> Capacity | NotJudged | str:
        """:func:`judgeable` of ``inputs`` (its arguments, in its order)."""
        if inputs != self._inputs:  # item by item: the same object, else an equal one
            self._inputs = inputs
            self._verdict = judgeable(*inputs)
        return self._verdict


def counts_current(status: BatteryStatus) -> bool:
    """The monitor measures the current (its counters move): PX4's SIH has no current sensor (BatterySimulator.cpp: ibatt -1,
    reported as current_battery -100 with current_consumed stuck at 0); its drawn energy is read from battery_remaining."""
    return status.current_a is not None and status.current_a >= 0.0 and drawn_wh(status, None) is not None


def remaining_pct(status: BatteryStatus | None, battery: Battery | None) -> int | None:
    """battery_remaining, BATTERY_STATUS's else SYS_STATUS's."""
    if status is not None and status.remaining_pct is not None:
        return status.remaining_pct
    return battery.remaining_pct if battery is not None else None
