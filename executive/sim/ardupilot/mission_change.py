"""ArduPilot's mission change detector as the real firmware behaves: a write to the mission in AUTO restarts the current command.

ModeAuto::update (Rover/mode_auto.cpp) asks ``mis_change_detector.check_for_mission_change()`` at every
loop (400 Hz, before AP_Mission::update), and on True restarts the waypoint it drives
(AP_Mission::restart_current_nav_cmd: AR_WPNav plans the leg again from the stopping point,
"Auto mission changed, restarted command"). AP_Mission_ChangeDetector::check_for_mission_change
(libraries/AP_Mission/AP_Mission_ChangeDetector.cpp) looks only when the mission's last change time or
its current navigation index moved since the last check, compares the current and next two navigation
commands (``mis_change_detect_cmd_max = 3``) with the copy it kept, and returns
``cmds_changed && !curr_cmd_idx_changed``: a write noticed in the same check as a new current command
is taken in silently.

By its source, a write beyond those three commands would change nothing; the real ArduRover 4.7-dev
SITL build (2598e9d4b2e7) restarted at every write wherever it lay: an identical rewrite of item 8 and
an append of item 9 while it drove to item 1 each restarted it
(tests/data/ardurover/mission-writes-in-auto-rover.tlog). Its comparison (Mission_Command's
``operator==``, a memcmp that "relies on all bytes in the structure") runs over buffers left
uninitialised (the stack array ``cmd[]`` and the member ``mis_change_detect``: padding and unused union
bytes), reported upstream as ArduPilot issue #31495 (Valgrind), a fix proposed in pull request #33861.
So here any write counts as a change; what spares a write is the current command changing in the same
check.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class MissionChangeDetector:
    """AP_Mission_ChangeDetector, as the real build behaves (see the module): :meth:`check` once per AUTO update."""

    changes: int = 0  # the mission's write count at the last check (AP_Mission::last_change_time_ms)
    current: int | None = None  # the current command at the last check

    def start(self, changes: int, current: int | None) -> None:
        """The mission (re)starts in AUTO: what it holds now is the reference (ModeAuto::update's IGNORE_RETURN check)."""
        self.changes, self.current = changes, current

    def check(self, changes: int, current: int | None) -> bool:
        """True when the mission was written since the last check and its current command did not change meanwhile."""
        written, moved = changes != self.changes, current != self.current
        self.changes, self.current = changes, current
        return written and not moved
