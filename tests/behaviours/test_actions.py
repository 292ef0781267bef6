"""Actions tick by tick: the status on each tick and the exact commands sent."""

from __future__ import annotations

import math

import pytest
from py_trees.common import Status

from executive.autopilot.rover_motion import RoverMotion, TargetEstimate
from executive.behaviours import Arm, Disarm, GoTo, SetMode
from executive.behaviours.motion import CUT_SHARE
from executive.testing.links import ack
from executive.world import geo
from executive.world.dialect import mavlink
from executive.world.geo import destination
from executive.world.state import GlobalPosition

DO_SET_MODE = mavlink.MAV_CMD_DO_SET_MODE
ARM_DISARM = mavlink.MAV_CMD_COMPONENT_ARM_DISARM


def at(lat: float, lon: float, t: float = 0.0, vn: float = 0.0, ve: float = 0.0) -> GlobalPosition:
    return GlobalPosition(lat, lon, 0.0, vn, ve, 0.0, 0.0, t)


class TestSetMode:
    def test_already_in_mode_succeeds_without_a_command(self, harness, vehicle):
        vehicle.set(vehicle__mode="GUIDED")
        h = harness(SetMode("GUIDED"))
        assert h.tick() == Status.SUCCESS
        assert h.link.take() == []

    def test_ack_then_heartbeat_confirms(self, harness, vehicle):
        vehicle.set(vehicle__mode="HOLD")
        h = harness(SetMode("guided"))
        assert h.tick() == Status.RUNNING
        (sent,) = h.link.take()
        assert (sent.get_type(), sent.command, sent.confirmation) == ("COMMAND_LONG", DO_SET_MODE, 0)
        assert (sent.param1, sent.param2) == (mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 15)
        assert (sent.target_system, sent.target_component) == (1, 1)
        h.ack(DO_SET_MODE)
        assert h.tick() == Status.RUNNING  # an ack is not the mode: wait for the heartbeat
        vehicle.set(vehicle__mode="GUIDED")
        assert h.tick() == Status.SUCCESS
        assert h.link.take() == []  # no retry after the ack

    def test_confirm_by_ack_does_not_wait_for_the_heartbeat(self, harness, vehicle, clock):
        vehicle.set(vehicle__mode="HOLD", link__last_heartbeat=clock.now())
        h = harness(SetMode("GUIDED", confirm_by_ack=True))
        assert h.tick() == Status.RUNNING
        assert len(h.link.take("COMMAND_LONG")) == 1
        assert h.tick() == Status.RUNNING  # no ack yet
        h.ack(DO_SET_MODE)
        assert h.tick() == Status.SUCCESS  # ArduPilot acks ACCEPTED once the mode is set; the heartbeat still says HOLD
        assert h.link.take() == []

    def test_confirm_by_ack_ignores_a_refusal_and_an_earlier_ack(self, harness, vehicle, commander, clock):
        vehicle.set(vehicle__mode="HOLD", link__last_heartbeat=clock.now())
        commander.set_mode("LOITER")  # someone else's request, acked before this one is sent
        commander.on_ack(ack(DO_SET_MODE))
        node = SetMode("GUIDED", confirm_by_ack=True)
        h = harness(node)
        assert h.tick() == Status.RUNNING
        h.ack(DO_SET_MODE, mavlink.MAV_RESULT_FAILED)
        assert h.tick() == Status.FAILURE

    def test_confirm_by_ack_holds_until_a_later_heartbeat_says_otherwise(self, harness, vehicle, clock):
        # re-ticked every tick (a sequence without memory): no new request while the ack is the latest word
        vehicle.set(vehicle__mode="HOLD", link__last_heartbeat=clock.now())
        node = SetMode("GUIDED", confirm_by_ack=True)
        h = harness(node)
        assert h.tick() == Status.RUNNING
        h.link.take()
        h.ack(DO_SET_MODE)
        assert h.tick() == Status.SUCCESS
        assert [h.tick() for _ in range(3)] == [Status.SUCCESS] * 3
        assert h.link.take("COMMAND_LONG") == []
        vehicle.set(vehicle__mode="MANUAL", link__last_heartbeat=clock.now() + 0.05)  # a heartbeat after the ack: a person changed it
        assert h.tick() == Status.RUNNING
        assert len(h.link.take("COMMAND_LONG")) == 1  # asked again

    def test_refused_mode_fails_with_the_reason(self, harness, vehicle):
        vehicle.set(vehicle__mode="HOLD", vehicle__statustext=(4, "Flight mode change failed"))
        node = SetMode("GUIDED")
        h = harness(node)
        assert h.tick() == Status.RUNNING
        h.ack(DO_SET_MODE, mavlink.MAV_RESULT_FAILED)
        assert h.tick() == Status.FAILURE
        assert node.feedback_message == "refused: FAILED (Flight mode change failed)"

    def test_no_ack_is_retried_with_confirmation_then_times_out(self, harness, vehicle):
        vehicle.set(vehicle__mode="HOLD")
        node = SetMode("GUIDED", confirm_timeout_s=30.0)
        h = harness(node)
        confirmations, status, ticks = [], Status.RUNNING, 0
        while status == Status.RUNNING and ticks < 100:
            status = h.tick(0.125)  # exact in binary: no rounding in the deadlines
            ticks += 1
            confirmations += [m.confirmation for m in h.link.take("COMMAND_LONG")]
        assert confirmations == [0, 1, 2, 3]
        assert status == Status.FAILURE
        # sent on tick 1, retried on 13, 25 and 37 (1.5 s ack timeout = 12 ticks), given up on the
        # flush of tick 49: the action sees it on tick 50
        assert ticks == 50
        assert node.feedback_message == "no ack after 4 attempts"

    def test_accepted_but_never_shown_fails_after_confirm_timeout(self, harness, vehicle):
        vehicle.set(vehicle__mode="HOLD")
        node = SetMode("GUIDED", confirm_timeout_s=2.0)
        h = harness(node)
        h.tick()
        h.ack(DO_SET_MODE)
        statuses = [h.tick(0.5) for _ in range(5)]
        assert statuses == [Status.RUNNING] * 4 + [Status.FAILURE]  # elapsed 0.5 ... 2.5 s
        assert node.feedback_message == "not confirmed after 2 s"

    def test_unknown_mode_is_refused_before_anything_is_sent(self, harness, vehicle):
        vehicle.set(vehicle__mode="HOLD")
        h = harness(SetMode("WARP"))
        with pytest.raises(KeyError):
            h.tick()
        assert h.link.take() == []


