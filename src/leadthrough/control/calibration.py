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

The gravity error is explained first by a payload at the flange (a point mass ``m``,
``G_true = G_model + m · Y(q)`` with ``Y = −J_vᵀ g`` the gravity torque of one
kilogram at the flange), fitted by weighted least squares and taken only where it stands
out of the gravity error the model may have anyway (:meth:`CalibrationRun.payload`), so
that it follows the arm to other poses; what remains is a bias at q₀. The Coulomb error
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
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.control.tracking import (
    VERIFIED_PERIOD,
    decaying_damping,
    pd_gains,
    period_bandwidth,
    predicted_state,
)
from leadthrough.errors import ParameterError
from leadthrough.estimation.momentum_balance import MomentumBalance, stretch_readings
from leadthrough.friction.measured_level import MeasuredLevelError
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.trajectories import triangular_velocity
from leadthrough.validation import real

BoolArray = NDArray[np.bool_]

#: A joint faster than this fraction of the calibration speed slides [–].
_SLIDING = 0.25
#: A joint faster than this multiple of the calibration speed jumps out of stiction [–].
_JUMPING = 2.0
#: Paced sliding readings in each direction that show a joint slid (fewer in more than half
#: of the joints: the arm was held) [–].
_ENOUGH = 3
#: Share of the samples in which the motion drives a joint one way at pace that must be
#: paced readings of it, each way, for its Coulomb level to count as measured [–]. On the
#: 56 YuMi plants of seeds 1–28 (``benchmarks/guiding_quality.py``, 250 Hz: about 75 such
#: samples each way), the 33 joints read from fewer than 10 readings one way had their
#: levels 10–15 % off in the median, up to +29 %, and gravity errors up to half a level
#: off; from 10 readings on, 2–4 % in the median. Lugre #28's wrist, read from 3 and 6,
#: came out +20 % and 0.16 Nm off: the feed-forward ran the released arm, in passive mode
#: too, 0.9 rad into its soft limit.
_MEASURED = 0.125
#: A joint this many strokes off its calibration motion has been pushed [–].
_DISTURBED = 4.0
#: Smallest change of a joint's angle taken as a move [rad]: below any encoder's count,
#: above a float's rounding of the angles it reports.
_LEAST_STEP = 1e-12
#: How far from a whole number of counts a joint's moves may be and still be counts [–]:
#: an encoder's are whole to a float's rounding (angles through float32: ~1e-4 of a 1 mrad
#: count); a finer encoder's moves, or a jump's, are not, bar chance.
_WHOLE_COUNTS = 0.01


#: Heaviest payload a calibration may report by default, relative to the arm's moving mass
#: [–]: the largest rated payload over the arm's weight among today's collaborative arms
#: (UR16e 16 / 33 kg, LBR iiwa 14 14 / 30 kg, Kinova Gen3 4 / 8.2 kg; the UR10e 0.37, the
#: Panda 0.17), taken of the links' mass, which is a little less than the weight. It is a
#: plausibility check, not the arm's rating: on a Panda (rated 3 kg) it allows 8.4 kg, so
#: someone leaning on it by up to ~80 N is read as a payload; set ``max_payload`` to the
#: rated payload where it is known.
PAYLOAD_SHARE = 0.5
#: ``CalibrationParameters.predict``'s settings.
PREDICTIONS = ("needed", "always", "never")


