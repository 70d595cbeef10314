"""Start-up calibration: measure the model error before anyone guides the arm.

At rest the momentum observer cannot tell a model error from friction (friction holds
any torque up to breakaway), so a bias learned at rest is never certain. Sliding, it
can: friction is then known up to its level. So lead-through starts by moving every
joint a few mrad back and forth at a slow, constant-ish speed, nobody touching. With
``τ̂₊`` and ``τ̂₋`` the readings while a joint slides in the positive and negative
direction at the motion's pace, the torque the model misses there (SPEC §5:
``τ̂_ext = τ_ext + (G − G_true) + (τ_f − τ_f,true)``)::

    gravity error   ΔG   = (τ̂₊ + τ̂₋) / 2      (= G_model − G_true at q₀)
    Coulomb error   Δτ_C = (τ̂₊ − τ̂₋) / 2      (= τ_C,model − τ_C,true)

The motion slides every joint 15 mrad at 0.1 rad/s, above the Stribeck range of the
arms it must work on (Stribeck velocities up to 0.03 rad/s on the plants of
``benchmarks/guiding_quality.py``): slower, friction still falls with speed there, and a
joint held by a 4–6 Hz tracking loop sticks and jumps instead of sliding. At 5 mrad and
0.05 rad/s (before) the heavy joints moved in bursts of 40–60 ms, and the readings of
lugre #29's joint 4, stuck and jumping at 3× the pace, were its filtered velocity's edges
through the pace band (+0.22 → +0.06 Nm rising, −0.33 Nm falling, the same direction):
its level came out 16 % high and the released arm slid 1.5 rad, in passive mode too.

A reading is the momentum balance over each stretch a joint slides at pace
(:mod:`~leadthrough.estimation.momentum_balance`: kept one sample behind the robot, read
when the run is over): the generalized momentum from the encoders' central difference, the
torque the model misses as the slope of the momentum it does not explain.
Before, the readings were the momentum observer's estimate at each sample, fed the robot's
filtered velocity: its lag (~25 ms with the filter and the delay) turned the inertial
torque of the motion's reversals and of the tracking's ringing into readings, which
scattered 3–54 % of the level on the YuMi's plants (now 0–1 %), and on a Panda, whose
levels (0.15–0.36 Nm) are small beside its inertia, read ±1–2 Nm and refused 7 of 8
calibrations.

At the motion's pace means between a quarter of its speed and twice it. A light joint
whose stiction exceeds what the tracking builds up within the stroke sticks and then jumps,
for a few ms, at several times that speed, through the Stribeck curve, where friction is
above its Coulomb level; the observer lagged such a jump, and reading the jumps put the
gravity error of a wrist joint 0.09 Nm off, enough for the released arm to run 0.2 rad
(``tests/test_released_arm.py``, with the observer's readings of the time). A joint's Coulomb
level is measured only if it slid at pace for at least an eighth of the time the motion
drove it that way, each way (:data:`_MEASURED`): a handful of readings between a joint's
jumps is a sample of its stick-slip, not of its sliding, and an overstated level is what
the compensation and the active law trust as surely there. A joint that slid less keeps its
model's level, and its gravity, read from the readings it has, counts as not known (its
whole ``G`` uncertain, as without a calibration).

The readings come from the *measured* motor torque, the feed-forward acts through the
*commanded* one. Where the two differ by an offset of the measurement (a joint torque
sensor's zero, a current read outside the loop that drives the motor: an error the arm
never feels), the readings carry it as if gravity were off by it, and a gravity
correction taken from them would command it onto the arm. So the
calibration also averages ``τ_measured − τ_commanded`` over its run (the operator's push
does not enter it; the motion's back and forth averages out most of the drive's ripple,
whose rest, up to 0.014 Nm on the realistic twin's shoulder, joins the gravity error): that
:attr:`Calibration.torque_offset` is added back to the gravity error, which is then the
arm's, and taken off every later measurement (``LeadThrough``). With offsets of ±0.2 Nm
(``benchmarks/guiding_quality.py --plants torque_offset=-0.2,0.2``) the arm calibrated
without this ran away when released in 15 of the 28 LuGre cases in passive mode (8 in
active mode), up to 6.1 rad.

The gravity error is explained first by a payload (a mass ``m`` at ``c`` in the flange
frame, ``G_true = G_model + m · Y(q) + Y_h(q) · m c`` with ``Y = −J_vᵀ g`` the gravity
torque of one kilogram at the flange and ``Y_h = J_ωᵀ [g]× R`` that of its first moment),
fitted by weighted least squares and taken only where it stands out of the gravity error
the model may have anyway (:meth:`CalibrationRun.payload`, :meth:`CalibrationRun.payload_body`:
one pose shows the moment's two components across gravity, not the one along it), so that
it follows the arm to other poses; what remains is a bias at q₀. The Coulomb error
rescales the friction model. A level read at q₀ is known there to its readings' scatter,
and less well the farther the joint travels from q₀
(:meth:`Calibration.level_error`, :mod:`~leadthrough.friction.measured_level`).
Results outside plausible bounds mean someone touched the arm: the calibration is
refused (one line saying why) and the controller keeps its model. So is a run whose
encoders step more than the motion moves in two periods (:meth:`CalibrationRun.unresolved`):
its readings would be the encoders' counts.

Safety: the calibration moves no joint faster than ``max_speed`` (a few times its own
peak speed). A faster joint stops it at once: refused, the arm held against gravity.

Tracking: computed torque, ``τ = G + M(q) (q̈_ref + ω² e + 2ζω ė + ω³/4 ∫e) + τ_f``.
The full ``M(q)`` matters: per-joint gains ``m_ii ω²`` on a coupled arm give a loop
gain of ``ω² M⁻¹ diag(M)``, whose eigenvalues reach 3.9 on a Panda without rotor
inertia (2.5 on the YuMi) and push the crossover ~2× past what the one-period delay
allows: the Panda's wrist joints then ran away at 2.8 → 6.5 rad/s within 32 ms,
nobody touching. With ``M(q)`` every mode has the bandwidth ω.

That bandwidth is 4 Hz at 250 Hz, the replay's (:mod:`~leadthrough.control.tracking`),
whose loop, linearised with two periods of delay (the most of the plant family), keeps a
damping ratio of 0.20. The 6 Hz of before had −0.02 there: friction damps it on the
YuMi, but a Panda's levels are small beside its inertia, and on its dry #4 with two
periods of delay joint 3 rang up to 2.6× the motion's speed, read its level 1.7× the
truth, and the arm kept moving for 0.8 s after (``tests/test_calibration.py``). Slower,
where a joint's loop would grow with two periods of delay even so (its own viscous
friction does not damp it: a Panda's below 250 Hz), that joint tracks the state predicted
for when the command acts, one period after its sample (``predicted_state``; ``q``, ``q̇``
and ``e`` above are then those predicted, G and M taken there, and the reference one period
later): ``CalibrationParameters.predict``.

The package, one module per part:

- :mod:`.parameters`: :class:`CalibrationParameters`, the motion, its tracking and what
  it accepts;
- :mod:`.run`: :class:`CalibrationRun`, the motion at the pose the arm rests at, its
  readings and their judgement;
- :mod:`.result`: :class:`Calibration`, what it measured, and the model it gives.
"""

from leadthrough.control.calibration.parameters import (
    PAYLOAD_SHARE,
    PREDICTIONS,
    CalibrationParameters,
    calibration_gains,
)
from leadthrough.control.calibration.result import (
    Calibration,
    gravity_share,
    implausible_friction,
)
from leadthrough.control.calibration.run import CalibrationRun

__all__ = [
    "PAYLOAD_SHARE",
    "PREDICTIONS",
    "Calibration",
    "CalibrationParameters",
    "CalibrationRun",
    "calibration_gains",
    "gravity_share",
    "implausible_friction",
]
