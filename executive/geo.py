"""Distances and bearings on the WGS84 ellipsoid (geographiclib)."""

from __future__ import annotations

from geographiclib.geodesic import Geodesic

_WGS84 = Geodesic.WGS84
_INVERSE = Geodesic.DISTANCE | Geodesic.AZIMUTH


def distance_bearing(lat1: float, lon1: float, lat2: float, lon2: float) -> tuple[float, float]:
    """Metres from point 1 to point 2 and the initial bearing there, degrees [0, 360)."""
    g = _WGS84.Inverse(lat1, lon1, lat2, lon2, _INVERSE)
    return g["s12"], g["azi1"] % 360.0


def distance(lat1: float, lon1: float, lat2: float, lon2: float) -> float:
    """Metres between two points."""
    return _WGS84.Inverse(lat1, lon1, lat2, lon2, Geodesic.DISTANCE)["s12"]


def destination(lat: float, lon: float, bearing_deg: float, distance_m: float) -> tuple[float, float]:
    """The point ``distance_m`` from (lat, lon) toward ``bearing_deg``."""
    g = _WGS84.Direct(lat, lon, bearing_deg, distance_m)
    return g["lat2"], g["lon2"]
