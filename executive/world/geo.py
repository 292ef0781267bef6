"""Distances and bearings on the WGS84 ellipsoid (geographiclib).

Geodesics (the shortest paths) for distance, bearing and destination; rhumb lines (a constant
compass bearing) for moving points "toward a bearing"; the latitude/longitude bounding box of a set
of points. Nothing here is a flat-earth approximation.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

from geographiclib.geodesic import Geodesic

_WGS84 = Geodesic.WGS84
_INVERSE = Geodesic.DISTANCE | Geodesic.AZIMUTH
_E2 = _WGS84.f * (2.0 - _WGS84.f)  # first eccentricity squared


@functools.lru_cache(maxsize=256)
def distance_bearing(lat1: float, lon1: float, lat2: float, lon2: float) -> tuple[float, float]:
    """Metres from point 1 to point 2 and the initial bearing there, degrees [0, 360).

    Remembered for the last few pairs: a tick asks again for the same position (the position comes
    at 5 Hz, ticks at 10 Hz), and different parts ask for the same pair (the energy watch for the
    distance to the leg's point, the leg's behaviour for its distance and bearing, the status line);
    a geodesic costs ~30 µs.
    """
    g = _WGS84.Inverse(lat1, lon1, lat2, lon2, _INVERSE)
    return g["s12"], g["azi1"] % 360.0


def distance(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Metres between two points: :func:`distance_bearing`'s, remembered with it (geographiclib's ``s12`` is the same
    number whether or not the azimuths are asked for: ``Geodesic._GenInverse`` computes them apart)."""
    return distance_bearing(lat1, lon1, lat2, lon2)[0]


def destination(lat: float, lon: float, bearing_deg: float, distance_m: float) -> tuple[float, float]:
    """The point ``distance_m`` from (lat, lon) toward ``bearing_deg``."""
    g = _WGS84.Direct(lat, lon, bearing_deg, distance_m)
    return g["lat2"], g["lon2"]


def normalize_lon(lon: float) -> float:
    """A longitude in [-180, 180)."""
    return (lon + 180.0) % 360.0 - 180.0


def bounding_box_centre(points: Sequence[tuple[float, float]]) -> tuple[float, float]:
    """The centre of the latitude/longitude box around ``points`` (lat, lon); a box across the antimeridian is handled.

    Longitudes are taken within 180° of the first point's, so the points must span less than half the globe.
    """
    if not points:
        raise ValueError("no points: no bounding box")
    lon0 = points[0][1]
    lats = [lat for lat, _ in points]
    lons = [lon0 + normalize_lon(lon - lon0) for _, lon in points]
    return (min(lats) + max(lats)) / 2.0, normalize_lon((min(lons) + max(lons)) / 2.0)


def rhumb_destination(lat: float, lon: float, bearing_deg: float, distance_m: float) -> tuple[float, float]:
    """The point ``distance_m`` from (lat, lon) along the rhumb line (constant compass bearing) toward ``bearing_deg``.

    Exact on the ellipsoid: the meridian arc (``distance_m * cos(bearing)``) is a geodesic, solved by
    geographiclib; the longitude follows from the isometric latitude. Going back the same distance
    toward ``bearing_deg + 180`` (or a negative distance) returns to the start. Raises ValueError for
    a start at a pole or a rhumb line that would pass one.
    """
    if abs(lat) >= 90.0:
        raise ValueError(f"latitude {lat:g}: no compass bearing at a pole")
    alpha = math.radians(bearing_deg)
    north_m, east_m = distance_m * math.cos(alpha), distance_m * math.sin(alpha)
    meridian = _WGS84.Direct(lat, 0.0, 0.0, north_m, Geodesic.LATITUDE | Geodesic.AZIMUTH)
    lat2 = meridian["lat2"]
    if abs(meridian["azi2"]) > 90.0 or abs(lat2) >= 90.0:  # the meridian arc went over the pole
        raise ValueError(f"{distance_m:g} m toward {bearing_deg:g}° from latitude {lat:g} passes a pole")
    phi1, phi2 = math.radians(lat), math.radians(lat2)
    return lat2, normalize_lon(lon + math.degrees(east_m * _dpsi_per_meridian_m(phi1, phi2)))


# 5-point Gauss-Legendre nodes and weights on [-1, 1]
_GAUSS = ((0.0, 0.5688888888888889), (0.5384693101056831, 0.4786286704993665), (-0.5384693101056831, 0.4786286704993665),
          (0.9061798459386640, 0.2369268850561891), (-0.9061798459386640, 0.2369268850561891))  # fmt: skip


def _dpsi_per_meridian_m(phi1: float, phi2: float) -> float:
    """Isometric latitude gained per metre of meridian between two latitudes (radians): d(psi) / d(meridian distance).

    Both integrals by Gauss-Legendre quadrature over [phi1, phi2], so the ratio stays exact as the
    interval shrinks (no difference of nearly equal numbers) and is symmetric in its arguments;
    farther apart, the closed form.
    """
    if abs(phi2 - phi1) > 1e-2:
        return (_isometric_latitude(phi2) - _isometric_latitude(phi1)) / (_meridian_arc(phi2) - _meridian_arc(phi1))
    mid, half = (phi1 + phi2) / 2.0, (phi2 - phi1) / 2.0
    dpsi = dmu = 0.0
    for x, w in _GAUSS:
        w2 = 1.0 - _E2 * math.sin(mid + half * x) ** 2
        dpsi += w * (1.0 - _E2) / (w2 * math.cos(mid + half * x))  # d(psi)/d(phi) = rho / (N cos(phi))
        dmu += w * _WGS84.a * (1.0 - _E2) / w2**1.5  # d(mu)/d(phi) = rho, the meridian's radius of curvature
    return dpsi / dmu


def _meridian_arc(phi: float) -> float:
    """Metres of meridian from the equator to latitude ``phi`` (radians, signed)."""
    return math.copysign(_WGS84.Inverse(0.0, 0.0, math.degrees(phi), 0.0, Geodesic.DISTANCE)["s12"], phi)


def _isometric_latitude(phi: float) -> float:
    """psi(phi) on the WGS84 ellipsoid, radians."""
    e = math.sqrt(_E2)
    return math.asinh(math.tan(phi)) - e * math.atanh(e * math.sin(phi))
