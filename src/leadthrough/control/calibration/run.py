"""The start-up calibration's run: the motion at the pose the arm rests at, its readings.

What the readings show, judged plausible or refused, is a
:class:`~leadthrough.control.calibration.result.Calibration`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.control.calibration.parameters import CalibrationParameters, calibration_gains
from leadthrough.control.calibration.result import BoolArray, Calibration, implausible_friction
from leadthrough.control.tracking import VERIFIED_PERIOD, predicted_state
from leadthrough.estimation.momentum_balance import MomentumBalance, stretch_readings
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray
from leadthrough.model.dynamics import Dynamics
from leadthrough.trajectories import triangular_velocity

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
#: Reduction of the weighted squared gravity error a payload's moment must bring for it to
#: be taken [–]: Akaike's 2 per parameter, for the two of its three components one pose
#: shows. (The mass's own 2σ test in χ² of two degrees of freedom, 6.18, left the moment
#: of a YuMi's 0.5 kg tool 6 cm off the flange, read at 5.9, and weighed it at 0.84 kg.)
_MOMENT_GAIN = 4.0
#: A joint this many strokes off its calibration motion has been pushed [–].
_DISTURBED = 4.0
#: Smallest change of a joint's angle taken as a move [rad]: below any encoder's count,
#: above a float's rounding of the angles it reports.
_LEAST_STEP = 1e-12
#: How far from a whole number of counts a joint's moves may be and still be counts [–]:
#: an encoder's are whole to a float's rounding (angles through float32: ~1e-4 of a 1 mrad
#: count); a finer encoder's moves, or a jump's, are not, bar chance.
_WHOLE_COUNTS = 0.01


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
    ) -> BoolArray:
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
            cause = "was the arm touched?"
            if self._sank(joint, q[joint] - q_ref[joint]):
                cause = ("a payload the model lacks (give it with set_payload(mass, com)), or "
                         "was the arm touched?")  # fmt: skip
            off = 1e3 * error[joint]
            self.disturbance = (f"joint {joint + 1} was {off:.0f} mrad off the calibration "
                                f"motion: {cause} Its friction not trusted")  # fmt: skip

    def _sank(self, joint: int, off: float) -> bool:
        """Whether ``joint`` went ``off`` [rad] the way a weight at the flange pulls it.

        Then the likeliest cause is a tool nobody gave the model: a UR10e's 5 kg 10 cm out
        along its flange sank its wrist 64 mrad within 0.14 s of the start, before the
        tracking's integral held it, and the refusal asked only whether it was touched.
        """
        pull = -self.payload_regressor(self.pose)[joint]  # a weight's torque on the joint
        return bool(off * pull > 0.0)

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
                           "was the arm touched, or does it carry a payload heavier than "
                           "max_payload (give it with set_payload(mass, com))? Its friction "
                           "not measured")  # fmt: skip

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
        payload, moment = self.payload_body(gravity_error, slid)
        allowed = p.payload_limit(self.dynamics.robot)
        if payload > allowed:
            return self._refused(f"a payload of {payload:.2f} kg is more than the "
                                 f"{allowed:.3g} kg allowed (max_payload): was the arm "
                                 "touched? A tool that heavy: give it with set_payload(mass, "
                                 "com), or raise max_payload", scale, measured,
                                 offset)  # fmt: skip
        explained = (payload * self.payload_regressor(self.pose)
                     + self.moment_regressor(self.pose) @ moment)  # fmt: skip
        bias = np.where(slid, gravity_error + explained, 0.0)
        spread = np.where(measured, 0.5 * np.hypot(_scatter(plus), _scatter(minus)), 0.0)
        return Calibration(self.pose, gravity_error, coulomb_error, payload, bias, scale, True,
                           measured=measured, coulomb_spread=spread,
                           torque_offset=offset, predicted=self.predicted,
                           payload_com=moment / payload if moment.any() else None)  # fmt: skip

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
        weight = self._gravity_weights(slid)
        information = float(weight * per_kilogram @ per_kilogram)
        if information <= 0.0:  # no payload shows in this pose (unobservable)
            return 0.0
        mass = float(-(weight * per_kilogram) @ gravity_error) / information
        return mass if mass >= 2.0 / np.sqrt(information) else 0.0

    def payload_body(self, gravity_error: FloatArray, slid: BoolArray) -> tuple[float, FloatArray]:
        """The payload's mass [kg] and first moment ``h = m c`` [kg m] (flange frame).

        A payload (:meth:`payload`) whose centre of mass is off the flange also loads the
        joints with its moment, ``G_true = G_model + m Y(q) + Y_h(q) h``
        (:meth:`moment_regressor`). At one pose the moment's component along gravity
        turns nothing (a tool hanging straight down), so only the two across it are
        fitted, with the mass, by the same weighted least squares; they are taken if
        they explain the gravity error by more than :data:`_MOMENT_GAIN` beyond the
        mass alone, else the mass alone. A tool's centre along the vertical at the pose
        stays unknown (0): give it with ``LeadThrough.set_payload(mass, com)``.
        Without the moment, a 1 kg tool 5 cm to the side and 10 cm out on a Panda was
        weighed as 1.00 kg at the flange, the bias at the pose took its moment there,
        and the arm released 0.6 rad away ran 1.1 rad on its wrist in either mode.
        """
        mass = self.payload(gravity_error, self.payload_regressor(self.pose), slid)
        none = np.zeros(3)
        if mass == 0.0:
            return 0.0, none
        weight = self._gravity_weights(slid)
        down = self.dynamics.pose(self.pose)[:3, :3].T @ self.dynamics.robot.gravity
        across = np.linalg.svd(down[None, :])[2][1:].T  # (3, 2): the flange axes ⟂ gravity
        columns = np.column_stack([self.payload_regressor(self.pose),
                                   self.moment_regressor(self.pose) @ across])  # fmt: skip
        root = np.sqrt(weight)
        fit, *_ = np.linalg.lstsq(root[:, None] * columns, -root * gravity_error, rcond=None)
        alone = gravity_error + mass * columns[:, 0]
        both = gravity_error + columns @ fit
        gain = float(weight @ alone**2 - weight @ both**2)
        if gain < _MOMENT_GAIN or fit[0] <= 0.0:
            return mass, none
        return float(fit[0]), across @ fit[1:]

    def _gravity_weights(self, slid: BoolArray) -> FloatArray:
        """Inverse variances of what the model's gravity may be off anyway, per joint [1/Nm²].

        ``σ_j = gravity_uncertainty · |G_j| + friction_accuracy · τ_C,j`` on the joints
        that slid (:meth:`payload`); 0 elsewhere.
        """
        pose_gravity = np.abs(self.dynamics.gravity(self.pose))
        level = self.friction.coulomb_level(self.pose)
        spread = (self.gravity_uncertainty * pose_gravity
                  + self.parameters.friction_accuracy * level)  # fmt: skip
        return np.where(slid & (spread > 0.0), 1.0 / np.maximum(spread, 1e-12) ** 2, 0.0)

    def payload_regressor(self, q: FloatArray) -> FloatArray:
        """Gravity torque of one kilogram at the flange, ``Y = −J_vᵀ g`` [Nm/kg]."""
        return -self.dynamics.jacobian(q)[:3].T @ self.dynamics.robot.gravity

    def moment_regressor(self, q: FloatArray) -> FloatArray:
        """Gravity torque of a payload's first moment ``h`` [kg m] in the flange frame.

        ``Y_h = J_ωᵀ [g]× R`` [Nm/(kg m)], (n, 3), R the flange's orientation: the
        potential ``−gᵀ R h`` of a mass ``m`` at ``c`` (``h = m c``) beyond its mass at
        the flange.
        """
        jacobian, gravity = self.dynamics.jacobian(q), self.dynamics.robot.gravity
        cross = np.array([[0.0, -gravity[2], gravity[1]], [gravity[2], 0.0, -gravity[0]],
                          [-gravity[1], gravity[0], 0.0]])  # fmt: skip
        return jacobian[3:].T @ cross @ self.dynamics.pose(q)[:3, :3]

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
