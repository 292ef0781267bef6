"""Immutable values the IO readers put on the blackboard.

Each is replaced whole when a new message arrives, so a behaviour never sees half an update,
and a snapshot of the blackboard shows exactly which facts changed.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from enum import IntFlag, StrEnum

import executive


@dataclass(frozen=True, slots=True)
class GlobalPosition:
    """Where the vehicle is (GLOBAL_POSITION_INT)."""

    lat: float  # degrees
    lon: float  # degrees
    alt_rel_m: float  # above home; meaningless on a surface vehicle before EKF origin is set
    vn_m_s: float
    ve_m_s: float
    vd_m_s: float
    heading_deg: float | None  # None when the autopilot does not know it
    time: float  # executive clock time of reception
    boot_s: float | None = None  # when the autopilot measured it (its boot clock): exact intervals, whatever the link's jitter
    #: Its altitude above mean sea level (GLOBAL_POSITION_INT alt): the estimate itself, where ``alt_rel_m`` also moves with
    #: the autopilot's home (PX4 corrects home's altitude in the air, commander/HomePosition.cpp); None: not reported. Out of
    #: the repr, the blackboard's text in the snapshot recordings: those of every mission stay as they were.
    alt_msl_m: float | None = field(default=None, repr=False)

    @property
    def ground_speed_m_s(self) -> float:
        return float((self.vn_m_s**2 + self.ve_m_s**2) ** 0.5)


@dataclass(frozen=True, slots=True)
class Attitude:
    """ATTITUDE, in degrees; yaw in [0, 360)."""

    roll_deg: float
    pitch_deg: float
    yaw_deg: float
    yaw_rate_deg_s: float
    time: float
    boot_s: float | None = None  # when the autopilot measured it (its boot clock)


class EkfFlags(IntFlag):
    """EKF_STATUS_REPORT.flags."""

    ATTITUDE = 1
    VELOCITY_HORIZ = 2
    VELOCITY_VERT = 4
    POS_HORIZ_REL = 8
    POS_HORIZ_ABS = 16
    POS_VERT_ABS = 32
    POS_VERT_AGL = 64
    CONST_POS_MODE = 128
    PRED_POS_HORIZ_REL = 256
    PRED_POS_HORIZ_ABS = 512
    UNINITIALIZED = 1024
    GPS_GLITCHING = 32768


_HORIZONTAL_POSITION = int(EkfFlags.POS_HORIZ_ABS | EkfFlags.POS_HORIZ_REL)
_CONST_POS_MODE, _PRED_POS_HORIZ_REL = int(EkfFlags.CONST_POS_MODE), int(EkfFlags.PRED_POS_HORIZ_REL)


@dataclass(frozen=True, slots=True)
class EkfStatus:
    """EKF_STATUS_REPORT: flags and normalised variances (1.0 = at the failsafe threshold scale)."""

    flags: EkfFlags
    velocity_variance: float
    pos_horiz_variance: float
    pos_vert_variance: float
    compass_variance: float
    terrain_alt_variance: float
    time: float
    #: PX4's ESTIMATOR_STATUS: CONST_POS_MODE is also set at rest on the ground (ekf2/EKF/ekf_helper.cpp get_ekf_soln_status:
    #: ``fake_pos || valid_fake_pos || vehicle_at_rest``), so with an aiding source fused it is no loss of position.
    const_pos_at_rest: bool = False

    def position_ok(self) -> bool:
        """A horizontal position estimate, not a constant-position one.

        ArduPilot (ArduRover's own test): POS_HORIZ_ABS or _REL, and not CONST_POS_MODE. PX4: the same, except that
        CONST_POS_MODE with PRED_POS_HORIZ_REL (PX4's isHorizontalAidingActive: GNSS, optical flow or vision fused;
        fake_pos_control.cpp fakes a position only while none is) is the vehicle at rest, position known: 0x3ff on
        the ground before take-off.
        """
        flags = int(self.flags)  # in ints: an IntFlag's ``&`` and ``|`` make a new flag each time, and the guards ask each tick
        has_position = bool(flags & _HORIZONTAL_POSITION)
        if not flags & _CONST_POS_MODE:
            return has_position
        return has_position and self.const_pos_at_rest and bool(flags & _PRED_POS_HORIZ_REL)

    def variances_ok(self, threshold: float = 0.8) -> bool:
        """ArduPilot's EKF failsafe trips when two of compass/velocity/position variances exceed FS_EKF_THRESH."""
        over = sum(v >= threshold for v in (self.compass_variance, self.velocity_variance, self.pos_horiz_variance))
        return over < 2


@dataclass(frozen=True, slots=True)
class Battery:
    """SYS_STATUS battery fields; ``None`` where the autopilot reports 'unknown'."""

    voltage_v: float | None
    current_a: float | None
    remaining_pct: int | None
    time: float


@dataclass(frozen=True, slots=True)
class BatteryStatus:
    """BATTERY_STATUS (MAVLink common.xml, id 147) of the main battery (``id`` 0); ``None`` where the autopilot says 'unknown'.

    ``consumed_mah``: current_consumed, mAh (-1: not estimated); ``consumed_wh``: energy_consumed, hJ / 36
    (-1: not estimated; ArduPilot sends consumed_wh * 36, ``GCS_Common.cpp`` send_battery_status; PX4 always -1,
    ``src/modules/mavlink/streams/BATTERY_STATUS.hpp``); ``remaining_pct``: battery_remaining (-1: not estimated);
    ``time_remaining_s``: time_remaining (0: not estimated); ``voltage_v``: the cells summed (UINT16_MAX: no cell;
    a monitor without cell voltages puts the pack's voltage in cell 0, both firmwares); ``current_a``: current_battery
    (-1: not measured); ``charge_state``: MAV_BATTERY_CHARGE_STATE (0: undefined).
    """

    consumed_mah: float | None
    consumed_wh: float | None
    remaining_pct: int | None
    time_remaining_s: int | None
    voltage_v: float | None
    current_a: float | None
    charge_state: int
    time: float


@dataclass(frozen=True, slots=True)
class Rangefinder:
    """The downward rangefinder (DISTANCE_SENSOR, orientation PITCH_270): its reading judged against its own range.

    ``status``: ``good`` within [min_m, max_m]; ``too_far`` beyond max_m (the seabed or ground is
    farther than it can measure: at least max_m away); ``too_close`` under min_m; ``invalid``
    (signal quality 1). Only a ``good`` reading is a height above the bottom.
    """

    distance_m: float
    min_m: float
    max_m: float
    status: str
    time: float

    @property
    def good(self) -> bool:
        return self.status == "good"


@dataclass(frozen=True, slots=True)
class HomePosition:
    """HOME_POSITION: where RTL goes and relative altitudes start."""

    lat: float
    lon: float
    alt_m: float  # above mean sea level
    time: float


@dataclass(frozen=True, slots=True)
class PositionTarget:
    """POSITION_TARGET_GLOBAL_INT: the point the autopilot's mode steers to (ArduPilot in GUIDED, AUTO...; PX4 its navigator's setpoint)."""

    lat: float
    lon: float
    alt_m: float  # in the report's frame: above sea level (PX4, ArduRover's MAV_FRAME_GLOBAL)
    time: float  # executive clock time of reception


@dataclass(frozen=True, slots=True)
class TargetAsk:
    """A point the executive asked the autopilot to steer to in ``mode`` (as the heartbeat shows it), and when; no ``lat``/``lon``
    for a local-frame setpoint."""

    lat: float | None
    lon: float | None
    mode: str | None  # the mode that follows it: the one asked last (GUIDED, OFFBOARD; PX4's AUTO.LOITER for a DO_REPOSITION)
    time: float


@dataclass(frozen=True, slots=True)
class GpsFix:
    """GPS_RAW_INT: fix type (GPS_FIX_TYPE: 3 = 3D fix), satellites, horizontal dilution."""

    fix_type: int
    satellites: int | None
    hdop: float | None
    time: float

    @property
    def has_3d_fix(self) -> bool:
        return self.fix_type >= 3


class SwitchPosition(StrEnum):
    """Where an RC switch is."""

    UP = "UP"
    MIDDLE = "MIDDLE"
    DOWN = "DOWN"


@dataclass(frozen=True, slots=True)
class RcSwitches:
    """The operator's switches (AgileX/FlySky layout: SWA..SWD, knob VRA), from RC channels or CAN 0x241."""

    swa: SwitchPosition | None
    swb: SwitchPosition | None
    swc: SwitchPosition | None
    swd: SwitchPosition | None
    knob: int | None  # VRA, [-100, 100]
    time: float


@dataclass(frozen=True, slots=True)
class SampleRead:
    """One sensor reading taken by the sampler."""

    sensor: str
    value: float
    unit: str
    time: float


class SamplerState(StrEnum):
    IDLE = "IDLE"
    SAMPLING = "SAMPLING"
    DONE = "DONE"
    PARTIAL = "PARTIAL"  # ended with readings, but not of every sensor named (sampling.require: all)
    FAILED = "FAILED"  # includes cancelled


@dataclass(frozen=True, slots=True)
class SamplerStatus:
    """What the sampler is doing for which request, and what it has read so far."""

    ticket: int
    state: SamplerState
    reads: tuple[SampleRead, ...]
    reason: str
    time: float
    instrument: str = ""  # which instrument reads ("simulated", "serial:/dev/ttyUSB0")
    missing: tuple[str, ...] = ()  # sensors named that gave no reading in the sample (once it ended)


@dataclass(frozen=True, slots=True, repr=False)
class SampleRecord:
    """A finished sample, as recorded: where, when, every read, and the sensors named that gave none.

    ``partial``: it lacks a sensor and the mission requires them all (``sampling.require: all``):
    recorded, but its sample point is not done (:meth:`complete` is False). Named ``Sample`` until 0.2
    (the Sample action is :class:`executive.behaviours.sampling.Sample`).
    """

    leg_index: int
    lat: float
    lon: float
    reads: tuple[SampleRead, ...]
    started: float
    finished: float
    instrument: str = ""  # which instrument took it ("" in journals from before instruments were recorded)
    missing: tuple[str, ...] = ()  # sensors the mission named that gave no reading
    partial: bool = False

    @property
    def complete(self) -> bool:
        """Its sample point is done."""
        return not self.partial

    def __repr__(self) -> str:
        """As a dataclass's, under the name the recordings show it by since 0.1 (``/mission/samples`` in snapshot and MCAP files)."""
        return f"Sample({', '.join(f'{f.name}={getattr(self, f.name)!r}' for f in fields(self))})"


class CommandState(StrEnum):
    """Where a command stands."""

    QUEUED = "QUEUED"
    SENT = "SENT"
    IN_PROGRESS = "IN_PROGRESS"  # MAV_RESULT_IN_PROGRESS: the autopilot is working on it
    RETRYING = "RETRYING"  # refused for now (its result says why): asked again, per the request's RefusalRetry
    ACCEPTED = "ACCEPTED"
    REJECTED = "REJECTED"  # any other MAV_RESULT
    TIMED_OUT = "TIMED_OUT"  # no ack after every retry
    CANCELLED = "CANCELLED"  # the requester no longer wants it: no more retries, a late ack is ignored

    @property
    def done(self) -> bool:
        return self in (CommandState.ACCEPTED, CommandState.REJECTED, CommandState.TIMED_OUT, CommandState.CANCELLED)


class Outcome(StrEnum):
    """What an acked command asks of the autopilot; the latest of each and its ack are on ``/command/<value>``.

    The autopilot port's requests name the outcome, never the firmware's command: the MAVLink back end maps
    each to its MAV_CMD (``executive.io.mavlink.commander.COMMAND_OUTCOMES``).
    """

    MODE = "mode"  # a flight mode (hold, the route's mode, a named mode, a landing mode)
    ARMING = "arming"  # arm or disarm
    MESSAGE_RATE = "message_rate"  # how often the autopilot sends a message (the telemetry streams)
    HOME = "home"  # home set here or at a point
    SPEED = "speed"  # the cruise speed of the legs
    REPOSITION = "reposition"  # go to a point, acked (the autopilot switches to the mode that does it)
    TRANSITION = "transition"  # a VTOL to fixed-wing or multicopter flight
    TAKE_OFF = "take_off"
    LAND = "land"  # land (a sub: surface) where the vehicle is
    VTOL_TAKE_OFF = "vtol_take_off"  # a VTOL's climb as a multicopter
    VTOL_LAND = "vtol_land"
    RETURN_HOME = "return_home"
    START_ROUTE = "start_route"  # fly the route the autopilot holds
    ROUTE_ITEM = "route_item"  # the route's item the autopilot heads for
    MESSAGE = "message"  # one message asked for once


@dataclass(frozen=True, slots=True)
class CommandStatus:
    """The latest command of one outcome (:class:`Outcome`) and what became of it: the MAV_CMD that carried it, its ack."""

    ticket: int  # unique per request; a behaviour keeps the ticket it was given
    command: int  # MAV_CMD id
    name: str  # MAV_CMD name without the prefix, e.g. DO_SET_MODE
    state: CommandState
    result: int | None  # MAV_RESULT of the last ack
    attempts: int
    time: float
    result_name: str = "no ack"  # the result without the MAV_RESULT_ prefix, e.g. TEMPORARILY_REJECTED


#: MISSION_CURRENT.mission_state: the mission is finished (MAVLink's MISSION_STATE_COMPLETE; PX4 sends it, then loiters).
MISSION_STATE_COMPLETE = 5


class TransferOperation(StrEnum):
    """What a mission transfer does."""

    UPLOAD = "UPLOAD"
    DOWNLOAD = "DOWNLOAD"
    CLEAR = "CLEAR"
    SET_CURRENT = "SET_CURRENT"


class TransferState(StrEnum):
    """Where a mission transfer stands."""

    IN_PROGRESS = "IN_PROGRESS"
    DONE = "DONE"
    FAILED = "FAILED"


@dataclass(frozen=True, slots=True)
class MissionTransferStatus:
    """The latest mission transfer and what became of it (``/link/mission_transfer``)."""

    ticket: int  # unique per request; a behaviour keeps the ticket it was given
    operation: TransferOperation
    state: TransferState
    progress: int  # items through so far, home included
    total: int  # items to go through, home included; 0 until known
    reason: str  # why it failed; "" otherwise
    result: int | None  # MAV_MISSION_RESULT of the MISSION_ACK that decided it, if one did
    retries: int  # messages resent after a timeout, over the whole transfer
    verifying: bool  # an upload is reading the mission back
    time: float
    mission_type: int = 0  # MAV_MISSION_TYPE: 0 the flight plan, 1 the fence, 2 the rally points


@dataclass(frozen=True, slots=True)
class FenceStatus:
    """FENCE_STATUS: the autopilot's own fence breached or not (ArduPilot sends it while its fence is enabled, and at once on a breach)."""

    breached: bool
    count: int  # breaches since boot
    breach_type: int  # FENCE_BREACH: 3 boundary (ArduPilot's circle and polygon)
    time: float  # when it arrived (clock time)


@dataclass(frozen=True, slots=True)
class MissionCurrent:
    """MISSION_CURRENT: the item the vehicle is on and the mission's state."""

    seq: int
    total: int  # items after home; 0 if the firmware does not say
    state: int  # MISSION_STATE; 0 (unknown) if the firmware does not say
    in_mission_mode: bool  # the vehicle is in its mission mode (AUTO)
    time: float


@dataclass(frozen=True, slots=True)
class MissionItemReached:
    """MISSION_ITEM_REACHED: the last item the vehicle reported reached, and the highest since the vehicle's mission last changed.

    ``highest`` is latched by the reader: two reports drained in one tick (item 3, then a GUIDED
    arrival's item 0) lose nothing.
    """

    seq: int
    time: float
    highest: int = -1


def __getattr__(name: str) -> object:  # old names (0.2), for one release: Sample is SampleRecord
    return executive.moved_attribute(__name__, name)
