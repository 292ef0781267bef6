"""ParameterIs: a pre-flight check of one of the autopilot's parameters, asked by PARAM_REQUEST_READ, refused with its name and value."""

from __future__ import annotations

from py_trees.common import Status

from executive.behaviours import ParameterIs

R, S, F = Status.RUNNING, Status.SUCCESS, Status.FAILURE


def requests(link) -> list[str]:
    return [m.param_id for m in link.take() if m.get_type() == "PARAM_REQUEST_READ"]


def test_asks_until_the_value_comes_then_accepts_it(harness, vehicle):
    node = ParameterIs("Q_GUIDED_MODE", (1.0,), "a hover point needs it", ask_every_s=1.0)
    h = harness(node)
    assert h.tick(0.5) == R and requests(h.link) == ["Q_GUIDED_MODE"]
    assert h.tick(0.5) == R and requests(h.link) == []
    assert h.tick(0.5) == R and requests(h.link) == ["Q_GUIDED_MODE"]  # no answer: asked again a second later
    vehicle.set(vehicle__params={"Q_GUIDED_MODE": 1.0})
    assert h.tick() == S and node.feedback_message == "Q_GUIDED_MODE 1"


def test_a_wrong_value_is_refused_naming_the_parameter_the_value_it_needs_and_why(harness, vehicle):
    vehicle.set(vehicle__params={"Q_GUIDED_MODE": 0.0})
    node = ParameterIs("Q_GUIDED_MODE", (1.0,), "a hover point needs it")
    h = harness(node)
    assert h.tick() == F and node.feedback_message == "Q_GUIDED_MODE is 0: set it to 1: a hover point needs it"
    assert requests(h.link) == []


def test_no_answer_is_a_failure_after_its_time_limit(harness):
    node = ParameterIs("Q_GUIDED_MODE", (1.0,), "a hover point", timeout_s=3.0)
    h = harness(node)
    assert [h.tick(1.0) for _ in range(5)] == [R, R, R, R, F]  # started at the first tick: over 3 s at the fifth
    assert node.feedback_message == "Q_GUIDED_MODE not reported by the autopilot within 3 s (it needs a hover point)"
