"""Payload mass and centre of mass from joint torques: regressor, twin runs, bad input."""

import warnings

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.errors import ParameterError
from leadthrough.estimation.log_observer import LogInputError
from leadthrough.estimation.payload import PayloadError, PayloadParameters, _PayloadRegressor
from leadthrough.experiments.payload_runs import record
from leadthrough.twin.mjcf import Payload
from leadthrough.twin.model_error import ModelError
from leadthrough.twin.sensors import SensorModel

#: The plant differs from the description: link masses ±5 %, COMs ±5 mm (seeded).
MODEL_ERROR = ModelError(mass_error=0.05, com_error=0.005)
AMPLITUDE = 0.4  # [rad] of the Fourier excitation's first harmonic
#: The twin measures the torque its drives apply: no drive-gain error to allow for.
EXACT_GAINS = PayloadParameters(gain_error=0.0)
PAYLOADS = [Payload(0.5, (0.03, -0.02, 0.04)), Payload(1.2, (0.0, 0.0, 0.1)),
            Payload(2.0, (-0.04, 0.02, 0.06)), Payload(3.0, (0.01, 0.05, 0.02))]  # fmt: skip


@pytest.fixture(scope="module")
def empty(ur10e):
    """The twin's run of the excitation without payload."""
    return record(ur10e, None, MODEL_ERROR, seed=1, amplitude=AMPLITUDE)


@pytest.fixture(scope="module")
def loaded(ur10e):
    """The same excitation with each payload of PAYLOADS."""
    return [record(ur10e, p, MODEL_ERROR, seed=1, amplitude=AMPLITUDE) for p in PAYLOADS]


