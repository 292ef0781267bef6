"""The Foxglove layout shipped with the package (``executive foxglove-layout -o layout.json``): a run's panels, no set-up.

Import it in Foxglove (Layouts, Import from file) and open a recording (``--snapshots FILE.mcap``) or
the live server (``--foxglove PORT``): the map with the route and the track, the tree's ticks and
the mission's state, the log, plots of speed, distance to the target, battery and the EKF's variances. Every topic and
field named here is one the recording holds (tests/observers/test_mcap_recording.py checks them against a run).
"""

from __future__ import annotations

from typing import Any

#: (panel title, message paths): Foxglove's Plot panel, one line per path (``/topic.field``).
PLOTS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("speed (m/s)", ("/mavlink/in/VFR_HUD.groundspeed", "/mavlink/in/VFR_HUD.airspeed")),
    # The autopilot's distance to its current target (ArduRover Rover/GCS_MAVLink_Rover.cpp send_nav_controller_output:
    # MIN(get_distance_to_destination(), UINT16_MAX), in its autopilot modes): the blackboard holds our target as text only.
    ("distance to the target (m)", ("/mavlink/in/NAV_CONTROLLER_OUTPUT.wp_dist",)),
    ("battery (%)", ("/mavlink/in/SYS_STATUS.battery_remaining", "/mavlink/in/BATTERY_STATUS.battery_remaining")),
    ("EKF variances", (
        "/mavlink/in/EKF_STATUS_REPORT.velocity_variance", "/mavlink/in/EKF_STATUS_REPORT.pos_horiz_variance",
        "/mavlink/in/EKF_STATUS_REPORT.compass_variance",
    )),
    ("heading (°) and mission leg", ("/mavlink/in/VFR_HUD.heading", "/mission/state.leg_index")),
)  # fmt: skip


def _plot(title: str, paths: tuple[str, ...]) -> dict[str, Any]:
    lines = [{"value": path, "enabled": True, "timestampMethod": "receiveTime"} for path in paths]
    return {"title": title, "paths": lines, "showXAxisLabels": True, "showYAxisLabels": True, "showLegend": True, "isSynced": True}


def layout() -> dict[str, Any]:
    """The layout as Foxglove exports one: each panel's config by id, and how they are laid out."""
    panels: dict[str, dict[str, Any]] = {
        "map!route": {
            "center": None, "zoomLevel": 18, "layer": "map", "followTopic": "/vehicle/location", "disabledTopics": [],
            "topicColors": {"/vehicle/location": "#e8590c", "/mission/route": "#1971c2"},
        },
        "3D!home": {"followTf": "vehicle", "topics": {"/vehicle/pose": {"visible": True}}, "transforms": {}},
        "StateTransitions!mission": {"paths": [{"value": "/mission/state.state", "timestampMethod": "receiveTime"}], "isSynced": True},
        "RawMessages!tree": {"topicPath": "/tree/tick", "diffEnabled": False, "expansion": "all"},
        "RawMessages!waiting": {"topicPath": '/blackboard.bb["/mission/waiting"]', "diffEnabled": False, "expansion": "all"},
        "RosOut!log": {"searchTerms": [], "minLogLevel": 1, "topicToRender": "/log"},
    }  # fmt: skip
    plots = [f"Plot!{i}" for i in range(len(PLOTS))]
    panels.update({panel: _plot(title, paths) for panel, (title, paths) in zip(plots, PLOTS, strict=True)})
    left = {"first": "map!route", "second": "3D!home", "direction": "column", "splitPercentage": 65}
    middle = {
        "first": "StateTransitions!mission",
        "second": {"first": "RawMessages!waiting", "second": {"first": "RawMessages!tree", "second": "RosOut!log", "direction": "column"},
                   "direction": "column", "splitPercentage": 25},
        "direction": "column", "splitPercentage": 15,
    }  # fmt: skip
    right: Any = plots[-1]
    for panel in reversed(plots[:-1]):
        right = {"first": panel, "second": right, "direction": "column"}
    return {
        "configById": panels,
        "globalVariables": {},
        "userNodes": {},
        "playbackConfig": {"speed": 1.0},
        "layout": {"first": left, "second": {"first": middle, "second": right, "direction": "row"}, "direction": "row", "splitPercentage": 35},
    }


def paths(layout_: dict[str, Any]) -> list[str]:
    """Every ``/topic.field`` (or topic) the layout's panels read."""
    found: list[str] = []
    for config in layout_["configById"].values():
        found += [p["value"] for p in config.get("paths", [])]
        found += [config[k] for k in ("topicPath", "topicToRender", "followTopic") if config.get(k)]
        found += list(config.get("topics", {}))
    return found
