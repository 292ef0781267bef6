"""CAN decode: AgileX frames per second (``agilex.decode`` alone, and the CanReader draining a virtual bus) against a full 500 kbit/s bus."""

from __future__ import annotations

import itertools
import time
import uuid

import can

from benchmarks.common import Row
from executive.io.can.agilex import MotionState, Odometry, RcState, SystemState, decode
from executive.io.can.reader import CanReader
from executive.world import blackboard
from executive.world.clock import ManualClock
from executive.world.state import SwitchPosition

#: 8-byte standard frames a fully loaded 500 kbit/s bus carries per second (~125 bits each with stuffing).
LINE_RATE_FPS = 4000.0
MIN_MULTIPLE = 20.0


def bunker_frames(count: int) -> list[can.Message]:
    """What a Bunker base sends, in its proportions: system, motion, RC (counting), odometry, and motor frames the executive does not read."""
    up, mid, down = SwitchPosition.UP, SwitchPosition.MIDDLE, SwitchPosition.DOWN
    frames = []
    for i in itertools.islice(itertools.count(), count):
        k = i % 6
        if k == 0:
            msg = SystemState(0, 1, 264, 0, i & 0xFF).encode()
        elif k == 1:
            msg = MotionState(800 + i % 50, -100 + i % 7).encode()
        elif k == 2:
            msg = RcState(up, mid, mid, down, i % 20, -(i % 20), 0, 50, -100, i & 0xFF).encode()
        elif k == 3:
            msg = Odometry(i * 16, i * 16 + 3).encode()
        else:  # 0x251/0x252: motor driver speed and current, not read by the executive
            msg = can.Message(arbitration_id=0x251 + (k - 4), data=bytes([0x05, 0xDC, 0x00, 0x20, 0, 0, 0, 0]), is_extended_id=False)
        frames.append(msg)
    return frames


def decode_rate(frames: list[can.Message]) -> float:
    """Frames per second through ``agilex.decode``."""
    t0 = time.perf_counter()
    for msg in frames:
        decode(msg)
    return len(frames) / (time.perf_counter() - t0)


def reader_rate(frames: list[can.Message], burst: int = 100) -> float:
    """Frames per second through ``CanReader.drain`` on a python-can virtual bus, ``burst`` frames per drain (~ a tick of a busy bus)."""
    blackboard.reset()
    channel = f"bench-{uuid.uuid4().hex[:8]}"
    clock = ManualClock(100.0)
    with can.Bus(interface="virtual", channel=channel) as rx, can.Bus(interface="virtual", channel=channel) as tx:
        reader = CanReader(rx, clock, rc=True)
        elapsed = 0.0
        for start in range(0, len(frames), burst):
            for msg in frames[start : start + burst]:
                tx.send(msg)
            clock.advance(0.01)
            t0 = time.perf_counter()
            reader.drain()
            elapsed += time.perf_counter() - t0
        if reader.stats.frames != len(frames):
            raise RuntimeError(f"the reader saw {reader.stats.frames} of {len(frames)} frames")
    return len(frames) / elapsed


def run(frames: int = 60_000, repeats: int = 3) -> list[Row]:
    """``agilex.decode`` and the CanReader, each the best of ``repeats``."""
    sample = bunker_frames(frames)
    decoded = max(decode_rate(sample) for _ in range(repeats))
    read = max(reader_rate(sample) for _ in range(repeats))
    target = f">= {MIN_MULTIPLE:g}x line rate"
    return [
        Row(
            "can",
            "CAN decode (agilex.decode)",
            round(decoded),
            "frames/s",
            target,
            decoded / LINE_RATE_FPS >= MIN_MULTIPLE,
            f"{decoded / LINE_RATE_FPS:.0f}x a full 500 kbit/s bus ({LINE_RATE_FPS:,.0f} frames/s)",
            {"multiple": decoded / LINE_RATE_FPS},
        ),
        Row(
            "can",
            "CAN reader (virtual bus)",
            round(read),
            "frames/s",
            target,
            read / LINE_RATE_FPS >= MIN_MULTIPLE,
            f"{read / LINE_RATE_FPS:.0f}x line rate; CanReader.drain, python-can virtual bus, 100 frames per drain",
            {"multiple": read / LINE_RATE_FPS},
        ),
    ]
