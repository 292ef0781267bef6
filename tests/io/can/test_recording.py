"""``--can-log``: the bus recorded in candump's format, the executive's own frames marked sent (T), the others received (R)."""

from __future__ import annotations

import can

from executive.io.can.recording import RecordingBus


def test_frames_sent_are_logged_as_sent_and_frames_received_as_received(tmp_path) -> None:
    path = tmp_path / "bus.log"
    base = can.Bus(interface="virtual", channel="test_recording", receive_own_messages=False)
    recording = RecordingBus(can.Bus(interface="virtual", channel="test_recording", receive_own_messages=False), str(path))
    try:
        recording.send(can.Message(arbitration_id=0x111, data=bytes(8), is_extended_id=False))  # the executive's motion command
        base.send(can.Message(arbitration_id=0x241, data=bytes(8), is_extended_id=False))  # the base's RC frame
        assert recording.recv(1.0) is not None
    finally:
        recording.shutdown()
        base.shutdown()
    lines = path.read_text().splitlines()
    assert [(line.split()[2][:3], line.split()[-1]) for line in lines] == [("111", "T"), ("241", "R")]
