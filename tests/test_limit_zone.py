"""The Coulomb compensation fades before the joint limits (friction.compensation.LimitZone)."""

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.control import lead_through
from leadthrough.errors import ParameterError
from leadthrough.experiments import guiding
from leadthrough.friction.compensation import CoulombCompensation, LimitZone

LOW, HIGH = np.array([-1.0, -np.inf]), np.array([2.0, np.inf])


@pytest.mark.parametrize(
    ("q", "torque", "share"),
    [
        (-0.5, -1.0, 1.0),  # two widths (0.5) from the lower limit: whole
        (-0.75, -1.0, 0.0),  # one width: none
        (-0.625, -1.0, 0.5),  # between: linear
        (-0.9, 1.0, 1.0),  # away from the lower limit: whole, however close
        (1.75, 1.0, 0.0),  # towards the upper limit, one width from it
        (1.75, -1.0, 1.0),
        (-2.0, -1.0, 0.0),  # beyond the limit
    ],
)
def test_the_share_fades_towards_the_limit_the_torque_pushes_to(q, torque, share):
    """Whole from two zone widths, none within one, linear between; only towards it."""
    zone = LimitZone(LOW, HIGH, 0.25)
    got = zone.share(np.array([q, q]), np.array([torque, torque]))
    assert got[0] == pytest.approx(share)
    assert got[1] == 1.0  # a joint without limits


def test_a_nan_reading_gives_nan_and_a_zone_must_have_a_width():
    """NaN in, NaN out (the supervisor stops on it); a width ≤ 0 is refused."""
    share = LimitZone(LOW, HIGH, 0.2).share(np.array([np.nan, 0.0]), np.array([1.0, 1.0]))
    assert np.isnan(share[0]) and share[1] == 1.0
    with pytest.raises(ParameterError, match="width"):
        LimitZone(LOW, HIGH, 0.0)


def test_the_compensation_leaves_a_joint_sliding_into_the_zone_to_its_friction():
    """Sliding towards the limit within a zone width of it: nothing; away from it: ε τ_C."""
    robot = lt.robots.yumi()
    friction = lt.FrictionModel.from_robot(robot)
    limits = LimitZone(robot.q_min, robot.q_max, 0.2)
    q = robot.q_min + 0.15
    towards = CoulombCompensation(friction, limits=limits).step(np.full(7, -0.5), q)
    away = CoulombCompensation(friction, limits=limits).step(np.full(7, 0.5), q)
    free = CoulombCompensation(friction).step(np.full(7, 0.5), q)
    np.testing.assert_array_equal(towards, 0.0)
    np.testing.assert_allclose(away, free)
    assert np.all(free > 0.0)


def _closest_approach(factory: guiding.ControllerFactory) -> float:
    """How near joint 6 comes to its limit [rad] on lugre #5's stiff upward line, active."""
    robot = lt.robots.yumi()
    case = guiding.Case("lugre", 5, "stiff", "upwards")
    path = guiding.case_path(robot, case.path)
    held, _ = guiding._run(robot, case, "active", factory, np.inf, path.duration + guiding.HOLD)
    angle = held.q_true[:, 5]
    return float(np.min(np.minimum(angle - robot.q_min[5], robot.q_max[5] - angle)))


def test_a_wrist_the_hand_turns_stops_where_its_references_do(monkeypatch):
    """What the fade prevents: a wrist compensated up to its limit runs deep into the zone.

    On lugre #5's stiff upward line the hand's point grip turns joint 6 with about what
    the compensation leaves of its friction (turning it does not take the push away), and
    it slides towards its lower limit at up to 2 rad/s. The admittance's references stop
    ``limit_zone`` (0.2 rad) short of the limit; compensated all the way, the joint ran on
    to 0.09 rad from it, where the tracking braked it in stick-slip (the worst vibration
    of that case, design log). With the fade its own friction stops it at the zone.
    """
    # the fade stops it in the zone's outer quarter; compensated up to the limit it runs past
    outer_quarter = 0.75 * lt.LeadThroughParameters().limit_zone
    assert _closest_approach(guiding.default_factory) > outer_quarter

    zoned = lead_through.PassiveFeedForward

    def unzoned(*args, **kwargs):  # the controller's feed-forward without the fade
        return zoned(*args, **{**kwargs, "limit_zone": None})

    monkeypatch.setattr(lead_through, "PassiveFeedForward", unzoned)
    assert _closest_approach(guiding.default_factory) < outer_quarter
