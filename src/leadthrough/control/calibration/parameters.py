"""Settings of the start-up calibration: its motion, its tracking and what it accepts."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from leadthrough.control.tracking import decaying_damping, pd_gains, period_bandwidth
from leadthrough.errors import ParameterError
from leadthrough.model.description import RobotDescription
from leadthrough.validation import real

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

#: The calibration's tracking gains per unit of M(q) for a bandwidth ω [rad/s]: stiffness
#: ω², damping 2ζω with ζ = 1, and an integral ω³/4 that holds a load the model does not
#: know (a payload) within the stroke.
calibration_gains = pd_gains(1.0, 0.25)


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
            refuses the calibration (:func:`~.result.implausible_friction`). The errors a measured
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
