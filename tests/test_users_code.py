"""A user's code fails as the user's code: a tree or behaviour of theirs that raises is named by its file and line, never "crashed (a bug)".

``validate`` and ``run`` say the same of a tree that cannot be built (exit 2, nothing sent); a
behaviour whose ``setup`` raises refuses the mission before anything is commanded (exit 2); one
that raises mid-mission aborts it with the vehicle made safe (exit 1). And a tree that succeeds
short of the waypoints says how many it reached.
"""

from __future__ import annotations

import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest

from executive.cli import main
from executive.cli.run import exit_code
from executive.mission.lifecycle import MissionStatus
from executive.observers.journal import Journal, journal_recorder
from executive.testing import Lockstep
from executive.world import blackboard
from tests_support import LINE_HOME, acting, line_mission, mission_text, run_recording

USERS = '''
    """A field team's trees and a behaviour of theirs."""

    import py_trees

    from executive.behaviours.base import ExecutiveBehaviour
    from executive.trees import waypoints


    def old_import(mission):
        from trees import waypoints as old  # the top-level trees module, gone since the redesign
        return old.build(mission)


    def not_a_tree(mission):
        return "waypoints"


    def done_at_once(mission):
        return py_trees.behaviours.Success(name="Done")


    class Sonar(ExecutiveBehaviour):
        """Raises where it is told to."""

        reads = ("/mission/leg_index",)

        def __init__(self, fails_in: str) -> None:
            super().__init__(f"Sonar ({fails_in})")
            self.fails_in = fails_in

        def setup(self, **kwargs):
            super().setup(**kwargs)
            if self.fails_in == "setup":
                raise OSError("no sonar on /dev/ttyUSB3")

        def update(self):
            if self.fails_in == "update" and self.get("/mission/leg_index") >= 2:
                raise ZeroDivisionError("division by zero")
            return py_trees.common.Status.RUNNING

        def terminate(self, new_status):
            if self.fails_in == "terminate":
                raise RuntimeError("sonar left open")


    def with_sonar(fails_in):
        def build(mission):
            route = waypoints.build(mission)
            return py_trees.composites.Parallel(
                "Route and sonar", policy=py_trees.common.ParallelPolicy.SuccessOnSelected([route]), children=[route, Sonar(fails_in)]
            )
        return build


    sonar_setup, sonar_update, sonar_terminate = with_sonar("setup"), with_sonar("update"), with_sonar("terminate")
'''