@dataclass(frozen=True)
class CalibrationParameters:
    """The calibration motion and what it accepts.

    Attributes:
        stroke: How far each joint moves from where it rests, and back [rad].
        speed: Peak joint speed [rad/s]; readings between a quarter of it and twice it
            count as sliding at the motion's pace (faster, a joint is jumping).
        cycles: Back-and-forth cycles [–].
        settle_time: Rest before the motion, for the observer to settle [s].
        bandwidth: Bandwidth of the joint tracking at 250 Hz and faster [Hz]: soft enough
            that the loop, with two periods of delay and a filtered velocity, still decays
            (damping ratio 0.20 at 4 Hz, −0.02 at 6 Hz, the default before, which rang a
            Panda's joint 3 to 2.6× the motion's speed), stiff enough that the lightest
            joint breaks away within a fraction of the stroke: with 10 mrad, 4 Hz left one
            of the 32 dry YuMi plants of ``benchmarks/guiding_quality.py`` refused; with the
            stroke grown as the bandwidth fell (15 mrad: the motion as slow beside its
            loop), all 64 of seeds 1–32 calibrate with one or two periods of delay. At a
            slower rate the loop's delay allows less (:meth:`at_period`).
        slow_rate_damping: Least damping ratio of the tracking loop, linearised with one
            period of delay, below 250 Hz [–] (:meth:`at_period`). 0.14 is what the 6 Hz
            loop had at 250 Hz (0.138), the stiffest the YuMi plants' wrists were seen to
            need there: at 125 and 100 Hz (3.95 and 3.41 Hz) every plant of seeds 1–8 (125
            Hz) and 1–4 (100 Hz) calibrated tracking the samples, a loop that grows with two
            periods of delay (ζ −0.07 and −0.08; ``predict`` makes it decay). One that
            decays with two unpredicted (what 0.36 gives: 2.8 and 2.44 Hz,
            the 4 Hz loop's margin at 250 Hz) lets stiction throw the wrist of dry #1 and #4
            four strokes off at 100 Hz (refused), and guides heavier at 125 Hz (seeds 1–4:
            effort 0.78 → 0.82).
        max_speed: Fastest a joint may move during the calibration [rad/s]; faster,
            the calibration stops (refused) and the arm is held against gravity. 20× the
            motion's speed, between what a stick-slip jump reaches and a runaway: a light
            wrist joint breaking out of stiction jumps for some 50 ms and a few tens of mrad,
            up to 1.35 rad/s on the dry YuMi plants of seeds 1–32 of
            ``benchmarks/guiding_quality.py`` with two periods of delay (0.94 with the 6 Hz
            loop of before; ``calibration_accuracy.py --seeds 32 --delay 2``; 1.0–1.2 rad/s,
            measured with that loop, on wider
            families: stiction up to 2×, three periods of delay, levels ±25 % along the
            travel), while the Panda's runaway went 2.8 → 6.5 rad/s within 32 ms. At 1 rad/s
            (before) dry #1 was 6 % from a refused calibration, and refused on the wider
            families. A joint that moves far trips the 4-stroke check at any speed.
        max_payload: Heaviest payload the calibration may report [kg]; None: the arm's
            own moving mass times :data:`PAYLOAD_SHARE` (:meth:`payload_limit`), since a
            fixed number is one arm's: 2 kg is four times the YuMi's rated payload and a
            sixth of a UR10e's, whose calibration with a tool it refused.
        max_friction_change: Largest change of a Coulomb level it may report, a factor
            either way [–]: a level measured outside [1 / (1 + c), 1 + c] times the model's
            refuses the calibration (:func:`implausible_friction`). The errors a measured
            level must pass multiply (the level's own, its position dependence, the drive
            gain: 0.8 × 0.85 × 0.9 ≈ 0.61 to 1.2 × 1.15 / 0.9 ≈ 1.53 on the plants of
            ``benchmarks/guiding_quality.py``), so the band is symmetric in the ratio's
            logarithm. 0.85 passes them with room for the reading's own error (±10 %) and
            refused the Panda's readings of its tracking's ringing through the observer's
            lag (0.16–0.42×, before the momentum balance). With 0.75 (before), dry
            #25's joint 1, 0.60× the model's, read 0.57× and was refused; with ±0.5, 2 of the
            4 dry plants of seeds 9–12 (1.50×, 1.61×), and one of them, guided uncalibrated,
            ran away 112 mrad when released.
        friction_accuracy: Relative error of a measured Coulomb level away from the
            calibration pose and speed [–]: what the controller assumes of the friction of
            the joints that slid. The stroke (10 mrad when measured) sees neither the position
            dependence (±15 % on the plants of ``benchmarks/guiding_quality.py``) nor the
            Stribeck curve: with 0.1 released arms crept up to 349 mrad there, with 0.2
            at most 21 mrad.
        max_torque_offset: Largest offset of the torque measurement it may report, a
            fraction of each joint's torque limit [–]: a measured torque that differs more
            from its command is not the motor torque the model expects (a torque without
            gravity, a link-side sensor) and refuses the calibration. 5 %: 1.5 Nm on the
            YuMi's shoulder, 0.5 Nm on its wrist.
        max_drift: Largest change of a joint's readings from the first cycle to the last,
            a fraction of what the joint carries at the pose [–]: its Coulomb level plus
            the gravity error its readings show. More refuses the calibration. At one pose
            the model's errors stay as they are (the stroke moves a joint 15 mrad) but for
            the transient in which the tracking's integral takes up a load the model lacks
            (a payload), whose inertia the readings then miss in proportion to that load;
            a reading that moves more is a push that changes: a hand on the arm. A relaxed
            hand that grabs as the run starts loads the arm below the push bound, and its
            mean push was read as a gravity error that drove the arm once the hand let go
            (the relaxed circles of seeds 9–11 of ``benchmarks/guiding_quality.py``, biases
            0.3–0.8 Nm off, released arms running 1.5 rad). Measured by
            ``benchmarks/calibration_drift.py``: with nobody touching (the YuMi's plants of
            seeds 1–8 at 250 Hz, 125 Hz and 1 kHz, the Panda's, UR5's and UR10e's), the
            readings move at most 0.068 of what a joint carries; with unknown payloads
            (the YuMi 0.5–2.3 kg, the UR10e 2–5 kg, the Panda 1–3 kg) at most 0.12; a
            relaxed hand grabbing at once (the YuMi's seeds 1, 2, 9, 10 and 11, both
            physics, four paths), at least 0.38, but for a hand that held joint
            2 still in one direction of the last cycle (dry #11 relaxed upwards: 0.16,
            accepted). A joint is checked where it slid at pace both ways in both the first
            and the last cycle (:meth:`CalibrationRun.drift`), 2–7 of the YuMi's 7; a
            motion of one cycle (``cycles`` = 1) is not checked.
        level_slope: Fastest relative change of a Coulomb level with its joint's angle
            [1/rad]: a level read at the pose to its readings' scatter is off by at most
            that much more per radian the joint travels from it, up to
            ``friction_accuracy`` (:mod:`~leadthrough.friction.measured_level`). 0.3 is
            the plant family's steepest (±15 %, two periods per turn); the real UR10e's
            levels change by at most 0.25 per radian over a stroke. None: the measured
            levels carry ``friction_accuracy`` everywhere, the pose included.
        predict: Which joints track the state predicted for when their command acts, one
            period after its sample (:func:`~leadthrough.control.tracking.predicted_state`),
            instead of the sample: ``"needed"`` (the default), each joint whose loop,
            linearised with two periods of delay (the plant family's longest) and damped by
            the joint's own viscous friction (the model's ``b / m_ii`` at the pose [1/s]),
            would grow (:attr:`CalibrationRun.predicted`); ``"always"``, every joint;
            ``"never"``, none. Predicted, a loop that grows with two periods at 125 and 100
            Hz decays (ζ −0.07 and −0.08 → 0.10 and 0.11 without viscous friction). The
            prediction takes the command's acceleration for the arm's, which a load or a
            stick-slip jump the model lacks makes wrong until the loop catches up, so it is
            kept to the joints that need it. With the default bandwidth that is no joint at
            250 Hz and faster, and at 125 and 100 Hz (at the home pose) every joint of the
            Panda (``b / m_ii`` 0–0.7 1/s) and the YuMi's joints 1–3 and 7 (its others 6–14
            1/s), the UR10e's 1–3 (and 6 at 100 Hz). At 125 Hz on every joint the YuMi's
            light wrist jumped four strokes off on 2 of 16 plants (refused), and seeds 1–4
            of ``benchmarks/guiding_quality.py`` guided with 2 of 8 plants uncalibrated
            (vibration 1.51× passive); at 250 Hz on every joint, seeds 5–8 guided 0.03
            heavier. At 125 Hz (``benchmarks/calibration_accuracy.py --robot panda --seeds
            16 --dt 0.008 [--predict never]``) tracking the samples refused a Panda's
            calibration on 6 of 16 plants, a joint at up to 2.8 rad/s, and left the arm
            moving at up to 0.34 rad/s; as needed, none refused, every level within 11.4 %,
            the arm at rest, and the YuMi's 16 plants calibrate as before (none refused,
            levels within 3.9 %).
    """

    stroke: float = 0.015
    speed: float = 0.1
    cycles: int = 2
    settle_time: float = 0.1
    bandwidth: float = 4.0
    max_speed: float = 2.0
    max_payload: float | None = None
    max_friction_change: float = 0.85
    friction_accuracy: float = 0.2
    max_torque_offset: float = 0.05
    max_drift: float = 0.25
    level_slope: float | None = 0.3
    slow_rate_damping: float = 0.14
    predict: str = "needed"

    def __post_init__(self) -> None:
        names = ("stroke", "speed", "bandwidth", "slow_rate_damping", "max_speed",
                 "max_friction_change", "friction_accuracy", "max_torque_offset",
                 "max_drift")  # fmt: skip
        for name in names:
            real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)
        if self.max_payload is not None:
            real("max_payload", self.max_payload, minimum=0.0, strict=True, error=ParameterError)
        real("settle_time", self.settle_time, minimum=0.0, error=ParameterError)
        if self.level_slope is not None:
            real("level_slope", self.level_slope, minimum=0.0, error=ParameterError)
        if self.predict not in PREDICTIONS:
            raise ParameterError("predict", f"must be one of {', '.join(PREDICTIONS)}, got "
                                 f"{self.predict!r}")  # fmt: skip
        if not isinstance(self.cycles, int) or self.cycles < 1:
            raise ParameterError("cycles", f"must be a whole number >= 1, got {self.cycles!r}")
        if self.max_speed <= self.speed:
            raise ParameterError("max_speed", f"must exceed the speed {self.speed:g} rad/s")

    def payload_limit(self, robot: RobotDescription) -> float:
        """Heaviest payload the calibration may report on ``robot`` [kg].

        ``max_payload``, or without one the arm's moving mass (its links') times
        :data:`PAYLOAD_SHARE`: the YuMi 2.5 kg, the Panda 8.4 kg, the UR10e 14 kg.
        """
        if self.max_payload is not None:
            return self.max_payload
        return PAYLOAD_SHARE * robot.total_mass

    def at_period(self, dt: float) -> CalibrationParameters:
        """These settings for a control period ``dt`` [s]: the same at 250 Hz and faster.

        Slower, the tracking's bandwidth drops to what the loop's delay allows
        (:func:`~leadthrough.control.tracking.period_bandwidth` with
        ``slow_rate_damping``: 4 Hz → 3.95 Hz at 125 Hz, 3.41 Hz at 100 Hz), and the
        stroke grows by as much, so that the motion stays as slow beside its loop (the run
        1.3 s at 250 Hz, 1.3 s at 125 Hz, 1.5 s at 100 Hz) and the 4-stroke check as far
        from the stick-slip jumps a slower loop lets a light joint make. Measured with the
        6 Hz ceiling of before: with 6 Hz and 10 mrad at 125 Hz, 5 of the 8 plants of
        seeds 1–4 were refused (joints 42–48 mrad off, one at 2.1 rad/s); with the
        bandwidth lowered but the stroke kept at 10 mrad, 2 of 16 at 100 Hz (40–41 mrad);
        with both, none of 16 at 125 or 100 Hz.
        """
        bandwidth = period_bandwidth(self.bandwidth, dt, calibration_gains,
                                     damping=self.slow_rate_damping)  # fmt: skip
        if bandwidth == self.bandwidth:
            return self
        return dataclasses.replace(self, bandwidth=bandwidth,
                                   stroke=self.stroke * self.bandwidth / bandwidth)  # fmt: skip

    def decaying_damping(self, dt: float) -> float:
        """The least viscous friction per unit inertia [1/s] with which the tracking decays.

        These settings' loop at the period ``dt`` [s], tracking the samples with two periods
        of delay (:func:`~leadthrough.control.tracking.decaying_damping`): a joint with less
        needs the prediction (``predict = "needed"``). ~30 linearisations: not for a
        control period.
        """
        return decaying_damping(calibration_gains(2.0 * np.pi * self.bandwidth), dt)

    @property
    def frequency(self) -> float:
        """Frequency of the triangular velocity wave [Hz] (stroke = speed / 4f)."""
        return self.speed / (4.0 * self.stroke)

    @property
    def duration(self) -> float:
        """Length of the whole calibration [s]."""
        return self.settle_time + self.cycles / self.frequency


