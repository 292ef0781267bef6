"""Fixtures every test shares: a clean blackboard, the square mission (the kit's clock, link, harness... come from executive.testing);
and the runs several files read (session scope, each with one xdist group for its users, so one worker makes it once)."""

from __future__ import annotations

import gc
import importlib
import logging
import os
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest
from hypothesis import settings

try:
    from _pytest.nodeid import NodeId  # pytest >= 9.2: see _groups_in_node_ids
except ImportError:  # an older pytest reads item._nodeid, which xdist writes itself
    NodeId = None  # type: ignore[assignment,misc]

if TYPE_CHECKING:
    from executive.mission.lifecycle import MissionState
    from executive.mission.model import Mission
    from tests_support import SharedEfficiencyRuns, SubRun, Ticks

# The fixtures import the package themselves: xdist's controller loads this file too and runs no test (with the kit's
# plugin, 0.6 s of CPU before it started its workers); a worker has the package from the test modules it collects.

# The suite starts ~150 `python -m executive` processes and each xdist worker rewrites ~130 test modules'
# asserts: without cached bytecode every one of them compiles the package and the tests from source
# again (43 s of the suite's 215 s of CPU on 2 cores). Where PYTHONDONTWRITEBYTECODE is set (some CI
# images set it), the test run still keeps its bytecode; this runs in the xdist controller, before the
# workers and every subprocess inherit the environment.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False

# The property tests draw the same examples in every run (a seed per test), so the suite passes or fails the same way on any
# machine and day; HYPOTHESIS_PROFILE=default draws new ones (to search further, by hand) and keeps failures in .hypothesis/.
settings.register_profile("suite", derandomize=True, database=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "suite"))
# Hypothesis (6.131 on) also draws some examples from the literals of the project's modules loaded at that moment
# (hypothesis/internal/conjecture/providers.py, _get_local_constants), which depends on what the tests before imported:
# a derandomized test drew other examples in each run. Here it draws from hypothesis's own constants only, the same in
# every run (tests/test_suite_examples.py fails if this stops working, e.g. when hypothesis renames it).
_providers = importlib.import_module("hypothesis.internal.conjecture.providers")
_no_local_constants = _providers.Constants()
_providers._get_local_constants = lambda: _no_local_constants