@pytest.fixture
def field_team(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """``field_team_trees.py`` on the path (forgotten after the test)."""
    (tmp_path / "field_team_trees.py").write_text(textwrap.dedent(USERS), encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    yield tmp_path / "field_team_trees.py"
    sys.modules.pop("field_team_trees", None)
    for key in [k for k in blackboard.KEYS if k.startswith(blackboard.PLUGIN_NAMESPACE)]:
        del blackboard.KEYS[key]


def line_of(path: Path, text: str) -> int:
    """The number of the line of ``path`` holding ``text``."""
    return next(n for n, line in enumerate(path.read_text().splitlines(), 1) if text in line)


def mission_with(tmp_path: Path, tree: str) -> str:
    path = tmp_path / "m.yaml"
    path.write_text(mission_text("field", "{lat: -35.3630, lon: 149.1652}").replace("vehicle: rover", f"vehicle: rover\ntree: {tree}"))
    return str(path)


def test_a_tree_whose_build_raises_is_the_users_error_in_validate_and_run_alike(
    field_team: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # as installed: this checkout's own top-level trees/ folder (the package's executive.trees) is not a module `trees`
    monkeypatch.setattr(sys, "path", [p for p in sys.path if not (Path(p or ".") / "trees").is_dir()])  # (tests/trees too)
    monkeypatch.delitem(sys.modules, "trees", raising=False)
    path = mission_with(tmp_path, "field_team_trees:old_import")
    line = next(n for n, text in enumerate(Path(path).read_text().splitlines(), 1) if text.startswith("tree:"))
    where = f"{field_team}:{line_of(field_team, 'from trees import')}"
    said = (
        f"{path}:{line}:7: tree: {where}: plugin 'field_team_trees:old_import': build(mission) raised "
        "ModuleNotFoundError: No module named 'trees' (the built-in trees are the package executive.trees: from executive.trees import ...)\n"
    )
    assert main(["validate", path]) == 2
    assert capsys.readouterr().err == said
    assert main(["run", path, "--socket", "none"]) == 2  # refused before the simulator (or a vehicle) is opened: nothing sent
    err = capsys.readouterr().err
    assert err == said and "Traceback" not in err and "a bug" not in err


def test_a_tree_that_returns_no_behaviour_is_refused(field_team: Path, tmp_path: Path, capsys) -> None:
    assert main(["validate", mission_with(tmp_path, "field_team_trees:not_a_tree")]) == 2
    assert "plugin 'field_team_trees:not_a_tree': build(mission) returned 'waypoints', not a py_trees behaviour" in capsys.readouterr().err


def test_a_behaviour_whose_setup_raises_refuses_the_mission_before_anything_is_commanded(field_team: Path) -> None:
    boots_at = (*LINE_HOME, 0.0)
    outcome, sim, received = run_recording(line_mission("field", tree="field_team_trees:sonar_setup"), boots_at)
    assert outcome.status is MissionStatus.ABORTED and outcome.users_code and exit_code(outcome) == 2
    where = f"{field_team}:{line_of(field_team, 'raise OSError')}"
    assert outcome.reason == (
        f"refused before anything was commanded: {where}: plugin field_team_trees.Sonar ('Sonar (setup)'): "
        "setup() raised OSError: no sonar on /dev/ttyUSB3"
    )
    assert acting(received) == [] and not sim.autopilot.armed


def test_a_behaviour_that_raises_mid_mission_aborts_it_with_the_vehicle_made_safe(field_team: Path, tmp_path: Path) -> None:
    journals: list[Journal] = []

    def journal(clock: object) -> dict[str, object]:
        journals.append(Journal(tmp_path / "j.db", clock))  # type: ignore[arg-type]
        return {"plugs": [journal_recorder(journals[0])]}

    with Lockstep(line_mission("field", tree="field_team_trees:sonar_update"), home=(*LINE_HOME, 0.0), options_for_clock=journal) as sim:
        outcome = sim.run_to_end(limit_s=300)
    assert outcome.status is MissionStatus.ABORTED and exit_code(outcome) == 1 and not outcome.users_code
    where = f"{field_team}:{line_of(field_team, 'raise ZeroDivisionError')}"
    assert outcome.reason == f"behaviour crashed: Route and sonar/Sonar (update): {where}: ZeroDivisionError: division by zero"
    assert outcome.safe == "the vehicle made safe: HOLD (confirmed)" and sim.autopilot.mode == "HOLD"
    report = journals[0].report()
    assert [leg["waypoint"] for leg in report["legs"]] == [1, 2]  # what was done before it is kept
    assert report["outcome"] == "ABORTED" and report["reason"] == outcome.reason


def test_a_terminate_that_raises_does_not_stop_the_vehicle_being_made_safe(field_team: Path, caplog: pytest.LogCaptureFixture) -> None:
    with Lockstep(line_mission("field", tree="field_team_trees:sonar_terminate"), home=(*LINE_HOME, 0.0)) as sim:
        assert sim.run(120, until=lambda: sim.runtime.mission_state.legs.leg_index >= 1) is None
        sim.runtime.request_stop("SIGTERM")
        outcome = sim.run_to_end(limit_s=60)
    assert outcome.status is MissionStatus.ABORTED and outcome.reason == "stopped: SIGTERM"
    assert outcome.safe == "the vehicle made safe: HOLD (confirmed)" and sim.autopilot.mode == "HOLD"
    assert "stopping the tree: Route and sonar/Sonar (terminate): " in caplog.text  # the node whose terminate() raised, named


def test_a_tree_that_succeeds_short_of_the_waypoints_says_how_many_it_reached(field_team: Path) -> None:
    outcome, _sim, received = run_recording(line_mission("field", tree="field_team_trees:done_at_once"), (*LINE_HOME, 0.0))
    assert outcome.status is MissionStatus.COMPLETED
    assert outcome.reason == "the tree succeeded; 0 of 4 waypoints reached"
    assert acting(received) == []
