"""The calibration-drift benchmark's helpers (benchmarks/calibration_drift.py)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import numpy as np

import calibration_drift
import leadthrough as lt
from leadthrough.twin.simulator import DigitalTwin


def test_each_judged_calibration_reports_its_largest_drift_ratio(tmp_path):
    """An untouched YuMi calibrates, its ratio recorded far below the limit; a figure is drawn."""
    yumi = lt.robots.yumi()
    with calibration_drift.largest_ratios() as ratios:
        ratio, accepted = calibration_drift.calibrate(yumi, DigitalTwin(yumi), ratios)
    assert accepted and 0.0 <= ratio < 0.1 * lt.LeadThroughParameters().calibration.max_drift
    assert ratios == []  # taken by calibrate
    runs = [calibration_drift.Run("nobody touching", "a", ratio, True),
            calibration_drift.Run("a hand at once", "b", 1.2, False),
            calibration_drift.Run("a hand at once", "c", np.nan, False)]  # fmt: skip
    out = tmp_path / "drift.png"
    calibration_drift.plot(runs, 0.25, out)
    assert out.stat().st_size > 1000
