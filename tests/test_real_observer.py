"""The observer and the payload estimate on real logs of a UR10e and a Panda (skip without)."""

import warnings

import numpy as np
import pytest

import leadthrough as lt
from leadthrough.estimation.log_observer import false_alarm_table, observe_log, run_detector
from realdata import REALDATA, needs_realdata

pytestmark = needs_realdata


@pytest.fixture(scope="module")
def ur10e():
    """The nominal UR10e (its assumed-drive-data warning silenced)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return lt.robots.ur10e()


def read(relative, robot):
    """A UR10e log of the shared folder."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return lt.read_log(REALDATA / "ur10e" / relative, robot=robot)


def test_at_rest_no_contact_rare_exceedance_and_a_useful_std(ur10e):
    """p1…p10 (99 s at rest): no contact, |τ̂| > 2 std < 1 %, std < 8× the RMS error per joint.

    At rest the estimate is the held arm's torque balance ``G(q) − K·i`` (``log_observer``):
    its RMS is the model's error there, no more; on the shoulder that is the nominal URDF's
    (10.4 Nm; its gravity is 9.1 Nm RMS off the published identification at these poses).
    """
    observed = [observe_log(read(f"validation/ur-20_01_17-p{k}.csv", ur10e), ur10e)
                for k in range(1, 11)]  # fmt: skip
    assert all(run_detector(o) == [] for o in observed)
    table = false_alarm_table(observed)
    assert np.all(table["exceed"] < 0.01), table["exceed"]
    assert np.all(table["z_rms"] > 0.125), table["z_rms"]
    dynamics = lt.Dynamics(ur10e)
    balance = np.concatenate([[dynamics.gravity(q) for q in o.q] - o.tau for o in observed])
    assert np.all(table["rms"] <= np.sqrt(np.mean(balance**2, axis=0)) + 0.2), table["rms"]
    assert np.all(table["rms"][[0, 2, 3, 4, 5]] < [4.0, 4.0, 1.5, 2.0, 1.5]), table["rms"]


def test_free_motion_rare_exceedance_and_a_useful_std(ur10e):
    """Validation runs in free motion: |τ̂| > 2 std < 1 %, std < 4× the RMS error per joint."""
    files = ["validation/ur-20_01_17-ptp_10_points.csv", "validation/collision_free.csv"]
    table = false_alarm_table([observe_log(read(f, ur10e), ur10e) for f in files])
    assert np.all(table["exceed"] < 0.01), table["exceed"]
    assert np.all(table["z_rms"] > 0.25), table["z_rms"]


def test_panda_on_its_torque_sensors_reads_near_zero_in_free_motion():
    """Panda excitation run, sensor torques: RMS τ̂_ext ≤ 3.5 Nm (≤ 20 % of the torque's RMS)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = lt.robots.panda()
    log = lt.read_log(REALDATA / "panda_gaz2019")
    observed = observe_log(log, robot)
    table = false_alarm_table([observed])
    assert np.all(table["rms"] < 3.5), table["rms"]
    assert np.all(table["rms"] < 0.2 * np.sqrt(np.mean(log.tau**2, axis=0)) + 0.5)
    assert run_detector(observed) == []


def head(log, seconds):
    """The first ``seconds`` of a log (keeps the tests fast)."""
    keep = log.t < log.t[0] + seconds
    return lt.JointLog(log.t[keep], log.q[keep], log.qd[keep], tau=log.tau[keep])


def test_unloaded_runs_read_no_payload(ur10e):
    """Two unloaded runs of other motions (25 s): one as unloaded= of the other, |m| < 0.1 kg."""
    first = head(read("identification/ur-20_02_12-50sec_12harm.csv", ur10e), 25.0)
    second = head(read("identification/ur-20_02_19_14harm50sec.csv", ur10e), 25.0)
    alone = lt.estimate_payload(first, ur10e)
    assert abs(alone.mass) <= 3 * alone.mass_std, alone  # the nominal model's phantom, covered
    paired = lt.estimate_payload(first, ur10e, unloaded=[second])
    assert abs(paired.mass) < 0.1, paired
    assert abs(paired.mass) <= 3 * paired.mass_std, paired


def test_an_identified_models_friction_noise_hides_pushes_that_the_nominal_noise_shows(ur10e):
    """link4.csv, the model identified on the excitation runs (README *With the identified model*).

    Its own friction noise σ (the currents' scatter at 100 Hz, 2.5 / 3.5 / 1.4 Nm on joints
    1–3) slows the thesis' observer (``Q_m = σ²``) so that none of the three pushes is
    detected; with the nominal σ the same model finds all three, the elbow's and the two
    stops, with joint 1's peak within 25 % of the nominal model's. When σ is read at the
    log's rate instead, the first half fails: update the README.
    """
    from dataclasses import replace

    from leadthrough.experiments.real_dynamics import ur10e_dynamics_study
    from leadthrough.friction.model import FrictionModel

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        identified = ur10e_dynamics_study(REALDATA).identified
    own = FrictionModel.from_robot(identified)
    nominal_noise = replace(own, noise_std=FrictionModel.from_robot(ur10e).noise_std)
    assert np.all(own.noise_std[:3] > 4.0 * nominal_noise.noise_std[:3])
    log = read("pushes/link4.csv", identified)
    assert lt.detect_contacts(log, identified, own) == []
    found = lt.detect_contacts(log, identified, nominal_noise)
    reference = lt.detect_contacts(read("pushes/link4.csv", ur10e), ur10e, None)
    assert len(found) == len(reference) == 3
    for event, nominal in zip(found, reference, strict=True):
        assert event.start < nominal.end and nominal.start < event.end  # the same push
        assert event.peak[0] == pytest.approx(nominal.peak[0], rel=0.25)
