"""The drive interface's delay, read from the data: which command the measured torque holds.

A motor torque measured at period k holds the command sent ``d`` periods before (``d ≥ 1``:
one period to apply a command and one to measure it on the twin and the thesis' interface,
more behind a bus or a drive that filters). The controller takes the dither that command
held off the observer's input (the dither is the controller's own torque, not the
operator's) and reads the measurement's offset against it while it calibrates. With ``d``
one period wrong, every edge of the dither reaches the observer as a one-period pulse of
twice its amplitude, which the observer reads as pushes; with the dither's twitches they
walk a released arm on (a LuGre plant with two periods of delay, where the default
``measurement_delay`` of 2 expects one: a resting joint slipped 2.4 mrad over 10 s,
0.65 mrad with the delay right).

The measured torque is the command plus what the drive adds (an offset, ripple, noise, a
gain error times the command): ``τ_m(k) ≈ c(k − d) + o``. From one period to the next,
less the change of the command sent ``L`` periods before,

    e_L(k) = Δτ_m(k) − Δc(k − L)        (Δx(k) = x(k) − x(k − 1))

is the drive's noise for ``L = d`` and carries every step of the commands otherwise. Each
candidate ``L`` keeps the mean of ``|e_L|²`` (over the joints, averaged over
:data:`MEMORY` s); the delay is the candidate with the least, taken only where it stands
out: its mean below :data:`EVIDENCE` times the delay in use's. Commands that do not
change tell nothing and every candidate then scores alike, so the delay stays.

**The measurement's sign.** A measured torque of the other sign convention than the
command's is not the torque the arm got: the observer reads twice the command as a push and
active mode follows it (a YuMi and a Panda fed the other sign turned 2.1 and 1.8 rad in 5 s
with nobody touching; a review). Each joint's command (sent ``delay`` periods before) and
measured torque are compared as levels over :data:`MEMORY` s (:func:`_fit`: their means,
variances and covariance). They move with gravity, the hand and the dither, far more than
with a period's error in the delay; where the command itself moves by at least
``floor`` (a tenth of the joint's Coulomb level) and a tenth of its mean level
(:data:`RIPPLE_SHARE`: the drives' ripple, 2 % of a joint's torque, is then small beside
it), a correlation ``≤ −`` :data:`SURE` with a slope
below ``−`` :data:`SLOPE` is the other sign: :meth:`InterfaceDelay.gain_problem`, once
:data:`JUDGED` s of samples are in (a fault of the controller). Compared period to period
instead (tried), the ripple of a loaded UR10e joint and a Panda's tracking ringing at 1 kHz
(the command's change alternating in sign, one period off) made slopes of +48 and −0.9;
a scale check on the levels (a slope outside 0.5–2: the motor side of a gear, another
torque constant) faulted a UR10e's elbow whose command barely moved against its ripple
(+2.5), and was left out.
"""

from __future__ import annotations

import math

import numpy as np

from leadthrough.compiled import kernel
from leadthrough.control.feedforward import measurement_delay
from leadthrough.model.description import FloatArray

#: The longest delay looked for [periods]: 32 ms at 250 Hz, 8 ms at 1 kHz.
LONGEST = 8
#: Time over which each candidate's mean square error is averaged [s].
MEMORY = 1.0
#: A candidate replaces the delay in use when its mean square error is below this share
#: of the one in use [–].
EVIDENCE = 0.25
#: Command changes scored before any decision [–]. Two candidates that see noise alone
#: differ by a ratio of two χ² of 7 × this many degrees of freedom (a 7-joint arm), below
#: :data:`EVIDENCE` with a chance of 5·10⁻¹⁹; deciding from the first change on, one of
#: seven wrong candidates beats the right one that way with a chance of 27 % (the twin's
#: dry #4, measured two periods after sending, was taken for four at its first change).
SCORED = 25
#: The correlation of command and measured levels taken as sure [–].
SURE = 0.9
#: The least slope of a measurement of the other sign [–]: a drive's gain is 1 ± 0.1–0.3.
SLOPE = 0.5
#: A command is judged where its std is at least this share of its mean level too [–]: five
#: times a drive's torque ripple of 2 %, which moves with the joint as the command may.
RIPPLE_SHARE = 0.1
#: Time of samples before the levels are judged [s].
JUDGED = 0.25


