"""Every benchmark runs, with the fewest iterations that exercise it (no timing is asserted: the figures come from ``python -m benchmarks``)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from benchmarks import __main__ as bench
from benchmarks import can_decode, efficiency, ingest, reaction, route_check, simspeed, soak, startup, tick
from benchmarks.common import Row, serpentine
from tests_support import SharedEfficiencyRuns


def _check(rows: list[Row], count: int) -> None:
    assert len(rows) == count
    for row in rows:
        assert math.isfinite(row.value), row
        assert row.passed in (True, False) or (row.passed is None and not row.target), row  # a figure without a target says so
        json.dumps(row.to_dict())
    assert bench.table(rows).count("\n") == count + 1


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_tick(autopilot: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # smaller sizes than the command's: the CPU share of rover_square's first two legs, the breakdown's legs 10 m, not 50 m
    square = (tick.MISSIONS / "rover_square.yaml").read_text()
    (tmp_path / "two_legs.yaml").write_text(
        "\n".join(line for line in square.splitlines() if "name: east}" not in line and "name: home}" not in line)
    )
    monkeypatch.setattr(tick, "serpentine", lambda count, leg_m, row_m: serpentine(count, 10.0, row_m=100.0))
    rows = tick.run(ticks=10, sizes=(2, 3), warmup_ticks=1, autopilot=autopilot, missions=[tmp_path / "two_legs.yaml"])  # type: ignore[arg-type]
    cpu = 1 if autopilot == "ardupilot" else 0  # the seed missions' CPU share: ArduPilot's
    mcap = 1 if autopilot == "ardupilot" else 0  # the recording as MCAP beside JSON lines' (ArduPilot's rows alone)
    _check(rows, cpu + 1 + len(tick.PARTS) + mcap + 1)  # the full tick, its parts beside their floors, the growth
    assert all(row.name.endswith(", px4") == (autopilot == "px4") for row in rows if not row.name.startswith("CPU share"))


def test_ingest() -> None:
    _check(ingest.run(seconds=3.0, repeats=1), 1)


def test_can_decode() -> None:
    _check(can_decode.run(frames=600, repeats=1), 2)


def test_route_check() -> None:
    _check(route_check.run(legs=20, zones=5, repeats=1), 3)


def test_soak() -> None:
    _check(soak.run(legs=2, sample_every=20, process_legs=3, leg_m=20.0), 4)


def test_reaction() -> None:
    _check(reaction.run(trials=1, settle_s=0.2, speedup=10.0), 1)  # 1 s of EKF start-up and a leg's start at 10x


def test_simulator_speed() -> None:
    _check(simspeed.run(speedups=(20.0,), length_m=20.0, runs=1, ekf_ready_after_s=1.0), 1)


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_startup_and_memory(autopilot: str) -> None:
    _check(startup.run(runs=1, sample_s=0.2, autopilot=autopilot), 2)  # type: ignore[arg-type]


@pytest.mark.xdist_group("leg_efficiency")
def test_efficiency(efficiency_runs: SharedEfficiencyRuns, monkeypatch: pytest.MonkeyPatch) -> None:
    from benchmarks import recorded

    efficiency_runs.share(monkeypatch)  # rover_square's runs are tests/trees/test_leg_efficiency.py's and test_waypoints_auto.py's too
    rows = efficiency.run(missions=("rover_square",), px4_legs=2)
    # both drives, on our simulator and on the recorded firmware; the PX4 vtol's (2 legs) on our simulated PX4 and on the real one
    _check(rows, 2 + 2 * recorded.available("rover_square") + 2 + 2 * recorded.px4_available())
    assert [row.name.split(" / ")[0] for row in rows[:2]] == ["GUIDED", "drive: auto"]
    px4 = rows[2 + 2 * recorded.available("rover_square") :][:2]
    assert [(row.name.split(" / ")[0], row.passed is None) for row in px4] == [("drive: auto", False), ("GUIDED", True)]
    assert all("our simulated PX4's AUTO.MISSION" in row.name for row in px4)


def test_the_command_writes_json(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setitem(bench.BENCHMARKS, "can", lambda: can_decode.run(frames=60, repeats=1))
    out = tmp_path / "bench.json"
    assert bench.main(["--only", "can", "--json", str(out)]) == 0
    assert "CAN decode" in capsys.readouterr().out
    assert [row["group"] for row in json.loads(out.read_text())["rows"]] == ["can", "can"]


def test_efficiency_on_the_recorded_px4_names_what_it_compared_against_and_judges_only_drive_auto() -> None:
    """drive: auto against PX4's own AUTO.MISSION over the whole route, pass/fail; GUIDED (OFFBOARD) information only: a vtol's 70 m
    acceptance radius ends each leg short, so the two are not like for like."""
    auto, guided = efficiency.px4_recorded_rows()
    assert "vtol-waypoints-px4-own-auto.tlog" in auto.name and "vtol-waypoints-auto.tlog" in auto.name
    assert auto.passed is True and 0.98 <= auto.value <= 1.02  # 134.4 s / 135.0 s
    assert "vtol-waypoints-guided.tlog" in guided.name and guided.passed is None and not guided.target
    assert guided.detail.startswith("information, not like for like")
