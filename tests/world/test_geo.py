"""Distances on the ellipsoid: geographiclib's own numbers, one geodesic for a pair asked again or asked both ways."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from geographiclib.geodesic import Geodesic

from executive.world import geo

PAIRS = [(52.0, 4.0, 52.001, 4.002), (-33.9, 151.2, -33.9001, 151.2003), (0.0, 179.9999, 0.0001, -179.9999), (60.0, 10.0, 61.0, 12.0)]


@pytest.fixture
def geodesics(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[tuple[float, ...]]]:
    """The geodesics solved (the points of each), from an empty memory."""
    solved: list[tuple[float, ...]] = []
    inverse = geo._WGS84.Inverse

    def counted(*args: float) -> dict[str, float]:
        solved.append(args[:4])
        return inverse(*args)

    geo.distance_bearing.cache_clear()
    monkeypatch.setattr(geo._WGS84, "Inverse", counted)
    yield solved
    geo.distance_bearing.cache_clear()


@pytest.mark.parametrize("pair", PAIRS)
def test_distance_is_geographiclibs(pair: tuple[float, float, float, float]) -> None:
    assert geo.distance(*pair) == Geodesic.WGS84.Inverse(*pair, Geodesic.DISTANCE)["s12"]
    assert geo.distance_bearing(*pair)[0] == geo.distance(*pair)


def test_a_pair_is_solved_once_whichever_asks(geodesics: list[tuple[float, ...]]) -> None:
    pair = PAIRS[0]
    geo.distance(*pair)  # the energy watch: metres to the leg's point
    metres, _ = geo.distance_bearing(*pair)  # the leg's behaviour: metres and bearing to it
    geo.distance(*pair)  # the next tick, the position unchanged
    assert geodesics == [pair] and metres == geo.distance(*pair)
    geo.distance(*PAIRS[1])
    assert geodesics == [pair, PAIRS[1]]
