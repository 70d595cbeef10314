"""Control laws of lead-through.

Orchestration, feed-forward, dither, admittance, calibration, constraints, tracking, replay.
"""
