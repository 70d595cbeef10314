"""The hand-impedance diagnosis (benchmarks/hand_impedance.py): its reading checked on the truth."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))

import hand_impedance
import leadthrough as lt
from leadthrough.experiments.guiding import HANDS


def test_the_true_torque_reads_the_hands_damping_and_none_for_its_forces_replayed(tmp_path):
    """The lock-in on the twin's true torque reads the hand's damping, and ~0 for its forces.

    The relaxed hand's 30 N s/m within the Hann window's bias; the same forces replayed
    without the impedance read less than a tenth of it.
    """
    readings = hand_impedance.read_case(
        lt.robots.yumi(), ("dry", 1, "relaxed", "sideways"), (15.0, 0.75), periods=4
    )
    truth = {r.source: r for r in readings if r.signal == "truth"}
    damping = HANDS["relaxed"].damping
    assert truth["hand"].windows >= 10 and truth["force"].windows >= 10
    assert 0.8 * damping <= truth["hand"].low <= truth["hand"].high <= 1.1 * damping
    assert abs(truth["force"].median) < 0.1 * damping
    # the probe moves the tool at its frequency by millimetres per second, in both runs
    assert all(0.003 < r.amplitude < 0.03 for r in readings)
    out = tmp_path / "impedance.png"
    hand_impedance.plot(readings, out)
    assert out.stat().st_size > 1000
