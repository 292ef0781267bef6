"""The live view in a real browser (headless Chromium, Debian's ``chromium``: .ci/run installs it) during a real run from the command line.

``EXECUTIVE_LIVE_VIEW_PNG=docs/live-view.png`` keeps the screenshot README and the manual show (tests/docs/test_pictures.py).
"""

from __future__ import annotations

import os
import queue
import re
import shutil
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from executive.io import control
from executive.observers.snapshots import SnapshotRecorder, replay, snapshot_recorder
from executive.observers.web.replay import ReplaySource
from executive.observers.web.server import WebAddress, WebServer
from tests_support import executive_process, line_mission, mission_text

if TYPE_CHECKING:
    from playwright.sync_api import Browser

ROOT = Path(__file__).parents[3]
CHROMIUM = "/usr/bin/chromium"
MISSION = mission_text(
    "live-view",
    "{lat: -35.3631711, lon: 149.1652300}  # 10 m north",
    "{lat: -35.3631711, lon: 149.1653401}  # then 10 m east",
    "{lat: -35.3577752, lon: 149.1657805}  # then 600 m north, 40 m east: the run cannot end before the page is up and Pause is pressed",
)


@pytest.fixture(scope="module")
def chromium() -> Iterator[Browser]:
    """One headless Chromium for the module's pages (a start costs ~2 s of CPU)."""
    if not os.path.exists(CHROMIUM) and not os.environ.get("CI"):
        pytest.skip(f"no {CHROMIUM} (apt-get install chromium; .ci/run does)")
    sync_api = pytest.importorskip("playwright.sync_api") if not os.environ.get("CI") else __import__("playwright.sync_api").sync_api
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        yield browser
        browser.close()


def announced_url(proc: subprocess.Popen) -> str:
    """The live view's address, as the executive prints it at start-up (its stderr read on in a thread so it never fills)."""
    lines: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: [lines.put(line) for line in proc.stderr], daemon=True).start()
    while True:
        line = lines.get(timeout=30)
        if found := re.search(r"live view on (http://\S+/)", line):
            return found[1]


@pytest.mark.xdist_group("chromium")  # one browser a worker: the module's pages share it
def test_the_page_shows_the_running_tree_and_its_pause_button_pauses_the_mission(tmp_path, request):
    mission, sock, token = tmp_path / "live.yaml", tmp_path / "ctl.sock", tmp_path / "token"
    mission.write_text(MISSION)
    token.write_text("a-token-of-twenty-chars\n")  # its buttons need it, as beyond the loopback interface; the page takes it from its address
    proc = executive_process("run", str(mission), "--speedup", "20", "--socket", str(sock), "--web", "127.0.0.1:0", "--web-token-file", str(token))
    try:
        chromium = request.getfixturevalue("chromium")  # started while the executive starts
        url = announced_url(proc)
        with chromium.new_page(viewport={"width": 1400, "height": 820}) as page:
            errors: list[str] = []
            page.on("pageerror", lambda error: errors.append(str(error)))
            page.goto(f"{url}?token=a-token-of-twenty-chars")
            # the tree's nodes by name, and their statuses as they tick: the leg being driven is RUNNING, pre-flight is done
            going = page.locator('#tree g.node[data-status="R"]', has_text="Go to waypoint")
            going.wait_for(timeout=20_000)
            names = page.locator("#tree text.name").all_text_contents()
            assert {"Mission", "Pre-flight", "EKF ok?", "Link alive?", "For each leg", "Go to waypoint"} <= set(names)
            assert page.locator('#tree g.node[data-status="S"]', has_text="Pre-flight").count() == 1
            on_last_leg = "$('leg').textContent === '3/3' && $('waiting').textContent.startsWith('waiting: Go to waypoint')"
            page.wait_for_function(on_last_leg.replace("$(", "document.getElementById("), timeout=20_000)
            assert page.locator("#state").inner_text() == "RUNNING"
            assert page.locator("#plan polyline.track").count() == 1 and page.locator("#plan circle.wp").count() == 3
            mode = page.locator("#bb tr", has=page.locator("td", has_text=re.compile(r"^/vehicle/mode$")))
            assert mode.locator("td").all_inner_texts() == ["/vehicle/mode", "'GUIDED'"]
            page.screenshot(path=tmp_path / "live-view.png")
            page.get_by_role("button", name="Pause").click()
            page.wait_for_function("document.getElementById('state').textContent === 'PAUSED'", timeout=20_000)
            assert "pause: done" in page.locator("#reply").inner_text()
        status = control.request(str(sock), "status")
        assert (status["state"], status["status"]["reason"]) == ("PAUSED", "web: pause")
        assert errors == []
        if keep := os.environ.get("EXECUTIVE_LIVE_VIEW_PNG"):
            shutil.copy(tmp_path / "live-view.png", ROOT / keep)
    finally:
        proc.terminate()
        proc.wait(timeout=30)


@pytest.mark.xdist_group("chromium")  # one browser a worker: the module's pages share it
def test_the_replay_page_moves_through_a_recording_with_its_slider(tmp_path, lockstep, chromium):
    path = tmp_path / "run.snap"
    recorder = SnapshotRecorder(path)
    lockstep(line_mission("replayed"), plugs=[snapshot_recorder(recorder)]).run_to_end(300.0)
    recorder.close()
    source = ReplaySource(str(path))
    server = WebServer(WebAddress("127.0.0.1", 0))
    server.start(source)
    try:
        with chromium.new_page(viewport={"width": 1400, "height": 820}) as page:
            page.goto(server.url)
            last = source.recording.last
            page.wait_for_function(f"document.getElementById('tickinfo').textContent.startsWith('tick {last} ')", timeout=20_000)
            assert page.locator("#controls").is_hidden()  # nothing to command in a recording
            page.locator("#slider").fill("150")
            page.wait_for_function("document.getElementById('tickinfo').textContent.startsWith('tick 150 ')", timeout=20_000)
            then = replay(path, 150)
            statuses = {node["name"]: then.status.get(node["id"], "-") for node in then.nodes}
            going = page.locator("#tree g.node", has_text="Go to waypoint")
            assert going.get_attribute("data-status") == statuses["Go to waypoint"] == "R"
            assert page.locator("#tree g.node", has_text="Pre-flight").get_attribute("data-status") == "S"
            leg = int(then.blackboard["/mission/leg_index"]) + 1
            assert page.locator("#state").inner_text() == "RUNNING" and page.locator("#leg").inner_text() == f"{leg}/4"
            assert page.locator("#plan polyline.track").count() == 1
    finally:
        server.close()
