"""The node catalogue: generated from the behaviour classes and factory functions themselves, complete, and open to plugins' classes."""

from __future__ import annotations

import pytest

from executive.behaviours import Guard
from executive.behaviours.base import TimedBehaviour
from executive.tree.catalogue import KINDS, PARAM_TYPES, Catalogue, CatalogueError, catalogue, mission_value, node_name
from executive.world.geofence import Geofence


def test_every_node_and_parameter_says_what_it_is():
    nodes = catalogue().nodes()
    assert {s.kind for s in nodes} == set(KINDS)
    for spec in nodes:
        assert spec.doc, spec.name
        for p in spec.params:
            assert p.type in PARAM_TYPES, (spec.name, p.name)
            assert p.doc, f"{spec.name}.{p.name} has no doc line"
            assert not (p.required and p.from_mission), (spec.name, p.name)


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        ("ekf_ok", "guard"), ("rc_not_taking_over", "guard"), ("nothing_to_sample", "guard"),
        ("set_mode", "action"), ("go_to", "action"), ("sample", "action"), ("failsafe_note", "action"),
        ("sequence", "composite"), ("selector", "composite"), ("parallel", "composite"),
        ("timeout", "decorator"), ("retry", "decorator"), ("inverter", "decorator"), ("repeat", "decorator"), ("once", "decorator"),
        ("unless_paused", "decorator"), ("wait_until", "decorator"), ("for_each_leg", "decorator"), ("failsafe_guarded", "decorator"),
        ("preflight", "subtree"), ("within_reach", "subtree"), ("checked", "subtree"), ("mission_root", "subtree"),
    ],
)  # fmt: skip
def test_each_kind_of_node_is_there(name, kind):
    spec = catalogue().get(name)
    assert spec is not None and spec.kind == kind


def test_bases_and_internal_parts_are_not_offered():
    names = catalogue().names()
    for hidden in ("guard", "command_action", "failsafe", "wait_for_guards", "_vertical_setpoint"):
        assert hidden not in names


def test_parameters_come_from_the_signature_with_units_defaults_and_mission_values():
    go_to = catalogue().get("go_to")
    assert go_to is not None
    radius, look_ahead, method = go_to.param("acceptance_radius_m"), go_to.param("look_ahead"), go_to.param("method")
    assert radius is not None and (radius.type, radius.unit, radius.required, radius.from_mission) == (
        "float",
        "m",
        False,
        "limits.acceptance_radius_m",
    )
    assert look_ahead is not None and (look_ahead.type, look_ahead.default) == ("bool", False)
    assert method is not None and method.type == "one of" and method.choices == ("setpoint", "reposition")
    set_mode = catalogue().get("set_mode")
    assert set_mode is not None and set_mode.param("mode").required  # type: ignore[union-attr]
    speed = catalogue().get("speed_within")
    assert speed is not None and (speed.param("limit").type, speed.param("limit").unit) == ("range", "m/s")  # type: ignore[union-attr]
    resend = go_to.param("resend_s")
    assert resend is not None and (resend.unit, resend.default) == ("s", 1.0)


def test_guards_take_their_debounce_with_their_own_figures_as_defaults():
    ekf = catalogue().get("ekf_ok")
    assert ekf is not None
    assert ekf.param("resume_after_s").default == 3.0 and ekf.param("resume_after_s").unit == "s"  # type: ignore[union-attr]
    assert ekf.param("awaiting_recovery").default is False  # type: ignore[union-attr]


def test_children_are_typed_slots():
    assert [(p.name, p.type) for p in catalogue().get("sequence").child_params] == [("children", "nodes")]  # type: ignore[union-attr]
    assert [(p.name, p.type) for p in catalogue().get("failsafe_guarded").child_params] == [("work", "node"), ("guards", "guards")]  # type: ignore[union-attr]
    assert [(p.name, p.type) for p in catalogue().get("checked").child_params] == [("guard", "guard")]  # type: ignore[union-attr]
    note = catalogue().get("failsafe_note")
    assert note is not None and note.param("guard").type == "node name" and note.refs == ("guard",)  # type: ignore[union-attr]


def test_mission_values_take_an_absent_section_s_defaults(square_mission):
    assert mission_value("limits.acceptance_radius_m", square_mission) == 1.5
    assert mission_value("vtol.takeoff_alt_m", square_mission) == 30.0  # no vtol: section
    assert mission_value("vehicle.safe_mode", square_mission) == "HOLD"
    assert mission_value("geofence", square_mission) is None


class SeaStateBelow(Guard):
    """The sea state is below ``max_level`` (a plugin's guard)."""

    reads = ("/vehicle/position",)
    param_docs = {"max_level": "Douglas sea scale"}

    def __init__(self, max_level: int = 4, name: str = "Sea calm?") -> None:
        super().__init__(name)
        self.max_level = max_level

    def check(self) -> str | None:
        return None


def test_plugins_classes_join_the_catalogue_with_the_same_description():
    built = Catalogue.build(extra=[SeaStateBelow])
    spec = built.get("sea_state_below")
    assert spec is not None and spec.kind == "guard" and spec.doc == "The sea state is below ``max_level`` (a plugin's guard)."
    assert spec.param("max_level").default == 4 and spec.origin.endswith("SeaStateBelow")  # type: ignore[union-attr]
    assert len(built.nodes()) == len(Catalogue.build().nodes()) + 1


def test_a_name_taken_twice_is_refused_naming_both():
    class EkfOk(SeaStateBelow):
        """Another EKF check."""

    with pytest.raises(CatalogueError, match=r"'ekf_ok' is taken twice: executive\.behaviours\.guards\.EkfOk and"):
        Catalogue.build(extra=[EkfOk])


def test_a_parameter_no_file_can_give_is_refused():
    class Fenced(TimedBehaviour):
        """Needs a fence nobody can write."""

        def __init__(self, fence: Geofence, name: str = "Fenced") -> None:
            super().__init__(name)

    with pytest.raises(CatalogueError, match="fenced: parameter 'fence'"):
        Catalogue.build(extra=[Fenced])


def test_node_names_are_snake_case_of_the_class():
    assert node_name(SeaStateBelow) == "sea_state_below"
    from executive.behaviours import GoTo, RcNotTakingOver

    assert (node_name(GoTo), node_name(RcNotTakingOver)) == ("go_to", "rc_not_taking_over")