@pytest.mark.parametrize("name", ["ur10e", "panda", "yumi"])
def test_regressor_matches_inverse_dynamics_with_a_payload(name):
    """Y_p θ plus the point-mass inertia term is τ(with payload) − τ(without), any state."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = lt.robots.load(name)
    regressor = _PayloadRegressor(robot)
    rng = np.random.default_rng(0)
    mass, com = 2.3, np.array([0.04, -0.03, 0.09])
    carrying = lt.Dynamics(robot.with_payload(mass, com))
    theta = np.concatenate([[mass], mass * com])
    for _ in range(5):
        q, qd, qdd = rng.uniform(-2, 2, (3, robot.n_joints))
        payload, inertia = regressor.columns(q, qd, qdd)
        added = carrying.inverse_dynamics(q, qd, qdd) - regressor.dynamics.inverse_dynamics(
            q, qd, qdd
        )
        predicted = payload @ theta + inertia @ regressor.point_inertia_parameters(theta)
        np.testing.assert_allclose(predicted, added, atol=1e-9)


@pytest.mark.parametrize("index", range(len(PAYLOADS)))
def test_unloaded_runs_cancel_the_model_error(ur10e, empty, loaded, index):
    """With runs of the same motion unloaded: mass within 0.1 kg, std < 0.1 kg, truth ±3 std."""
    truth = PAYLOADS[index]
    estimate = lt.estimate_payload(loaded[index], ur10e, unloaded=[empty], parameters=EXACT_GAINS)
    assert abs(estimate.mass - truth.mass) < 0.1, estimate
    assert estimate.mass_std < 0.1, estimate
    assert abs(estimate.mass - truth.mass) <= 3 * estimate.mass_std, estimate
    error = np.abs(estimate.com - truth.com)
    assert np.all(error < 0.02), (estimate.com, truth.com)  # [m]
    assert np.all(error <= 3 * estimate.com_std + 1e-3), (error, estimate.com_std)
    assert np.all(estimate.com_std < 0.05), estimate.com_std


def test_nominal_model_alone_std_covers_its_error(ur10e, loaded):
    """Without unloaded runs the model error biases the mass; the std says so (±3 std), < 0.3 kg."""
    for truth, log in zip(PAYLOADS, loaded, strict=True):
        estimate = lt.estimate_payload(log, ur10e, parameters=EXACT_GAINS)
        assert abs(estimate.mass - truth.mass) <= 3 * estimate.mass_std, (truth, estimate)
        assert estimate.mass_std < 0.3, estimate
        assert abs(estimate.mass - truth.mass) < 0.4, (truth, estimate)


def test_exact_model_reads_the_mass_without_unloaded_runs(ur10e):
    """When the description is the plant (no model error) the mass is within 0.1 kg."""
    truth = Payload(1.5, (0.0, 0.02, 0.05))
    log = record(ur10e, truth, ModelError(), seed=2, amplitude=AMPLITUDE)
    estimate = lt.estimate_payload([log], ur10e, parameters=EXACT_GAINS)
    assert abs(estimate.mass - truth.mass) < 0.1, estimate


def test_zero_payload_reads_zero_on_another_motion(ur10e, empty):
    """No payload, unloaded runs of a different motion: |m| < 0.1 kg and within ±3 std."""
    other = record(ur10e, None, MODEL_ERROR, seed=1, amplitude=AMPLITUDE, motion_seed=5)
    estimate = lt.estimate_payload(empty, ur10e, unloaded=other, parameters=EXACT_GAINS)
    assert abs(estimate.mass) < 0.1, estimate
    assert abs(estimate.mass) <= 3 * estimate.mass_std, estimate


def test_different_unloaded_motion_still_reads_the_mass(ur10e, loaded):
    """Unloaded runs of another motion: the 2 kg payload within 0.15 kg and ±3 std."""
    other = record(ur10e, None, MODEL_ERROR, seed=1, amplitude=AMPLITUDE, motion_seed=5)
    estimate = lt.estimate_payload(loaded[2], ur10e, unloaded=[other], parameters=EXACT_GAINS)
    assert abs(estimate.mass - 2.0) < 0.15, estimate
    assert abs(estimate.mass - 2.0) <= 3 * estimate.mass_std, estimate


def test_a_drive_gain_error_scales_the_mass_and_the_default_std_covers_it(ur10e):
    """Drive gains 8 % above nominal: the 2.5 kg payload reads ≈ 8 % low, within ±3 std."""
    truth = Payload(2.5, (0.0, 0.03, 0.06))
    sensors = SensorModel(torque_gain=(1.08,) * ur10e.n_joints)
    runs = [record(ur10e, p, MODEL_ERROR, seed=1, amplitude=AMPLITUDE, sensors=sensors)
            for p in (truth, None)]  # fmt: skip
    estimate = lt.estimate_payload(runs[0], ur10e, unloaded=runs[1])
    assert estimate.mass / truth.mass == pytest.approx(1 / 1.08, abs=0.03), estimate
    assert abs(estimate.mass - truth.mass) <= 3 * estimate.mass_std, estimate
    exact = lt.estimate_payload(runs[0], ur10e, unloaded=runs[1], parameters=EXACT_GAINS)
    assert abs(exact.mass - truth.mass) > 3 * exact.mass_std  # what gain_error is for


def test_bad_input_is_one_line_error(ur10e, empty):
    """No logs, too short, no torque, bad settings, one pose only: each a one-line error."""
    with pytest.raises(PayloadError, match="no logs"):
        lt.estimate_payload([], ur10e)
    short = lt.JointLog(empty.t[:20], empty.q[:20], empty.qd[:20], tau=empty.tau[:20])
    with pytest.raises(PayloadError, match="too short"):
        lt.estimate_payload(short, ur10e)
    bare = lt.JointLog(empty.t, empty.q, empty.qd, source="bare")
    with pytest.raises(LogInputError, match="bare"):
        lt.estimate_payload(bare, ur10e)
    with pytest.raises(ParameterError, match="model_error"):
        PayloadParameters(model_error=-1.0)
    still = lt.JointLog(empty.t, np.tile(empty.q[0], (empty.t.size, 1)),
                        np.zeros_like(empty.qd), tau=empty.tau)  # fmt: skip
    with pytest.raises(PayloadError, match="one pose"):  # m c not observable
        lt.estimate_payload(still, ur10e)
    # a static hold as a real arm logs it, its encoders flickering by 0.2 mrad: a real
    # UR10e hold read 91 m off the flange before (its offsets took the payload's torque)
    jitter = np.random.default_rng(0).uniform(-1e-4, 1e-4, still.q.shape)
    held = lt.JointLog(still.t, still.q + jitter, still.qd, tau=empty.tau, source="hold.csv")
    with pytest.raises(PayloadError, match=r"hold\.csv: the logs hold one pose"):
        lt.estimate_payload(held, ur10e)
