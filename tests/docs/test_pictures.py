"""The manual's pictures are the program's own output, made by tests, so that none shows what the program no longer does.

- ``docs/tree-rover_square.svg`` (the trees page): ``executive show rover_square -o tree.svg``, checked here node by node
  against what ``show`` draws now; ``EXECUTIVE_DOCS_PICTURES=1`` writes it again.
- ``docs/foxglove-rover_square.svg`` (README, the live view page's Foxglove section): the shipped Foxglove layout's map and plots,
  drawn with matplotlib from the MCAP file of a lock-step rover_square run (the route, the track, each plot's series as
  the file holds them); checked label by label; ``EXECUTIVE_DOCS_PICTURES=1`` writes it again.
- ``docs/live-view.png`` (README, the live view page): the screenshot tests/observers/web/test_live_view_browser.py takes in headless
  Chromium during a real run; ``EXECUTIVE_LIVE_VIEW_PNG=docs/live-view.png`` keeps it.
"""

from __future__ import annotations

import html
import json
import math
import os
import re
import shutil
from pathlib import Path
from typing import Any

import pytest

from executive.cli import main

DOCS = Path(__file__).parents[2] / "docs"
TREE = DOCS / "tree-rover_square.svg"
FOXGLOVE = DOCS / "foxglove-rover_square.svg"
MISSIONS = Path(__file__).parents[2] / "missions"


def labels(svg: str) -> list[str]:
    """The text of the drawing, node by node in Graphviz's order (its layout's numbers vary between Graphviz versions)."""
    return [html.unescape(text) for text in re.findall(r"<text[^>]*>([^<]*)</text>", svg)]


def test_the_tree_picture_is_what_executive_show_draws_now(tmp_path):
    if not shutil.which("dot") and not os.environ.get("CI"):
        pytest.skip("no Graphviz dot (apt-get install graphviz; .ci/run does)")
    drawn = tmp_path / "tree.svg"
    assert main(["show", "rover_square", "-o", str(drawn)]) == 0
    if os.environ.get("EXECUTIVE_DOCS_PICTURES"):
        shutil.copy(drawn, TREE)
    now = labels(drawn.read_text(encoding="utf-8"))
    assert {"Mission", "Pre-flight", "For each leg"} <= set(now)
    assert labels(TREE.read_text(encoding="utf-8")) == now, "docs/tree-rover_square.svg is out of date: EXECUTIVE_DOCS_PICTURES=1 makes it again"


def series(path: Path, topics: set[str]) -> dict[str, list[tuple[float, dict[str, Any]]]]:
    """Each topic's (log time in s, message), as the `mcap` library reads the file."""
    from mcap.reader import make_reader

    found: dict[str, list[tuple[float, dict[str, Any]]]] = {topic: [] for topic in topics}
    with path.open("rb") as f:
        for _, channel, message in make_reader(f).iter_messages(topics=sorted(topics)):
            found[channel.topic].append((message.log_time / 1e9, json.loads(message.data)))
    return found


