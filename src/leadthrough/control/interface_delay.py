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


class InterfaceDelay:
    """The measurement delay the data show (:mod:`leadthrough.control.interface_delay`).

    Each period the controller hands it the torque measured (:meth:`update`) and then the
    command it sends (:meth:`record`).

    Args:
        n: Number of joints.
        delay: The delay assumed until the data show another [periods] (≥ 1).
        dt: Control period [s].
        longest: The longest candidate [periods] (at least ``delay``).
    """

    def __init__(self, n: int, delay: int, dt: float, longest: int = LONGEST) -> None:
        self.delay = measurement_delay(delay)
        self.longest = max(longest, self.delay)
        self._rate = min(dt / MEMORY, 1.0)
        self._scores = np.zeros(self.longest)  # mean |e_L|² of L = 1 … longest [Nm²]
        self._previous = np.full(n, np.nan)  # the last measured torque [Nm]
        self._changes = np.zeros((self.longest, n))  # ring: Δτ_m of period p at p % longest
        self._commands = np.zeros((self.longest + 1, n))  # ring: command j at j % (longest + 1)
        self._sent = 0  # commands recorded: the period's number

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
        return self.delay


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