class InterfaceDelay:
    """The measurement delay the data show (:mod:`leadthrough.control.interface_delay`).

    Each period the controller hands it the torque measured (:meth:`update`) and then the
    command it sends (:meth:`record`).

    Args:
        n: Number of joints.
        delay: The delay assumed until the data show another [periods] (≥ 1).
        dt: Control period [s].
        longest: The longest candidate [periods] (at least ``delay``).
        floor: Per joint, the least std of the command over :data:`MEMORY` for its sign to
            be judged [Nm] (None: 0.1 Nm).
    """

    def __init__(
        self, n: int, delay: int, dt: float, longest: int = LONGEST, floor: FloatArray | None = None
    ) -> None:
        self.delay = measurement_delay(delay)
        self.longest = max(longest, self.delay)
        self._rate = min(dt / MEMORY, 1.0)
        self._scores = np.zeros(self.longest)  # mean |e_L|² of L = 1 … longest [Nm²]
        self._previous = np.full(n, np.nan)  # the last measured torque [Nm]
        self._changes = np.zeros((self.longest, n))  # ring: Δτ_m of period p at p % longest
        self._commands = np.zeros((self.longest + 1, n))  # ring: command j at j % (longest + 1)
        self._sent = 0  # commands recorded: the period's number
        #: per joint, the means of c, τ_m, c², c τ_m and τ_m² at the delay in use
        #: (:func:`_fit`), and the samples they hold
        self._moments = np.zeros((6, n))
        self._judged = max(round(JUDGED / dt), 2)  # samples before a judgement
        self._floor = np.full(n, 0.1) if floor is None else np.array(floor, dtype=float)
        self._implausible = -1  # the first joint whose gain is surely implausible (-1: none)

    def record(self, command: FloatArray) -> None:
        """The command sent this period [Nm], (n,)."""
        self._commands[self._sent % self._commands.shape[0]] = command
        self._sent += 1

    def update(self, tau_measured: FloatArray) -> int:
        """Take this period's measured torque [Nm], (n,); the delay the data show so far.

        Every candidate is scored on the same command change, the oldest one that all of
        them have seen measured: ``Δc(k − longest)`` against ``Δτ_m(k − longest + L)``
        (:func:`_score`). Scored on the latest changes instead, a candidate that has not
        seen a change yet scores nothing and looks best
        (``tests/test_interface_delay.py``). Nothing is scored before the controller has
        sent every command compared: a change from the zeros of its start is one from a
        torque the drive held before, which it did not send; no decision before
        :data:`SCORED` changes are scored.
        """
        self.delay = _score(self._changes, self._commands, self._scores, self._previous,
                            tau_measured, self._sent, self._rate, self.delay)  # fmt: skip
        self._implausible = _fit(self._moments, self._commands, tau_measured, self._sent,
                                 self._rate, self.delay, self._judged, self._floor, SURE,
                                 SLOPE)  # fmt: skip
        return self.delay

    @property
    def gain(self) -> FloatArray:
        """Each joint's measured torque per command, the levels' slope so far [–] (NaN: none)."""
        weight = 1.0 - (1.0 - self._rate) ** self._moments[5]  # as in _fit
        with np.errstate(invalid="ignore", divide="ignore"):
            mean_c, mean_m, square_c, cross = self._moments[:4] / weight
            variance = square_c - mean_c**2
            return np.where(variance > 0.0, (cross - mean_c * mean_m) / variance, np.nan)

    def gain_problem(self) -> str | None:
        """One line naming a joint whose measured torque surely has the other sign.

        Its levels are correlated ``≤ −SURE`` with a slope below ``−SLOPE``, after
        :data:`JUDGED` s of samples where its command moved (None: none, or not known yet).
        """
        j = self._implausible
        if j < 0:
            return None
        return (f"joint {j + 1}'s measured torque falls as its command rises ({self.gain[j]:+.2f}"
                "×): not the torque the arm gets (the other sign convention?)")  # fmt: skip