def draw_layout(path: Path, out: Path) -> dict[str, Any]:
    """The shipped layout's map (route and track) and plots drawn from the MCAP file at ``path`` into ``out`` (SVG); what was drawn."""
    import matplotlib
    import matplotlib.ticker

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from executive.observers.foxglove.layout import PLOTS

    plotted = [(title, [(p.partition(".")[0], p.partition(".")[2]) for p in paths]) for title, paths in PLOTS]
    data = series(path, {"/mission/route", "/vehicle/location"} | {topic for _, fields in plotted for topic, _ in fields})
    route = next(f for f in json.loads(data["/mission/route"][0][1]["geojson"])["features"] if f["geometry"]["type"] == "LineString")
    track = [(m["longitude"], m["latitude"]) for _, m in data["/vehicle/location"]]
    plt.rcParams.update({"svg.fonttype": "none", "svg.hashsalt": "executive", "font.size": 8})
    figure = plt.figure(figsize=(11, 6.5))
    grid = figure.add_gridspec(len(plotted), 2, width_ratios=(1, 1.3))
    map_axes = figure.add_subplot(grid[:, 0])
    map_axes.plot(*zip(*route["geometry"]["coordinates"], strict=True), "o-", color="#1971c2", label="/mission/route")
    map_axes.plot(*zip(*track, strict=True), color="#e8590c", linewidth=1, label="/vehicle/location")
    map_axes.set_aspect(1 / math.cos(math.radians(track[0][1])))
    map_axes.set(title="map: route and track", xlabel="longitude", ylabel="latitude")
    map_axes.ticklabel_format(useOffset=False)
    map_axes.xaxis.set_major_locator(matplotlib.ticker.MaxNLocator(3))
    map_axes.legend(loc="best")
    drawn: dict[str, Any] = {"route": route["geometry"]["coordinates"], "track": track, "plots": {}}
    for row, (title, fields) in enumerate(plotted):
        axes = figure.add_subplot(grid[row, 1])
        for topic, field in fields:
            points = [(t, m[field]) for t, m in data[topic] if m.get(field) is not None]
            drawn["plots"][f"{topic}.{field}"] = points
            if points:
                axes.plot(*zip(*points, strict=True), linewidth=1, label=f"{topic}.{field}")
        axes.set_title(title, loc="left")
        axes.legend(loc="upper right", fontsize=6)
        if row < len(plotted) - 1:
            axes.tick_params(labelbottom=False)
    axes.set_xlabel("vehicle time (s)")
    figure.suptitle("executive foxglove-layout, drawn from run --snapshots run.mcap (rover_square, lock-step)")
    figure.tight_layout()
    figure.savefig(out, format="svg", metadata={"Date": None, "Creator": None})
    plt.close(figure)
    return drawn


@pytest.mark.xdist_group("mcap_square")
def test_the_foxglove_picture_is_the_layout_drawn_from_a_recorded_run(tmp_path, rover_square_mcap):
    """The run: rover_square to its end, lock-step, recorded as ``run --snapshots run.mcap`` records it (conftest's, shared with
    tests/observers/test_mcap_recording.py)."""
    pytest.importorskip("matplotlib", reason="matplotlib is in the [test] extra")
    drawn = draw_layout(rover_square_mcap[0], tmp_path / "foxglove.svg")
    if os.environ.get("EXECUTIVE_DOCS_PICTURES"):
        shutil.copy(tmp_path / "foxglove.svg", FOXGLOVE)
    last_lon, last_lat = drawn["route"][-1]
    assert math.dist(drawn["track"][-1], (last_lon, last_lat)) * 111_000 < 5  # the track ends at the last waypoint (within ~5 m)
    assert all(drawn["plots"].values()), "a plotted field the file does not hold"
    assert drawn["plots"]["/mission/state.leg_index"][-1][1] == 4 and max(s for _, s in drawn["plots"]["/mavlink/in/VFR_HUD.groundspeed"]) > 1
    distances = [d for _, d in drawn["plots"]["/mavlink/in/NAV_CONTROLLER_OUTPUT.wp_dist"]]
    assert max(distances) >= 30 and min(distances) < 5  # a 30 m leg: from its start to its waypoint
    now = labels((tmp_path / "foxglove.svg").read_text(encoding="utf-8"))
    assert {"map: route and track", "distance to the target (m)", "/mission/route"} <= set(now)
    assert labels(FOXGLOVE.read_text(encoding="utf-8")) == now, f"{FOXGLOVE.name} is out of date: EXECUTIVE_DOCS_PICTURES=1 makes it again"


def test_the_pages_show_the_pictures_the_tests_make():
    assert "](tree-rover_square.svg)" in (DOCS / "trees.md").read_text(encoding="utf-8")
    assert "](foxglove-rover_square.svg)" in (DOCS / "live-view.md").read_text(encoding="utf-8")
    assert "](live-view.png)" in (DOCS / "live-view.md").read_text(encoding="utf-8")
    assert "](docs/live-view.png)" in (DOCS.parent / "README.md").read_text(encoding="utf-8")
    assert "](docs/foxglove-rover_square.svg)" in (DOCS.parent / "README.md").read_text(encoding="utf-8")
