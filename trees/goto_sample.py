"""The ASV go-to-and-sample node (seed system 1): accept the go-to, drive the path under guards, sample at the sample points.

::

    Mission: while PAUSED, hold the vehicle (the leg is kept); otherwise run:
    ├── Within reach: wait for the EKF's position; every point within 5 km? (else rejected before arming or any mode change)
    ├── Pre-flight: wait for the EKF, arm (or wait for the operator to arm)
    ├── Ready: auto_arm: set LOITER (as the boat's operator would); else nothing: the operator had to
    ├── Accept the go-to (else rejected, nothing sent that moves the vehicle): armed? in LOITER?
    ├── Go-to (reactive: every check every tick)
    │   ├── RC in auto? else its failsafe (rc_takeover; the seed's default: leave, the go-to fails with the reason)
    │   ├── EKF ok, else wait in MANUAL (ekf_loss; the seed's default; selector with memory: a recovery started is finished)
    │   │   ├── EKF ok?
    │   │   ├── Disarmed (the pilot has it)? -> the guards below wait, hands off
    │   │   └── Wait in MANUAL: set MANUAL, disarm, wait until the EKF is ok, re-arm
    │   └── Guarded path or hold (reactive selector)
    │       ├── Guarded path: link alive? armed? (disarmed = the RC took over), and the failsafe guards -> for each point:
    │       │   ├── Go to the point: GUIDED (else set it), go to (within 1.5 m; over 60 s fails; a point
    │       │   │   that is neither a sample point nor the last is driven through toward the next);
    │       │   │   drive: auto: the horizon on the autopilot (a sample point a NAV_LOITER_UNLIM stop), its
    │       │   │   mission at the leg, AUTO, the leg followed (a sample point or the last within 1.5 m)
    │       │   └── Sample if due: nothing to sample here? or: LOITER (else set it), sample (recorded)
    │       └── Wait for guards: the failsafe of the failing guard (mission failsafe: policy)
    └── Hold at the end (LOITER for a boat)

With ``drive: auto`` the sample is taken as in GUIDED (the hold mode set, then the sampler); the next
leg sets the autopilot's mission to its item (MISSION_SET_CURRENT) and AUTO again, so the route goes on
only when the executive has the sample.

"LOITER" before the go-to is the vehicle's hold, the mode the executive itself holds it in (a boat's
LOITER, a rover's HOLD), so a go-to resumed after a pause (accepted again) starts from there.
Without auto_arm the operator's arming is the go-to request: the vehicle must be in its hold by
then, or the go-to is rejected.

An RC change or a guard failing during a sample stops the Sample action, which cancels the
sampler: nothing is recorded, and the sample is taken again when the leg resumes (a sample already
recorded is never taken again). An operator's cancel (abort) ends the run: the runtime stops the
tree, which cancels a sample in progress the same way.

The seed's two rules are this tree's failsafe defaults (rc_takeover: wait, abort; ekf_loss: disarm,
resume); a mission that sets another policy for either gets the generic failsafe instead (the EKF
then guarded with the path).
"""

from __future__ import annotations

import py_trees

from executive.behaviours import (
    Arm,
    Armed,
    Disarm,
    EkfOk,
    ForEachLeg,
    GoTo,
    LinkAlive,
    ModeIs,
    NothingToSample,
    Sample,
    SetMode,
    WaitUntil,
    rc_auto_mode,
)
from executive.behaviours.failsafe import FailsafeNote
from executive.mission.declaration import TreeDeclaration, vehicle_profile
from executive.mission.model import Mission, SamplingOptions
from executive.mission.rules import failsafe_policy
from executive.trees.parts import ARM_RETRY_S, auto_leg, checked, failsafe_guarded, mission_root, preflight, safe_mode, within_reach


def _sample_hold_mode(mission: Mission) -> str:
    """The mode a sample point is held in (sampling.hold_mode, LOITER by default)."""
    return (mission.sampling or SamplingOptions()).hold_mode.upper()