class TestArm:
    def test_arm_confirmed_by_heartbeat(self, harness, vehicle):
        h = harness(Arm())
        assert h.tick() == Status.RUNNING
        (sent,) = h.link.take()
        assert (sent.command, sent.param1, sent.param2) == (ARM_DISARM, 1.0, 0.0)
        h.ack(ARM_DISARM)
        vehicle.set(vehicle__armed=True)
        assert h.tick() == Status.SUCCESS

    def test_prearm_refusal_fails_with_statustext(self, harness, vehicle):
        vehicle.set(vehicle__statustext=(3, "PreArm: AHRS: not using configured AHRS type"))
        node = Arm()
        h = harness(node)
        h.tick()
        h.ack(ARM_DISARM, mavlink.MAV_RESULT_FAILED)
        assert h.tick() == Status.FAILURE
        assert "PreArm: AHRS" in node.feedback_message

    def test_disarm(self, harness, vehicle):
        vehicle.set(vehicle__armed=True)
        h = harness(Disarm())
        assert h.tick() == Status.RUNNING
        (sent,) = h.link.take()
        assert (sent.command, sent.param1) == (ARM_DISARM, 0.0)
        vehicle.set(vehicle__armed=False)
        assert h.tick() == Status.SUCCESS


class TestGoTo:
    @pytest.fixture
    def running(self, mission_state, vehicle):
        mission_state.start()
        return mission_state.legs.target

    def test_sends_guided_target_and_reports_distance(self, harness, vehicle, running):
        lat, lon = destination(running.lat, running.lon, 180.0, 30.0)  # 30 m south of the waypoint
        vehicle.set(vehicle__position=at(lat, lon))
        node = GoTo(acceptance_radius_m=1.5, leg_timeout_s=60.0)
        h = harness(node)
        assert h.tick() == Status.RUNNING
        (sent,) = h.link.take()
        assert sent.get_type() == "SET_POSITION_TARGET_GLOBAL_INT"
        assert (sent.lat_int, sent.lon_int) == (round(running.lat * 1e7), round(running.lon * 1e7))
        assert (sent.type_mask, sent.coordinate_frame) == (0x0DF8, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)
        assert node.distance_m == pytest.approx(30.0, abs=0.01)
        assert node.bearing_deg == pytest.approx(0.0, abs=0.1)
        assert node.feedback_message == "leg 1/4: 30.0 m at 000°"

    def test_resends_the_target_every_second(self, harness, vehicle, running):
        vehicle.set(vehicle__position=at(*destination(running.lat, running.lon, 90.0, 10.0)))
        h = harness(GoTo(1.5, 60.0))
        sends = 0
        for _ in range(30):  # 3 s
            h.tick()
            sends += len(h.link.take("SET_POSITION_TARGET_GLOBAL_INT"))
        assert sends == 3

    def test_succeeds_inside_the_acceptance_radius(self, harness, vehicle, running):
        h = harness(GoTo(1.5, 60.0))
        statuses = []
        for distance in (10.0, 5.0, 1.6, 1.4):
            vehicle.set(vehicle__position=at(*destination(running.lat, running.lon, 45.0, distance)))
            statuses.append(h.tick())
        assert statuses == [Status.RUNNING, Status.RUNNING, Status.RUNNING, Status.SUCCESS]

    def test_fails_after_the_leg_timeout(self, harness, vehicle, running):
        vehicle.set(vehicle__position=at(*destination(running.lat, running.lon, 0.0, 100.0)))
        node = GoTo(1.5, leg_timeout_s=60.0)
        h = harness(node)
        statuses = [h.tick(1.0) for _ in range(62)]  # started on the first tick: elapsed 0 ... 61 s
        assert statuses == [Status.RUNNING] * 61 + [Status.FAILURE]
        assert node.feedback_message == "leg 1/4: timed out after 60 s, 100.0 m short"

    def test_no_position_keeps_running(self, harness, running):
        node = GoTo(1.5, 60.0)
        assert harness(node).tick() == Status.RUNNING
        assert node.feedback_message == "leg 1/4: no position"

    def test_no_active_leg_fails(self, harness, vehicle):
        node = GoTo(1.5, 60.0)
        assert harness(node).tick() == Status.FAILURE
        assert node.feedback_message == "no active leg"

    def test_an_edited_target_is_followed_at_once(self, harness, vehicle, running, mission_state):
        vehicle.set(vehicle__position=at(*destination(running.lat, running.lon, 180.0, 30.0)))
        node = GoTo(1.5, 60.0)
        h = harness(node)
        h.tick()
        h.link.take()
        moved = running.model_copy(update={"lon": destination(running.lat, running.lon, 90.0, 5.0)[1]})
        mission_state.set_route([moved, *mission_state.legs.route.waypoints[1:]], "test: offset 5 m east")
        assert h.tick() == Status.RUNNING
        (sent,) = h.link.take()  # sent now, not at the next resend
        assert (sent.lat_int, sent.lon_int) == (round(moved.lat * 1e7), round(moved.lon * 1e7))
        vehicle.set(vehicle__position=at(running.lat, running.lon))  # the old target is 5 m short of the new one
        assert h.tick() == Status.RUNNING
        vehicle.set(vehicle__position=at(moved.lat, moved.lon))
        assert h.tick() == Status.SUCCESS