@kernel
def _score(
    changes: FloatArray, commands: FloatArray, scores: FloatArray, previous: FloatArray,
    tau: FloatArray, period: int, rate: float, delay: int,
) -> int:  # fmt: skip
    """One period of :class:`InterfaceDelay`: store Δτ_m, score the candidates, decide.

    ``changes``, ``scores`` and ``previous`` are updated in place. ``period`` counts the
    commands recorded before this measured torque (this period's comes after it). A
    torque that is not finite is stored as NaN and every score that would read it is
    skipped, as the changes of the first period.
    """
    longest, n = changes.shape
    history = longest + 1
    for j in range(n):
        changes[period % longest, j] = tau[j] - previous[j]
        previous[j] = tau[j]
    if period < history:
        return delay
    old, older = (period - longest) % history, (period - longest - 1) % history
    for row in range(longest):  # a change not to use (NaN) would poison every score
        for j in range(n):
            if not math.isfinite(changes[row, j] - commands[old, j] + commands[older, j]):
                return delay
    best = 0
    for candidate in range(longest):  # candidate + 1 periods of delay
        row = (period + candidate + 1) % longest  # Δτ_m of period − longest + candidate + 1
        total = 0.0
        for j in range(n):
            error = changes[row, j] - (commands[old, j] - commands[older, j])
            total += error * error
        scores[candidate] += rate * (total - scores[candidate])
        if scores[candidate] < scores[best]:
            best = candidate
    if period - history + 1 >= SCORED and scores[best] < EVIDENCE * scores[delay - 1]:
        return best + 1
    return delay


@kernel
def _fit(
    moments: FloatArray, commands: FloatArray, tau: FloatArray, period: int, rate: float,
    delay: int, judged: int, floor: FloatArray, sure: float, slope: float,
) -> int:  # fmt: skip
    """Each joint's means of c, τ_m, c², c τ_m, τ_m² at ``delay``, in place; a joint off.

    ``τ_m`` is this period's measured torque and ``c`` the command sent ``delay`` periods
    before; a measurement not finite adds nothing. Row 5 counts the samples taken. Returns
    the first joint whose levels, after ``judged`` samples and with the command's std at
    least ``floor`` and :data:`RIPPLE_SHARE` of its mean, are correlated ``≤ −sure`` with
    a slope below ``−slope``; -1 if none.
    """
    history, n = commands.shape
    if period < delay:
        return -1
    sent = (period - delay) % history
    implausible = -1
    for j in range(n):
        command, measured = commands[sent, j], tau[j]
        if math.isfinite(measured):
            moments[0, j] += rate * (command - moments[0, j])
            moments[1, j] += rate * (measured - moments[1, j])
            moments[2, j] += rate * (command * command - moments[2, j])
            moments[3, j] += rate * (command * measured - moments[3, j])
            moments[4, j] += rate * (measured * measured - moments[4, j])
            moments[5, j] += 1.0
        if implausible >= 0 or moments[5, j] < judged:
            continue
        # each running mean starts from 0: divided by 1 − (1 − rate)^samples, it is the
        # weighted mean of the samples taken
        weight = 1.0 - (1.0 - rate) ** moments[5, j]
        mean_c, mean_m = moments[0, j] / weight, moments[1, j] / weight
        variance_c = moments[2, j] / weight - mean_c * mean_c
        variance_m = moments[4, j] / weight - mean_m * mean_m
        covariance = moments[3, j] / weight - mean_c * mean_m
        least = max(floor[j], RIPPLE_SHARE * abs(mean_c))  # the ripple is a share of c
        if variance_c < least * least or variance_m <= 0.0:
            continue
        correlation = covariance / math.sqrt(variance_c * variance_m)
        if correlation <= -sure and covariance / variance_c < -slope:
            implausible = j
    return implausible