# A suite started in the background (`pytest ... &` in a script, nohup, a CI step) inherits SIGINT ignored, as
# does every executive it starts: Ctrl-C's tests (`ctl tree --watch`, an interrupted first-heartbeat wait)
# then failed, 2 of 2154 in every such run. A terminal's Ctrl-C reaches a process whose SIGINT is the default:
# a handler here (reset to the default in every process started from it) makes that so.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int | None:
    """``-n auto``: a quarter more workers than cores, at least one more (2 cores: 3 workers; 8: 10).

    About a quarter of the suite's wall time is spent waiting (for a subprocess, a socket, a browser),
    with a core idle: measured on 2 cores, 2 workers took 95-98 s and 3 workers 84-89 s for the same
    CPU. ``PYTEST_XDIST_AUTO_NUM_WORKERS`` still wins (xdist's own hook reads it).
    """
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return cores + max(1, cores // 4)


#: The test workers' youngest-generation threshold (CPython's default is 700). Lock-step runs and property tests keep tens of
#: thousands of objects alive for a while (a run's records, hypothesis's caches): at 700 they were walked again in ~11k
#: collections, 5.5 CPU-s of the suite's workers. At 10,000, tests/trees/test_auv_survey.py, tests/hostile/test_mission_files.py,
#: tests/mission, tests/io/test_storage.py and tests/sim spent 0.83 CPU-s collecting instead of 1.54 (2,764 -> 135 young,
#: 251 -> 12 middle, 24 -> 2 full passes); 5,000 and 20,000 cost more (0.95, 1.07). No test's outcome depends on when garbage is
#: collected (none reads a weakref, a ResourceWarning or the memory in-process), and the executive processes the tests start
#: keep CPython's default.
GC_YOUNG_THRESHOLD = 10_000


def pytest_configure(config: pytest.Config) -> None:
    """The young generation collected less often (:data:`GC_YOUNG_THRESHOLD`) from the start: collection's imports too
    (a worker's collection spent 0.23 CPU-s collecting garbage instead of 0.34)."""
    gc.set_threshold(GC_YOUNG_THRESHOLD, *gc.get_threshold()[1:])


def pytest_collection_finish(session: pytest.Session) -> None:
    """What collection made (the package, the test modules, ~3,400 items) is kept to the end: frozen out of the collector's
    full passes, which would otherwise walk it again and again between the tests (gc.freeze, as a forking server does)."""
    gc.collect()
    gc.freeze()


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The tests marked ``slow`` first (collection order kept otherwise): xdist hands tests out in this order, so the longest
    starts at once and the short ones fill the other workers around it, instead of it starting late and running on alone
    (tests/test_wheel.py was collected 2,928th of 3,187: its 25 s could be the run's last, on one worker). In an xdist
    worker under ``--dist loadgroup``, each test marked ``xdist_group`` gets its group in its node id (below)."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)
    if getattr(config.option, "loadgroup", False):
        _groups_in_node_ids(items)


def _groups_in_node_ids(items: list[pytest.Item]) -> None:
    """``test_x@GROUP``, the node id by which xdist's loadgroup scheduler sends every test of GROUP to one worker.

    xdist (3.8) writes it to ``item._nodeid``, which pytest 9.2 no longer reads (``nodeid`` is made from ``item._id``): the
    groups were ignored, each test went to any worker and paid its group's module fixture again (the import contract's
    parse, 0.8 s, three times). Written here where pytest reads it, as xdist would; an id xdist has marked already is kept.
    Upstream: pytest-dev/pytest-xdist#1386 (open; the fix proposed in #1388 writes the same structured id).
    """
    if NodeId is None:
        return
    for item in items:
        names = sorted({str(mark.args[0] if mark.args else mark.kwargs.get("name", "default")) for mark in item.iter_markers("xdist_group")})
        if names and "@" not in item.nodeid:
            item._id = NodeId.parse(f"{item.nodeid}@{'_'.join(names)}")


@pytest.fixture(scope="session", autouse=True)
def filterpy_loaded() -> None:
    """The heading filter loads filterpy in the background; tests want it judging from the first reading."""
    from executive.sensing.heading import wait_for_filterpy

    assert wait_for_filterpy()


@pytest.fixture(autouse=True)
def every_test_on_a_clean_blackboard(clean_blackboard: None) -> None:
    """The kit's ``clean_blackboard``, for every test."""


@pytest.fixture(autouse=True)
def logging_as_it_was() -> Iterator[None]:
    """A command run in a test (``setup_logging``) points the root logger at that test's captured stderr, closed after it, and sets
    the operator's loggers to INFO (a later test's caplog would see their records): put both back."""
    from executive.operator.logs import OPERATOR_LOGGERS

    root = logging.getLogger()
    handlers, level = root.handlers[:], root.level
    operator_levels = {name: logging.getLogger(name).level for name in OPERATOR_LOGGERS}
    yield
    root.handlers[:] = handlers
    root.setLevel(level)
    for name, was in operator_levels.items():
        logging.getLogger(name).setLevel(was)


@pytest.fixture
def square_mission() -> Mission:
    """Four waypoints on a 20 m square (the rover square), radius 1.5 m, leg timeout 60 s."""
    from executive.mission.model import Mission

    corners = [(47.397742, 8.545594), (47.397922, 8.545594), (47.397922, 8.545860), (47.397742, 8.545860)]
    return Mission.model_validate(
        {
            "version": 1,
            "name": "square",
            "vehicle": "rover",
            "auto_arm": True,
            "limits": {"acceptance_radius_m": 1.5, "leg_timeout_s": 60.0, "recovery_timeout_s": 30.0, "ekf_wait_s": 60.0},
            "waypoints": [{"lat": lat, "lon": lon} for lat, lon in corners],
        }
    )


@pytest.fixture
def mission_state(square_mission: Mission) -> MissionState:
    from executive.mission.lifecycle import MissionState

    state = MissionState()
    state.upload(square_mission)
    return state


DATA = Path(__file__).parent / "data"


@pytest.fixture
def minimal_mission() -> Path:
    """A valid mission file: one waypoint, rover, tree waypoints."""
    return DATA / "minimal_mission.yaml"


@pytest.fixture
def minimal_yaml(minimal_mission: Path) -> str:
    """The text of the smallest valid mission."""
    return minimal_mission.read_text(encoding="utf-8")


@pytest.fixture(scope="session")
def auv_survey_run() -> SubRun:
    """missions/auv_survey.yaml on the lock-step simulated ArduSub, booted at its home, run once for the tests that read it (in two
    files: the tree's legs and the energy estimate); they are marked ``tests_support.AUV_SURVEY_RUN``, so one worker makes it."""
    import py_trees

    from executive.mission.loader import load_mission
    from executive.world import blackboard
    from tests_support import sub_run

    mission = load_mission(Path(__file__).parents[1] / "missions" / "auv_survey.yaml")
    assert mission.home is not None
    blackboard.reset()  # the board each test starts on (clean_blackboard), before and after
    try:
        return sub_run(mission, (mission.home.lat, mission.home.lon, mission.home.heading_deg))
    finally:
        py_trees.blackboard.Blackboard.clear()


@pytest.fixture(scope="session")
def rover_square_two_legs_jsonl(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """rover_square's first two legs (a turn: north, then east) on the lock-step simulator to their end, recorded as JSON lines and
    watched by nothing else: the bytes a watched run must equal, a file to replay (tests/observers/groot2: both files' tests are
    marked ``xdist_group("groot2_unmonitored")``, so one worker records it)."""
    from executive.mission.loader import load_mission
    from executive.observers.snapshots import SnapshotRecorder, snapshot_recorder
    from executive.testing.lockstep import Lockstep

    missions = Path(__file__).parents[1] / "missions"
    square = load_mission(missions / "rover_square.yaml")
    path = tmp_path_factory.mktemp("rover_square_two_legs") / "unmonitored.jsonl"
    recorder = SnapshotRecorder(path)
    try:
        with Lockstep(
            square.model_copy(update={"waypoints": square.waypoints[:2]}), mission_dir=missions, plugs=[snapshot_recorder(recorder)]
        ) as sim:
            assert sim.run_to_end(600).status.name == "COMPLETED"
    finally:
        recorder.close()
    return path


@pytest.fixture(scope="session")
def rover_square_mcap(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Ticks, Any]:
    """rover_square to its end, recorded twice from the same ticks, as MCAP and as JSON lines (``tests_support.record_rover_square``),
    once for the tests that read it: tests/observers/test_mcap_recording.py's and the Foxglove picture's, all marked
    ``xdist_group("mcap_square")``."""
    from tests_support import record_rover_square

    return record_rover_square(tmp_path_factory.mktemp("square"))


@pytest.fixture(scope="session")
def efficiency_runs() -> SharedEfficiencyRuns:
    """benchmarks.efficiency's timed runs made once for the tests that read the same one (the leg-efficiency tests, the benchmark's
    smoke test, the AUTO horizon's), all marked ``xdist_group("leg_efficiency")``."""
    from tests_support import SharedEfficiencyRuns

    return SharedEfficiencyRuns()
