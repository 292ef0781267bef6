"""CAN (python-can): the AgileX base's frames read onto the blackboard, and the autopilot's outputs driven onto the base.

- :func:`open_can` opens ``IFACE:CHANNEL`` (``socketcan:can0``, ``slcan:/dev/ttyACM0@115200``, ``virtual:test``...).
- :class:`CanReader` drains the bus each tick: ``/base/*`` and (``rc.source: can``) the CAN side of ``/rc``.
- :class:`DriveBridge` sends 0x421 + 0x111 at 50 Hz: the autopilot's skid-steer outputs, or zero motion.
- :mod:`executive.io.can.agilex` decodes and encodes the protocol v2 frames.
"""

from executive.io.can.bus import CanOpenError, CanSpecError, open_can
from executive.io.can.drive import DriveBridge, DriveConfig
from executive.io.can.reader import CanReader

__all__ = ["CanOpenError", "CanReader", "CanSpecError", "DriveBridge", "DriveConfig", "open_can"]