@dataclass(frozen=True, eq=False)
class Calibration:
    """What the calibration measured.

    Attributes:
        pose: Where it was measured [rad].
        gravity_error: ``G_model − G_true`` at ``pose`` [Nm].
        coulomb_error: ``τ_C,model − τ_C,true`` at ``pose`` [Nm].
        payload: Payload mass at the flange that explains the gravity error best [kg].
        bias: Gravity error left once the payload is modelled [Nm] (0 on a joint that
            did not slide both ways).
        friction_scale: True over modelled Coulomb level, per joint [–]; a refused
            calibration keeps what it read (1 where it read nothing), of which only the
            levels below the model's are used (:meth:`lowered`).
        accepted: Whether the result is plausible (nobody touched the arm).
        reason: Why it was refused ("" if accepted).
        measured: Joints whose Coulomb level was measured: they slid both ways at pace for
            long enough (:data:`_MEASURED`). The others keep the model's level (scale 1);
            their gravity error counts as not known. One that did not slide both ways at
            all (stiction held it) keeps its gravity too (no error) and does not enter the
            payload fit.
        torque_offset: The measured motor torque minus the command it measures, averaged
            over the run, per joint [Nm]: an offset of the measurement, which the arm never
            felt; already added back to :attr:`gravity_error`. None: not read (no measured
            torque, or the run stopped early).
        coulomb_spread: How far a Coulomb reading may be off, per joint [Nm]: half the
            standard deviations of the paced readings up and down, combined (each
            stretch's reading counted once per sample; :func:`_scatter`). A joint that
            sticks and jumps between stretches scatters them. On the YuMi's plants the
            momentum balance scatters little (no measured joint of seeds 1–48 above 5 % of
            its level), and reads the dry plants' levels 0.8 % off in the median and at
            most 5 % (``calibration_accuracy.py``, seeds 1–16; a stretch starts on the
            Stribeck curve, so mostly high): the stiction margin's 5 %, the least error of
            any level, bounds them at the pose. On the Panda's, whose 6 Hz tracking rang,
            stretches disagreed by up to ±25 % of a shoulder's level and the levels came out
            up to 14 % off (with two periods of delay up to 71 %; at 4 Hz within 8.8 %,
            ``calibration_accuracy.py --robot panda --seeds 16 --delay 2``). None: not
            known (0).
        predicted: Joints whose tracking took the state predicted for when their command
            acted (:attr:`CalibrationRun.predicted`). None: not known.
    """

    pose: FloatArray
    gravity_error: FloatArray
    coulomb_error: FloatArray
    payload: float
    bias: FloatArray
    friction_scale: FloatArray
    accepted: bool
    reason: str = ""
    measured: BoolArray | None = None
    coulomb_spread: FloatArray | None = None
    torque_offset: FloatArray | None = None
    predicted: BoolArray | None = None

    def summary(self) -> str:
        """One line: what was measured, or why the calibration was refused.

        A refused one also names the levels it read below the model's (:meth:`lowered`).
        """
        if not self.accepted:
            lowered = self.lowered()
            low = ", ".join(f"joint {j + 1} {lowered[j]:.2f}×"
                            for j in np.flatnonzero(lowered < 1.0))  # fmt: skip
            if not low:
                return self.reason
            return (f"{self.reason}; guiding with the model, its friction error at least what "
                    f"the levels read below it show ({low})")  # fmt: skip
        scale = self.friction_scale[self.measured]
        offset = ""
        if self.torque_offset is not None:
            offset = f", measured torque offset up to {np.max(np.abs(self.torque_offset)):.3f} Nm"
        ahead = ""
        if self.predicted is not None and self.predicted.any():
            joints = ", ".join(str(j + 1) for j in np.flatnonzero(self.predicted))
            ahead = f", joint(s) {joints} tracked one period ahead"
        return (f"calibrated: payload {self.payload:.2f} kg, Coulomb levels "
                f"×{scale.min():.2f}–{scale.max():.2f} of the model, gravity bias up to "
                f"{np.max(np.abs(self.bias)):.3f} Nm{offset}{ahead}")  # fmt: skip

    def lowered(self) -> FloatArray:
        """Per joint, how far below the model's a refused calibration read a level [–].

        The readings' ``friction_scale`` clipped to [0, 1] on the joints measured, 1
        elsewhere. A refused run's readings are not taken as levels (:meth:`friction`
        keeps the model's), but a level the model overstates is the error that runs a
        released arm on: the estimate reads it as a push along the motion and the
        compensation pushes with it, while one it understates only makes guiding heavier.
        So a level read at ``r`` < 1 times the model's widens that joint's relative
        error to at least ``1 − r``: more friction margin, never less. A joint that ran
        faster than ``max_speed`` or more than four strokes off its motion under the
        calibration's own feed-forward (the model's friction among it; or a hand: the two
        cannot be told apart) counts as read at 0: none of its model's level is sure (error
        1: no compensation, the whole level as margin; a hand on the arm during the
        calibration costs that joint its compensation until the next one). On dry #1 of a
        family whose levels are 0.5–1.5 of the model's (its wrist 0.52×), the wrist jumped
        at 2.01 rad/s under the 6 Hz loop of before, and ran more than 60 mrad off the
        motion under the 4 Hz one; guided
        with the model's level and error, the released arm ran 1.25 rad (passive 3.1 rad).
        """
        if self.measured is None:
            return np.ones_like(self.friction_scale)
        return np.where(self.measured, np.clip(self.friction_scale, 0.0, 1.0), 1.0)

    def robot(self, nominal: RobotDescription) -> RobotDescription:
        """The description with the measured payload."""
        return nominal.with_payload(self.payload) if self.accepted else nominal

    def friction(self, nominal: FrictionModel, accuracy: float | None = None) -> FrictionModel:
        """The friction model with the measured Coulomb levels.

        Args:
            nominal: The model before the calibration.
            accuracy: Relative error of the measured levels away from the pose [–]; the
                joints that slid then carry ``min(nominal error + reading error +
                |friction_scale − 1|, accuracy)``: the model's level along the travel,
                rescaled by one reading, is off by what the model's shape is, plus what the
                reading is (:attr:`coulomb_spread` over the level read), plus how far the
                reading moved it. One reading cannot tell a level that changed everywhere
                (the rescale is right elsewhere) from a model whose shape is off at the pose
                (an identified model read beyond the stroke it was fitted on: the rescale
                is then as wrong elsewhere as it moved the level; traced on a plant whose
                identified level, rescaled by 10 % at the pose, stood 16 % over the plant's
                inside the stroke against a stated 7 %). With ``min(nominal error,
                accuracy)``, before, an identified model's small error stood under a level
                the reading set (the observer's band covered 86–89 % of the moving samples on
                plants whose friction was identified first). None keeps the nominal errors.

        A refused calibration gives ``nominal`` back, its errors widened where it read a
        level below the model's (:meth:`lowered`).
        """
        if not self.accepted:  # the model's levels, with as much error as the readings show
            lowered = self.lowered()
            if np.all(lowered == 1.0):
                return nominal
            return dataclasses.replace(nominal, relative_error=np.maximum(
                nominal.relative_error, 1.0 - lowered))  # fmt: skip
        error = nominal.relative_error
        if accuracy is not None and self.measured is not None:
            moved = np.abs(self.friction_scale - 1.0)  # how far the reading moved the level
            reading = self.reading_error(nominal) + moved
            error = np.where(self.measured, np.minimum(error + reading, accuracy), error)
        return dataclasses.replace(nominal, coulomb=nominal.coulomb * self.friction_scale,
                                   relative_error=error)  # fmt: skip

    def reading_error(self, nominal: FrictionModel) -> FloatArray:
        """Each level's relative error at the pose: its readings' spread over it [–].

        :attr:`coulomb_spread` over the level read (``nominal``'s at the pose times
        :attr:`friction_scale`); zeros without a spread or where no level was read.
        """
        read = nominal.coulomb_level(self.pose) * self.friction_scale
        spread = np.zeros_like(read) if self.coulomb_spread is None else self.coulomb_spread
        return np.divide(spread, read, out=np.zeros_like(read), where=read > 0.0)

    def level_error(
        self, far: FloatArray, nominal: FrictionModel, slope: float | None, floor: float
    ) -> MeasuredLevelError | None:
        """How far the levels read here are off anywhere (None: nothing read, no slope).

        Args:
            far: The relative error each level carries anywhere [–] (the controller's
                after :meth:`friction`; also that of the joints not read).
            nominal: The friction model the readings rescaled.
            slope: ``CalibrationParameters.level_slope`` [1/rad].
            floor: The least relative error of any level [–] (the stiction margin).
        """
        if not self.accepted or self.measured is None or slope is None:
            return None
        at_pose = np.minimum(np.maximum(self.reading_error(nominal), floor), far)
        return MeasuredLevelError(self.pose.copy(), np.where(self.measured, at_pose, far),
                                  np.array(far, dtype=float), slope)  # fmt: skip