class TestGoToLookAhead:
    """Leg 2/4 of the 20 m square: heading north for the north-west corner, then east (a 90° turn).

    The vehicle reports SITL's rover parameters (WP_SPEED 5, WP_RADIUS 3) unless a test says otherwise.
    """

    SITL = {"WP_SPEED": 5.0, "WP_RADIUS": 3.0}

    @pytest.fixture
    def corner(self, mission_state, vehicle):
        vehicle.set(vehicle__params=dict(self.SITL))
        mission_state.start()
        mission_state.advance_leg()
        return mission_state.legs.target

    def approach(self, h, vehicle, corner, distances, speed=2.5):
        """Tick once at each distance south of the corner, heading north at ``speed`` (positions fresh), until the leg ends; the statuses."""
        statuses = []
        for distance in distances:
            vehicle.set(vehicle__position=at(*destination(corner.lat, corner.lon, 180.0, distance), t=h.clock.now(), vn=speed))
            statuses.append(h.tick())
            if statuses[-1] == Status.SUCCESS:
                break
        return statuses

    def driven(self, h, vehicle, corner, params, start_m=20.0, ticks=200):
        """The vehicle driven as the autopilot drives it (following the shaped target toward the corner, from rest ``start_m``
        south of it), a tick each 0.1 s, until the leg ends: (distance, status, node's feedback, (lat, lon)) each tick."""
        motion = RoverMotion.from_params(params)
        estimate = TargetEstimate(motion, motion.speed_m_s, destination(corner.lat, corner.lon, 180.0, start_m), h.clock.now())
        estimate.start(estimate.origin, (0.0, 0.0), h.clock.now())
        rows = []
        for _ in range(ticks):
            estimate.advance((corner.lat, corner.lon), h.clock.now())
            (n, e), (vn, ve) = estimate.target.pos, estimate.target.vel
            lat, lon = estimate.origin[0] + n / 111_319.49, estimate.origin[1] + e / (111_319.49 * math.cos(math.radians(estimate.origin[0])))
            vehicle.set(vehicle__position=at(lat, lon, t=h.clock.now(), vn=vn, ve=ve))
            status = h.tick()
            rows.append((geo.distance(lat, lon, corner.lat, corner.lon), status, h.root.feedback_message, (lat, lon)))
            if status == Status.SUCCESS:
                break
        return rows

    def test_a_corner_is_driven_through_once_the_swing_cuts_it_no_more_than_auto(self, harness, vehicle, corner):
        node = GoTo(1.5, 60.0, look_ahead=True)
        rows = self.driven(harness(node), vehicle, corner, self.SITL)
        distance, status, feedback, here = rows[-1]
        assert status == Status.SUCCESS and 3.0 <= distance <= 8.0  # well before the acceptance radius (1.5 m): no stop
        geometry = node.corner(at(corner.lat, corner.lon))
        assert geometry is not None and geometry.turn_rad == pytest.approx(math.pi / 2, abs=0.01)
        assert geometry.outbound_m == pytest.approx(20.0, abs=0.1)
        assert feedback.startswith(f"leg 2/4: driven through ({distance:.1f} m out; the swing cuts the corner by ")
        assert feedback.endswith(f"AUTO by {geometry.auto_cut_m:.1f} m)")
        cut = float(feedback.split("cuts the corner by ")[1].split(" m")[0])
        assert cut <= CUT_SHARE * geometry.auto_cut_m + 0.05  # (rounded to 0.1 m in the message)
        # the shaped target GoTo follows is the autopilot's: here, exactly where the vehicle was driven
        assert node._estimate is not None and node._estimate.off_by_m(here) < 0.01

    def test_the_vehicle_s_own_parameters_decide_and_the_firmware_s_defaults_stand_in(self, harness, vehicle, corner):
        sitl = self.driven(harness(GoTo(1.5, 60.0, look_ahead=True)), vehicle, corner, self.SITL)[-1][0]
        vehicle.set(vehicle__params={})  # the vehicle never told them: WP_SPEED 2, WP_RADIUS 2, so AUTO cuts only 0.5 m
        defaults = self.driven(harness(GoTo(1.5, 60.0, look_ahead=True)), vehicle, corner, {})[-1][0]
        assert 1.5 < defaults < sitl

    def test_without_look_ahead_the_leg_ends_inside_the_acceptance_radius(self, harness, vehicle, corner):
        h = harness(GoTo(1.5, 60.0))
        assert self.approach(h, vehicle, corner, (5.0, 2.9, 1.6, 1.4)) == [Status.RUNNING] * 3 + [Status.SUCCESS]

    def test_an_autopilot_whose_driving_is_not_modelled_stops_at_every_waypoint(self, harness, vehicle, corner, autopilot):
        autopilot.adopt(mavlink.MAV_AUTOPILOT_PX4, mavlink.MAV_TYPE_GROUND_ROVER)
        assert autopilot.capabilities.motion_params == ()
        statuses = self.approach(harness(GoTo(1.5, 60.0, look_ahead=True)), vehicle, corner, (8.0, 5.0, 3.0, 1.6, 1.4))
        assert statuses == [Status.RUNNING] * 4 + [Status.SUCCESS]

    def test_a_skid_steered_rover_stops_where_it_would_pivot(self, harness, vehicle, corner):
        vehicle.set(vehicle__params={**self.SITL, "SERVO1_FUNCTION": 73.0, "SERVO3_FUNCTION": 74.0})  # ThrottleLeft, ThrottleRight
        statuses = self.approach(harness(GoTo(1.5, 60.0, look_ahead=True)), vehicle, corner, (8.0, 5.0, 3.0, 1.6, 1.4))
        assert statuses == [Status.RUNNING] * 4 + [Status.SUCCESS]  # 90° is more than WP_PIVOT_ANGLE (60°): a pivot, as in AUTO

    def test_straight_on_is_driven_through_as_soon_as_it_is_worth_predicting(self, harness, vehicle, corner, mission_state):
        waypoints = list(mission_state.legs.route.waypoints)
        straight = waypoints[2].model_copy(update={"lat": corner.lat + 0.0003, "lon": corner.lon})
        mission_state.set_route([waypoints[0], corner, straight, waypoints[3]], "test: straight on")
        rows = self.driven(harness(GoTo(1.5, 60.0, look_ahead=True)), vehicle, corner, self.SITL)
        assert rows[-1][1] == Status.SUCCESS and rows[-1][0] > 6.0  # no corner to cut

    def test_the_last_leg_stops(self, harness, vehicle, mission_state):
        mission_state.start()
        for _ in range(3):
            mission_state.advance_leg()
        last = mission_state.legs.target
        vehicle.set(vehicle__params=dict(self.SITL))
        assert self.approach(harness(GoTo(1.5, 60.0, look_ahead=True)), vehicle, last, (6.0, 1.6, 1.4)) == [Status.RUNNING] * 2 + [Status.SUCCESS]

    def test_a_sample_point_stops(self, harness, vehicle, mission_state, square_mission):
        waypoints = list(square_mission.waypoints)
        waypoints[1] = waypoints[1].model_copy(update={"sample": True})
        mission_state.upload(square_mission.model_copy(update={"tree": "goto_sample", "waypoints": waypoints}))
        mission_state.start()
        mission_state.advance_leg()
        vehicle.set(vehicle__params=dict(self.SITL))
        statuses = self.approach(harness(GoTo(1.5, 60.0, look_ahead=True)), vehicle, waypoints[1], (6.0, 1.6, 1.4))
        assert statuses == [Status.RUNNING] * 2 + [Status.SUCCESS]

    def test_the_next_target_goes_out_on_the_tick_after(self, harness, vehicle, corner, mission_state):
        # ForEachLeg advances on the SUCCESS; the next leg's GoTo sends its waypoint at its first tick
        from executive.behaviours import ForEachLeg

        h = harness(ForEachLeg(GoTo(1.5, 60.0, look_ahead=True)))
        self.approach(h, vehicle, corner, (10.0,))
        h.link.take()
        for distance in (8.0, 6.0, 5.0, 4.0, 3.0, 2.0, 1.4):
            self.approach(h, vehicle, corner, (distance,))
            if mission_state.legs.leg_index == 2:
                break
        assert mission_state.legs.leg_index == 2
        h.tick()
        (sent,) = h.link.take("SET_POSITION_TARGET_GLOBAL_INT")
        following = mission_state.legs.target
        assert (sent.lat_int, sent.lon_int) == (round(following.lat * 1e7), round(following.lon * 1e7))