def accept(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The go-to's acceptance checks on the operator's part, once the vehicle is ready: a failure rejects it (the mission fails with the reason).

    The distance rule is checked before, by :func:`within_reach`: nothing is armed or set for a go-to out of reach.
    """
    return py_trees.composites.Sequence("Accept the go-to", memory=False, children=[Armed(), ModeIs(safe_mode(mission))])


def reach(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The seed's 5 km rule (``limits.max_goal_distance_m``), from the vehicle's position, before anything is sent."""
    limit = mission.limits.max_goal_distance_m
    return within_reach(mission, "Within reach", check_name=f"Every point within {limit:g} m?")


def ekf_or_wait_in_manual(mission: Mission) -> py_trees.behaviour.Behaviour:
    """EKF ok, else (the vehicle armed) MANUAL, disarmed until the EKF recovers, then re-armed.

    A selector with memory: once started, the recovery runs to its end (it disarms the vehicle
    itself, which must not read as a pilot's take-over). A vehicle already disarmed belongs to the
    pilot: it is left alone, and the guarded path waits for it to be armed again.
    """
    manual, limit = vehicle_profile(mission.vehicle).manual_mode, failsafe_policy(mission)["ekf_loss"].timeout_s
    ekf = EkfOk()
    ekf.resume_after_s = 0.0  # its recovery is the wait branch's to judge (a sane EKF for EkfOk.resume_after_s)
    wait = py_trees.composites.Sequence(
        f"Wait in {manual}",
        memory=True,
        children=[
            FailsafeNote("ekf_loss", f"disarm in {manual}, resume when it recovers (within {limit:g} s)", guard=ekf),
            SetMode(manual),
            Disarm(),
            WaitUntil(EkfOk().awaiting_recovery(), limit, name="Wait until the EKF recovers"),
            WaitUntil(Arm(), limit, name="Re-arm", retry_s=ARM_RETRY_S),
            FailsafeNote("ekf_loss", "recovered, re-armed -> resume"),
        ],
    )
    pilot_has_it = py_trees.decorators.Inverter(name="Disarmed (the pilot has it)?", child=Armed())
    return py_trees.composites.Selector(f"EKF ok, else wait in {manual}", memory=True, children=[ekf, pilot_has_it, wait])


def go_to_point(mission: Mission) -> py_trees.behaviour.Behaviour:
    """To the current point: GUIDED (else set it), go to; drive: auto: the leg in AUTO (:func:`~executive.trees.parts.auto_leg`)."""
    if mission.drive == "auto":
        return auto_leg(mission)
    limits, guided = mission.limits, vehicle_profile(mission.vehicle).guided_mode
    return py_trees.composites.Sequence(
        "Go to the point",
        memory=False,  # the mode is checked every tick (someone may change it): set again when it is not GUIDED
        children=[
            SetMode(guided, name=f"{guided} (else set it)", confirm_by_ack=True),  # moving a tick after the ack, not at the next heartbeat
            GoTo(limits.acceptance_radius_m, limits.leg_timeout_s, look_ahead=True),
        ],
    )


def point(mission: Mission) -> py_trees.behaviour.Behaviour:
    """One point of the path: go there; at a sample point not sampled yet, hold in LOITER and sample."""
    hold, go = _sample_hold_mode(mission), go_to_point(mission)
    sample = py_trees.composites.Sequence("Sample here", memory=False, children=[SetMode(hold, name=f"{hold} (else set it)"), Sample()])
    due = py_trees.composites.Selector("Sample if due", memory=False, children=[NothingToSample(), sample])
    return py_trees.composites.Sequence("Point", memory=True, children=[go, due])


#: The ASV seed: a rover or a boat, its ``sampling:`` options, RC channel 5 high arms it (where the file says nothing else);
#: an EKF loss disarms it in MANUAL until the EKF recovers (then re-armed), and the RC leaving auto ends the go-to.
DECLARATION = TreeDeclaration(
    doc="the ASV go-to-and-sample node: drive the path under guards, sample at the sample points",
    vehicles=frozenset({"rover", "boat"}),
    auto_drive={"rover": "ArduRover", "boat": "ArduRover"},
    section="sampling",
    rc_defaults={"arm_channel": 5},
    failsafes={"ekf_loss": ("disarm", "resume"), "rc_takeover": ("wait", "abort")},
    samples=True,
    timed_legs=True,
)


def build(mission: Mission) -> py_trees.behaviour.Behaviour:
    """The tree for a ``tree: goto_sample`` mission."""
    ekf_loss = failsafe_policy(mission)["ekf_loss"]
    seed_ekf_rule = (ekf_loss.reaction, ekf_loss.recovery) == ("disarm", "resume")
    path = failsafe_guarded(ForEachLeg(point(mission)), [LinkAlive(), Armed(), *([] if seed_ekf_rule else [EkfOk()])], mission, name="Guarded path")
    leave = failsafe_policy(mission)["rc_takeover"].recovery == "abort"
    rc = checked(rc_auto_mode(mission.rc, "RC in auto? (else leave)" if leave else "RC in auto?"), mission)
    goto = py_trees.composites.Sequence("Go-to", memory=False, children=[rc, *([ekf_or_wait_in_manual(mission)] if seed_ekf_rule else []), path])
    steps: list[py_trees.behaviour.Behaviour] = [reach(mission), preflight(mission)]
    if mission.auto_arm:
        steps.append(SetMode(safe_mode(mission), name=f"Ready: set {safe_mode(mission)}"))
    steps += [accept(mission), goto, SetMode(safe_mode(mission), name="Hold at the end")]
    return mission_root(mission, *steps)
