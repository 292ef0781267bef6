"""Mission Planner's fence and rally files, read into an import's :class:`~executive.mission.formats.plan_items.FileContents`.

Three kinds, told apart by content:

- ``QGC WPL 110`` with fence or rally items (Mission Planner's Fence and Rally plans saved to a file):
  MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION / _EXCLUSION runs (param1 the corner count),
  MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION / _EXCLUSION (param1 the radius), MAV_CMD_NAV_RALLY_POINT: read by
  :func:`~executive.mission.formats.plan_reading.read_waypoints` (a route file may carry them too);
- the older fence points file (``.fen``; ``.poly`` for a polygon alone): a ``latitude longitude`` pair a
  line, ``#`` comments, as pymavlink's ``MAVFenceLoader`` reads it; in a ``.fen`` the first point is
  the fence's return point (not imported: a return goes to a rally point or home) and the last repeats
  the first corner; it holds one inclusion polygon;
- the rally file (``.rally``): ``RALLY latitude longitude altitude break_altitude land_direction flags``
  lines, as pymavlink's ``MAVRallyLoader`` reads them (the last three are a plane's landing: not imported).
"""

from __future__ import annotations

import math
import re

from executive.mission.formats.plan_items import At, FencePolygon, FileContents
from executive.mission.formats.plan_reading import read_waypoints

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_POINT = re.compile(rf"^\s*({_NUMBER})\s+({_NUMBER})\s*$")


def read_zone_file(text: str, filename: str) -> FileContents:
    """A Mission Planner fence or rally file (any of the three kinds), its zones and rally points located in it."""
    text = text.removeprefix("\ufeff")
    if text.startswith("QGC WPL"):
        src = read_waypoints(text, filename)
        for item in src.items:  # a zone file's route items would be a second route
            src.warn(item.at, "not imported: a fence or rally file's route item (the route comes from the imported file)")
        src.items.clear()
        return src
    src = FileContents(filename, At(1, 1, "(file)"))
    lines = [(n, line) for n, line in enumerate(text.splitlines(), start=1) if line.strip() and not line.lstrip().startswith("#")]
    if lines and lines[0][1].split()[0].upper() == "RALLY":
        _rally_lines(src, lines)
    else:
        _fence_points(src, lines, return_point=filename.lower().endswith(".fen"))
    return src


def _rally_lines(src: FileContents, lines: list[tuple[int, str]]) -> None:
    for n, line in lines:
        fields = line.split()
        name = f"rally[{len(src.rally)}]"
        if len(fields) != 7 or fields[0].upper() != "RALLY":
            src.error(At(n, 1, name), f"expected RALLY latitude longitude altitude break_altitude land_direction flags, got {line.strip()[:60]!r}")
            continue
        try:
            lat, lon, alt, break_alt, land_dir, flags = map(float, fields[1:])
        except ValueError:
            src.error(At(n, 1, name), f"expected numbers after RALLY, got {line.strip()[:60]!r}")
            continue
        if not all(map(math.isfinite, (lat, lon, alt))):
            src.error(At(n, 1, name), "expected finite numbers")
            continue
        if break_alt or land_dir or flags:
            src.warn(At(n, 1, name), "break altitude, landing direction and flags not imported (a plane's landing at the rally point)")
        src.rally.append((lat, lon, alt, At(n, 1, name)))


def _fence_points(src: FileContents, lines: list[tuple[int, str]], *, return_point: bool) -> None:
    points: list[tuple[float, float, At]] = []
    for n, line in lines:
        found = _POINT.match(line)
        if found is None:
            src.error(At(n, 1, f"point[{len(points)}]"), f"expected 'latitude longitude', got {line.strip()[:60]!r}")
            continue
        points.append((float(found.group(1)), float(found.group(2)), At(n, 1, f"point[{len(points)}]")))
    if return_point and points:
        src.warn(points[0][2], "the fence's return point is not imported: a return goes to a rally point or home")
        points = points[1:]
    if points and points[-1][:2] == points[0][:2]:
        points = points[:-1]  # the closing point
    if len(points) < 3:
        src.error(src.start, f"a fence polygon needs 3 corners or more, the file has {len(points)}")
        return
    src.polygons.append(FencePolygon(True, points, points[0][2]))