def _scatter(readings: FloatArray) -> FloatArray:
    """Standard deviation of each column's readings, NaNs left out [Nm] (0 if none).

    Each stretch's reading counts once per sample of it. Not a robust spread: a joint read
    from a few stretches that disagree (the Panda's shoulder, ±25 % of its level from one
    stretch to the next) has half its samples on one value, and a median absolute
    deviation of ~0 stated its level known to 5 % where it was 10–14 % off.
    """
    finite = np.isfinite(readings)
    counts = np.count_nonzero(finite, axis=0)
    mean = np.where(finite, readings, 0.0).sum(axis=0) / np.maximum(counts, 1)
    squares = np.where(finite, (readings - mean) ** 2, 0.0).sum(axis=0)
    return np.sqrt(squares / np.maximum(counts, 1))


def _column_medians(values: FloatArray) -> FloatArray:
    """``np.nanmedian(values, axis=0)`` in a few vector operations (NaN: no finite value).

    NumPy's ``nanmedian`` loops over the columns in Python: with the run's samples at 1 kHz
    its calls took a millisecond of the calibration's last period.
    """
    ordered = np.sort(values, axis=0)  # NaNs last
    counts = np.count_nonzero(~np.isnan(values), axis=0)
    columns = np.arange(values.shape[1])
    low, high = np.maximum((counts - 1) // 2, 0), counts // 2
    middle = (ordered[low, columns] + ordered[high, columns]) / 2
    return np.where(counts > 0, middle, np.nan)


def implausible_friction(scale: FloatArray, max_change: float) -> NDArray[np.bool_]:
    """Where a measured Coulomb level, ``scale`` times the model's, is not plausible [–].

    Outside ``[1 / (1 + max_change), 1 + max_change]``: the errors a level must pass
    multiply, so the band is symmetric in the ratio's logarithm (a level 1.6× the model's
    is as plausible as one 1 / 1.6× of it). A ratio ≤ 0 (friction that pushes) is never.
    """
    limit = 1.0 + max_change
    return (scale > limit) | (scale < 1.0 / limit)


def gravity_share(bias: FloatArray, gravity: FloatArray, limit: float) -> FloatArray:
    """Per joint, the relative error of G that explains a gravity error read at a pose [–].

    ``bias`` = ``G_model − G_true`` and ``gravity`` = ``G_model`` at the calibration pose
    [Nm]. A drive that applies ``g`` times what it is told scales a joint's gravity torque
    rather than shifts it: the part of ``bias`` up to ``limit`` times ``|G|`` (the drives'
    gain tolerance, ``LeadThroughParameters.drive_gain_uncertainty``) is taken as ``k G``,
    which follows G away from the pose, and only the rest as a constant. A mass off does not
    scale each joint's G alike, so its share stays constant: with the masses' 5 % in the
    limit too (15 %), a mass error read on a wrist joint holding 0.4 Nm was taken as 14 % of
    its G, and a released arm with masses ±10 % coasted 0.56 s. A drive gain of 1.09 on
    a shoulder holding 5 Nm at the pose reads a bias of 0.4 Nm there, but is 0.03 Nm off
    where the shoulder holds 0.3 Nm: kept constant, the difference read as a push that ran a
    released arm on for 0.67 s (dry #59 stiff upwards of ``benchmarks/guiding_quality.py``).
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(gravity != 0.0, bias / gravity, 0.0)
    return np.clip(share, -limit, limit)


#: The calibration's tracking gains per unit of M(q) for a bandwidth ω [rad/s]: stiffness
#: ω², damping 2ζω with ζ = 1, and an integral ω³/4 that holds a load the model does not
#: know (a payload) within the stroke.
calibration_gains = pd_gains(1.0, 0.25)


class CalibrationRun:
    """The calibration motion around the pose the arm rests at, and its readings.

    Args:
        dynamics: Model of the arm.
        friction: Friction model (its mean at the reference speed is fed forward).
        pose: Where the arm rests [rad].
        parameters: Motion settings.
        gravity_uncertainty: Relative error of the model's gravity torque [–] (masses and
            drive gains, ``LeadThroughParameters.gravity_uncertainty``): what a payload must
            stand out of (:meth:`payload`).
        dt: The control period [s] (``parameters`` are those for it,
            :meth:`CalibrationParameters.at_period`): with two periods of delay, it decides
            which joints' loops would grow and so track the predicted state
            (:attr:`predicted`).
        decaying_damping: :func:`~leadthrough.control.tracking.decaying_damping` of this
            loop at ``dt`` [1/s], if the caller computed it beforehand (``LeadThrough``
            does, when it is built: the run starts in a control period).
    """

    def __init__(
        self,
        dynamics: Dynamics,
        friction: FrictionModel,
        pose: ArrayLike,
        parameters: CalibrationParameters | None = None,
        gravity_uncertainty: float = 0.15,
        dt: float = VERIFIED_PERIOD,
        decaying_damping: float | None = None,
    ) -> None:
        self.parameters = parameters or CalibrationParameters()
        self.dynamics, self.friction = dynamics, friction
        self.gravity_uncertainty = gravity_uncertainty
        self.pose = np.array(pose, dtype=float)
        low, high = dynamics.robot.q_min, dynamics.robot.q_max
        # move into the side with more room (a joint resting near a limit moves away from it)
        self._direction = np.where(high - self.pose >= self.pose - low, 1.0, -1.0)
        self._gains = calibration_gains(2.0 * np.pi * self.parameters.bandwidth)
        #: the joints whose tracking takes the state predicted for when a command acts
        self.predicted = self._predicted_joints(dynamics, friction, dt, decaying_damping)
        self._error_integral = np.zeros_like(self.pose)
        self._last_t: float | None = None  # the previous command's time [s]
        # the acceleration the last command asked for, its integral's share left out [rad/s²]
        self._accelerating = np.zeros_like(self.pose)
        self.disturbance: str | None = None  # why the calibration must stop, if it must
        # the joint that ran faster than max_speed or too far off the motion, if one
        self.runaway: int | None = None
        #: per joint, how far its readings moved over what it carries (``max_drift``; 0
        #: where not checked), once :meth:`judge` got that far [–]
        self.drift_ratio: FloatArray | None = None
        self._balance = MomentumBalance(dynamics, friction)  # what the readings come from
        #: the largest external torque the model's errors may read untouched [Nm]
        self.push_bound = self._plausible_push(gravity_uncertainty)
        self._discrepancy = np.zeros_like(self.pose)  # Σ (τ_measured − τ_commanded) [Nm]
        self._discrepancies = 0
        self._moves: list[FloatArray] = []  # |q_k − q_{k−1}| of every sample [rad]
        self._last_q: FloatArray | None = None

    @property
    def duration(self) -> float:
        """Length of the calibration [s]."""
        return self.parameters.duration

    def _predicted_joints(
        self,
        dynamics: Dynamics,
        friction: FrictionModel,
        dt: float,
        least: float | None,
    ) -> NDArray[np.bool_]:
        """``predict`` per joint: ``"needed"``, where the joint's loop would grow.

        Linearised with two periods of delay (:data:`~leadthrough.control.tracking.
        LONGEST_DELAY`) at the period ``dt`` [s]: where the joint's own viscous friction
        per unit of its inertia at the pose, which damps it, is below ``least``
        (:func:`~leadthrough.control.tracking.decaying_damping`; computed here if None).
        """
        n = self.pose.size
        if self.parameters.predict != "needed":
            return np.full(n, self.parameters.predict == "always")
        if least is None:
            least = self.parameters.decaying_damping(dt)
        return friction.viscous / np.diag(dynamics.mass(self.pose)) < least

    def command(self, t: float, q: FloatArray, qd: FloatArray) -> FloatArray:
        """Torque [Nm] tracking the calibration motion at time ``t`` [s] from its start."""
        q_ref, qd_ref, qdd_ref = self._reference(t)
        self._check(q, qd, q_ref)
        # the robot's own period, sample to sample (none before the first command)
        period = 0.0 if self._last_t is None else max(t - self._last_t, 0.0)
        self._last_t = t
        if self.predicted.any():  # where those joints will be when the command acts
            ahead, speed = predicted_state(q, qd, self._accelerating, period)
            q, qd = np.where(self.predicted, ahead, q), np.where(self.predicted, speed, qd)
            now, later = (q_ref, qd_ref, qdd_ref), self._reference(t + period)
            q_ref, qd_ref, qdd_ref = (np.where(self.predicted, b, a)
                                      for a, b in zip(now, later, strict=True))  # fmt: skip
        error = q_ref - q
        self._error_integral += error * period
        stiffness, damping, integral = self._gains
        # the integral holds what the model lacks (a payload): it accelerates nothing
        self._accelerating = qdd_ref + stiffness * error + damping * (qd_ref - qd)
        wanted = self._accelerating + integral * self._error_integral
        friction = self.friction.mean(qd_ref, q_ref)
        return self.dynamics.gravity(q) + self.dynamics.mass(q) @ wanted + friction

    def _reference(self, t: float) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The motion at ``t`` [s] from the start: q_ref [rad], q̇_ref [rad/s], q̈_ref [rad/s²]."""
        p = self.parameters
        moving = max(t - p.settle_time, 0.0)
        offset, velocity, acceleration = triangular_velocity(moving, p.speed, p.frequency)
        if t < p.settle_time:
            velocity = acceleration = np.zeros_like(velocity)
        d = self._direction
        return self.pose + d * offset, d * velocity, d * acceleration

    def _check(self, q: FloatArray, qd: FloatArray, q_ref: FloatArray) -> None:
        """Note the first disturbance: a joint too fast, or too far off the motion."""
        if self.disturbance is not None:
            return
        p = self.parameters
        speed, error = np.abs(qd), np.abs(q_ref - q)
        if np.max(speed) > p.max_speed:
            joint = self.runaway = int(np.argmax(speed))
            self.disturbance = (f"joint {joint + 1} moved at {speed[joint]:.3f} rad/s, faster "
                                f"than the calibration's {p.max_speed:g} rad/s: stopped, "
                                "arm held, its friction not trusted")  # fmt: skip
        elif np.max(error) > _DISTURBED * p.stroke:
            joint = self.runaway = int(np.argmax(error))
            self.disturbance = (f"joint {joint + 1} was {1e3 * error[joint]:.0f} mrad off the "
                                "calibration motion: was the arm touched? Its friction not "
                                "trusted")  # fmt: skip

    def _plausible_push(self, gravity_uncertainty: float) -> FloatArray:
        """What the observer may read at the pose with nobody touching the arm [Nm].

        The model errors this calibration would still accept, each at its bound: a torque
        offset of ``max_torque_offset`` of the torque limit, a gravity error of
        ``gravity_uncertainty`` of G(q₀) plus a payload of :meth:`~CalibrationParameters.
        payload_limit` at the flange, and friction (1 + ``max_friction_change``) times the
        Coulomb level (a level that far off the model's while a joint slides, or the
        stiction that holds a joint between strokes).
        """
        p, q = self.parameters, self.pose
        payload = p.payload_limit(self.dynamics.robot) * np.abs(self.payload_regressor(q))
        return (p.max_torque_offset * self.dynamics.robot.torque_limits
                + gravity_uncertainty * np.abs(self.dynamics.gravity(q)) + payload
                + (1.0 + p.max_friction_change) * self.friction.coulomb_level(q))  # fmt: skip

    def check_push(self, estimate: FloatArray) -> None:
        """Stop the run at once if the observer reads a push no model error explains.

        ``estimate``: the observer's external torque this period [Nm]. Above
        :attr:`push_bound` on any joint, someone (or something) pushes the arm: the tracking
        would hold it against them until the run ends (a stiff hand that grabbed at once
        pulled 60 N by then, and the arm jumped after it at 1.5 rad/s when let go), so the
        run is refused now and the arm let go.
        """
        over = np.abs(estimate) - self.push_bound
        if self.disturbance is None and np.max(over) > 0.0:
            joint = int(np.argmax(over))
            self.interrupt(f"joint {joint + 1} was pushed with {estimate[joint]:+.2f} Nm, more "
                           f"than the {self.push_bound[joint]:.2f} Nm its model may be off: "
                           "was the arm touched? Its friction not measured")  # fmt: skip

    def interrupt(self, reason: str) -> None:
        """Stop the run for ``reason`` (the first disturbance is the one kept).

        Something outside the motion said the arm is not alone (an enabling device held:
        a hand is on it): the run is refused with ``reason``, every level left as the
        model gives it, as for a push that stopped the run early.
        """
        if self.disturbance is None:
            self.disturbance = reason

    def record(
        self, t: float, q: FloatArray, tau: FloatArray, discrepancy: FloatArray | None = None
    ) -> None:
        """Keep one sample of the motion for its readings (:meth:`readings`).

        Args:
            t: Time since the calibration began [s].
            q: Joint positions as the encoders read them [rad].
            tau: The motor torque applied over the last period [Nm] (measured, or the
                command that reached the drive).
            discrepancy: The measured motor torque minus the command it measures [Nm]
                (None: the robot measures none); averaged into the torque offset.
        """
        self._note_move(q)
        if t < self.parameters.settle_time:
            return
        if discrepancy is not None:
            self._discrepancy += discrepancy
            self._discrepancies += 1
        self._balance.add(t, q, tau)

    def _note_move(self, q: FloatArray) -> None:
        """Keep each joint's change of angle from the sample before (:attr:`encoder_step`)."""
        q = np.asarray(q, dtype=float)
        if self._last_q is not None:
            self._moves.append(np.abs(q - self._last_q))
        self._last_q = q.copy()

    @property
    def encoder_step(self) -> FloatArray:
        """Each joint's encoder count as its moves so far show it [rad]; inf where they do not.

        The smallest change of the joint's angle from one sample to the next, where every
        change is a whole number of it (:data:`_WHOLE_COUNTS`): what an encoder's counts
        give once the joint has moved by one. Where they are not (an encoder finer than
        the motion shows: a count too small to be seen, the arbitrary steps of a
        stick-slip jump), or the joint moved fewer than three times, inf.
        """
        n = self.pose.shape[0]
        if not self._moves:
            return np.full(n, np.inf)
        moves = np.array(self._moves)
        step = np.full(n, np.inf)
        for joint in range(n):
            moved = moves[moves[:, joint] > _LEAST_STEP, joint]
            if moved.size < _ENOUGH:
                continue
            counts = moved / moved.min()
            if np.max(np.abs(counts - np.round(counts))) <= _WHOLE_COUNTS:
                step[joint] = moved.min()
        return step

    def unresolved(self, t: FloatArray) -> BoolArray:
        """Joints whose encoder cannot read the motion's pace, from the samples at ``t`` [s].

        The readings' velocity is the encoders' central difference, in steps of one count
        over two periods, ``Δ / 2T``. Where that step is above the motion's speed ``v``
        (``Δ > 2 v T``), a joint at pace reads still or faster than the pace, never the
        pace: its stretches at pace come out in fragments, and the momentum at their ends
        off by up to a count's worth of velocity. Through the arm's inertia (``p = M q̇``)
        and its Coriolis torque that velocity enters every other joint's balance too, so one
        such joint refuses the whole calibration (``judge``). ``Δ`` is the smallest change of
        the joint's angle between two samples (:attr:`encoder_step`): a count, once the
        joint moved by one; a joint whose moves show no count is not judged.

        Measured on the YuMi's plants of seeds 1–4 of ``benchmarks/guiding_quality.py``
        (250 Hz, 0.1 rad/s: 0.8 mrad in two periods). With 64 counts per motor turn (0.98
        mrad at a joint) the calibration read dry #1's joint 4's gravity error +0.20 Nm
        against −0.02, and seven released arms ran on past 1 mrad, one 238 mrad. With 128
        (0.49 mrad) the readings are coarser but still worth taking: accepted, every goal
        each case must keep held (effort 0.70); refused, the arm guided as without a
        calibration (0.85) and two cases shook 1.58–1.62× passive.
        """
        if len(t) < 2:
            return np.zeros(self.pose.shape, dtype=bool)
        step = self.encoder_step
        return np.isfinite(step) & (step > self._two_periods(t))

    def _two_periods(self, t: FloatArray) -> float:
        """How far the motion moves a joint at its speed in two periods of ``t`` [rad]."""
        return 2.0 * self.parameters.speed * float(np.median(np.diff(t)))

    def readings(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Times [s], joint velocities [rad/s] and readings [Nm] of the samples recorded.

        The velocity is the encoders' central difference and a reading is the momentum
        balance over the stretch the joint slid at the motion's pace
        (:mod:`~leadthrough.estimation.momentum_balance`); NaN where it did not.
        """
        t, velocity, unexplained = self._balance.arrays()
        pace = (_SLIDING * self.parameters.speed, _JUMPING * self.parameters.speed)
        return t, velocity, stretch_readings(t, velocity, unexplained, pace)

    def result(self) -> Calibration:
        """The model error measured (refused with a reason when implausible)."""
        return self.judge(*self.readings())

    def judge(self, t: FloatArray, velocity: FloatArray, readings: FloatArray) -> Calibration:
        """The model error the readings show (refused with a reason when implausible).

        Args:
            t: Times since the calibration began [s], (N,).
            velocity: Joint velocities [rad/s], (N, n).
            readings: What the model misses while each joint slides at pace [Nm], (N, n);
                NaN where it does not.
        """
        p = self.parameters
        if self.disturbance is not None:
            if self.runaway is None:
                return self._refused(self.disturbance)
            # none of the friction that ran a joint away is sure: read at 0 (lowered)
            untrusted = np.arange(self.pose.shape[0]) == self.runaway
            return self._refused(self.disturbance, np.where(untrusted, 0.0, 1.0), untrusted)
        offset = self.torque_offset()
        if offset is not None:
            limit = p.max_torque_offset * self.dynamics.robot.torque_limits
            if np.any(np.abs(offset) > limit):
                joint = int(np.argmax(np.abs(offset) / limit))
                return self._refused(f"joint {joint + 1}'s measured torque is "
                                     f"{offset[joint]:+.2f} Nm off its command: is it the "
                                     "motor torque?", offset=None)  # fmt: skip
        coarse = self._too_coarse(t)
        if coarse is not None:
            return self._refused(coarse, offset=offset)
        plus = np.where(velocity > 0.0, readings, np.nan)
        minus = np.where(velocity < 0.0, readings, np.nan)
        paced = np.array([np.sum(np.isfinite(plus), axis=0), np.sum(np.isfinite(minus), axis=0)])
        slid = np.all(paced >= _ENOUGH, axis=0)
        if np.count_nonzero(slid) < 0.5 * slid.size:
            joints = ", ".join(str(j + 1) for j in np.flatnonzero(~slid))
            return self._refused(f"joint(s) {joints} did not slide both ways", offset=offset)
        measured = slid & np.all(paced >= _MEASURED * self._asked(t), axis=0)
        level = self.friction.coulomb_level(self.pose)
        e_plus = _column_medians(np.where(slid, plus, 0.0))
        e_minus = _column_medians(np.where(slid, minus, 0.0))  # a stuck joint: no error
        read = 0.5 * (e_plus + e_minus)  # what does not change sign with the motion
        # the readings' gravity error, plus what the measurement adds that the arm never felt
        gravity_error = np.where(slid, read + (0.0 if offset is None else offset), 0.0)
        coulomb_error = np.where(measured, 0.5 * (e_plus - e_minus), 0.0)
        # a joint modelled without friction keeps it: no level to rescale
        scale = np.where(level > 0.0, 1.0 - coulomb_error / np.where(level > 0.0, level, 1.0), 1.0)
        # a push that changed while the run read it: a hand (max_drift); a joint modelled
        # without friction has no level to hold its readings' change against
        carried = level + np.abs(read)
        drift = np.where(slid & (level > 0.0), self.drift(t, plus, minus), np.nan)
        moved = np.divide(np.abs(drift), carried, out=np.zeros_like(carried),
                          where=np.isfinite(drift))  # fmt: skip
        self.drift_ratio = moved
        if np.max(moved) > p.max_drift:
            joint = int(np.argmax(moved))
            return self._refused(f"joint {joint + 1}'s readings moved {drift[joint]:+.2f} Nm "
                                 "between the first cycle and the last: was the arm "
                                 "touched?", scale, measured, offset)  # fmt: skip
        changed = implausible_friction(scale, p.max_friction_change)
        if np.any(changed):
            joint = int(np.argmax(np.where(changed, np.abs(scale - 1.0), -1.0)))
            return self._refused(f"joint {joint + 1}'s friction seems {scale[joint]:.2f}× the "
                                 "model's: was the arm touched?", scale, measured,
                                 offset)  # fmt: skip
        per_kilogram = self.payload_regressor(self.pose)
        payload = self.payload(gravity_error, per_kilogram, slid)
        allowed = p.payload_limit(self.dynamics.robot)
        if payload > allowed:
            return self._refused(f"a payload of {payload:.2f} kg is more than the "
                                 f"{allowed:.3g} kg allowed: was the arm touched?", scale,
                                 measured, offset)  # fmt: skip
        bias = np.where(slid, gravity_error + payload * per_kilogram, 0.0)
        spread = np.where(measured, 0.5 * np.hypot(_scatter(plus), _scatter(minus)), 0.0)
        return Calibration(self.pose, gravity_error, coulomb_error, payload, bias, scale, True,
                           measured=measured, coulomb_spread=spread,
                           torque_offset=offset, predicted=self.predicted)  # fmt: skip

    def _too_coarse(self, t: FloatArray) -> str | None:
        """Why the encoders cannot give readings (:meth:`unresolved`), or None if they can."""
        unresolved = self.unresolved(t)
        if not unresolved.any():
            return None
        joints = ", ".join(str(j + 1) for j in np.flatnonzero(unresolved))
        step = 1e3 * np.max(self.encoder_step[unresolved])
        return (f"the encoder(s) of joint(s) {joints} step up to {step:.3g} mrad, more than "
                f"the motion moves in two periods ({1e3 * self._two_periods(t):.3g} mrad): "
                "too coarse to read its pace")  # fmt: skip

    def drift(self, t: FloatArray, plus: FloatArray, minus: FloatArray) -> FloatArray:
        """How far each joint's readings moved from the first cycle to the last [Nm].

        The last cycle's median reading minus the first's, averaged over both directions
        (``max_drift``): a push that changes moves both directions' readings together, a
        level that reads differently from one cycle to the next (stick-slip, the Stribeck
        range) moves them apart. NaN where a joint was not read in both directions of both
        cycles, and with a single cycle. Checked in one direction alone, the readings of
        lugre #5 of ``benchmarks/guiding_quality.py`` at 125 Hz moved 0.27 of what the
        joint carries with nobody touching (both directions: at most 0.04 at that rate).

        Args:
            t: Times since the calibration began [s], (N,).
            plus: The readings while each joint slid in the positive direction [Nm],
                (N, n); NaN elsewhere.
            minus: The same in the negative direction.
        """
        p = self.parameters
        if p.cycles < 2:
            return np.full(plus.shape[1], np.nan)
        cycle = np.floor((np.asarray(t) - p.settle_time) * p.frequency)[:, None]
        change = [_column_medians(np.where(cycle == p.cycles - 1, side, np.nan))
                  - _column_medians(np.where(cycle == 0, side, np.nan))
                  for side in (plus, minus)]  # fmt: skip
        return 0.5 * (change[0] + change[1])

    def _asked(self, t: FloatArray) -> FloatArray:
        """Samples in which the motion drove each joint up / down at pace, (2, n)."""
        p = self.parameters
        _, velocity, _ = triangular_velocity(np.asarray(t) - p.settle_time, p.speed, p.frequency)
        wanted = self._direction * np.reshape(velocity, (-1, 1))
        threshold = _SLIDING * p.speed
        return np.array([np.sum(wanted > threshold, axis=0), np.sum(wanted < -threshold, axis=0)])

    def torque_offset(self) -> FloatArray | None:
        """The measured motor torque minus its command, averaged over the run [Nm].

        None without a measured torque (or before the motion began).
        """
        if self._discrepancies == 0:
            return None
        return self._discrepancy / self._discrepancies

    def payload(
        self, gravity_error: FloatArray, per_kilogram: FloatArray, slid: BoolArray
    ) -> float:
        """The payload [kg] the gravity errors of the joints that slid show, or 0.

        Weighted least squares on ``gravity_error = −m · Y``: each joint's error counts
        with the inverse variance of what the model may be off there anyway, ``σ_j =
        gravity_uncertainty · |G_j| + friction_accuracy · τ_C,j`` (drive gains and masses,
        and the reading's own error, taken as large as a measured level's). Near its home
        pose a payload loads the YuMi's joints much as its own gravity does, so drive gains
        10 % off look like 0.1–0.2 kg to a plain least-squares fit: a payload is taken only
        if it stands out of the model's own error by two standard deviations (``m ≥ 2
        σ_m``); else the errors stay biases at the pose. A spurious 0.20 kg on lugre #32 put
        0.57 Nm of model error on joint 4 once the arm had moved sideways, and its released
        arm ran 1.3 rad in either mode.
        """
        pose_gravity = np.abs(self.dynamics.gravity(self.pose))
        level = self.friction.coulomb_level(self.pose)
        spread = (self.gravity_uncertainty * pose_gravity
                  + self.parameters.friction_accuracy * level)  # fmt: skip
        weight = np.where(slid & (spread > 0.0), 1.0 / np.maximum(spread, 1e-12) ** 2, 0.0)
        information = float(weight * per_kilogram @ per_kilogram)
        if information <= 0.0:  # no payload shows in this pose (unobservable)
            return 0.0
        mass = float(-(weight * per_kilogram) @ gravity_error) / information
        return mass if mass >= 2.0 / np.sqrt(information) else 0.0

    def payload_regressor(self, q: FloatArray) -> FloatArray:
        """Gravity torque of one kilogram at the flange, ``Y = −J_vᵀ g`` [Nm/kg]."""
        return -self.dynamics.jacobian(q)[:3].T @ self.dynamics.robot.gravity

    def _refused(
        self, reason: str, scale: FloatArray | None = None, measured: BoolArray | None = None,
        offset: FloatArray | None = None,
    ) -> Calibration:  # fmt: skip
        """Refused: only how far below the model's it read levels, and the offset, are used.

        ``scale`` and ``measured``: the levels read, when the readings got that far;
        ``offset``: the measurement's offset, when the run was not stopped early.
        """
        n = self.pose.shape[0]
        zeros = np.zeros(n)
        scale = np.ones(n) if scale is None else scale
        measured = np.zeros(n, dtype=bool) if measured is None else measured
        return Calibration(self.pose, zeros, zeros, 0.0, zeros, scale, False,
                           f"calibration refused: {reason}", measured,
                           torque_offset=offset, predicted=self.predicted)  # fmt: skip
