"""Online contact detection on the observer's external torque estimate.

Each period the detector takes the estimate τ̂_ext [Nm] and its standard deviation σ
[Nm] (the observer's own std combined with the model's torque uncertainty, see
:mod:`leadthrough.estimation.log_observer`) and works on the normalised residual::

    z = (τ̂_ext − b) / σ                      per joint

where ``b`` is an optional slowly tracked bias (a model error that holds still, e.g. at
a static pose; frozen while an event is open). A contact is a hysteresis episode:

- it opens when any joint has |z| > ``on`` (default 3: a Gaussian false alarm 0.3 % of
  the samples, before the minimum duration);
- it is dated back to the first sample of the run of samples with some |z| > ``off``
  that leads there (the rise of the push, not the moment it became certain);
- it closes at the first sample where every |z| <= ``off`` again;
- it is kept if it lasted at least ``min_duration`` (a one-sample spike is not a
  contact); two events closer than ``merge_gap`` are one.

The event lists the joints whose |z| exceeded ``on`` and, per joint, the signed
estimated torque of largest magnitude over the event (bias removed).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import InputShapeError, ParameterError
from leadthrough.model.description import FloatArray
from leadthrough.validation import real


@dataclass(frozen=True)
class ContactParameters:
    """Thresholds of the contact detector.

    Attributes:
        on: An event opens when |τ̂_ext − b| exceeds ``on`` std on some joint [–].
        off: It closes when every joint is back within ``off`` std [–], < ``on``.
        min_duration: Shortest event kept [s].
        merge_gap: Events separated by less than this are merged [s].
        bias_time: Time constant of the tracked bias ``b`` [s] (None: no bias, b = 0).
            The bias follows τ̂_ext only while no event is open or pending.
    """

    on: float = 3.0
    off: float = 1.5
    min_duration: float = 0.1
    merge_gap: float = 0.2
    bias_time: float | None = None

    def __post_init__(self) -> None:
        real("on", self.on, minimum=0.0, strict=True, error=ParameterError)
        real("off", self.off, minimum=0.0, strict=True, error=ParameterError)
        if self.off >= self.on:
            raise ParameterError("off", f"must be below on ({self.on:g}), got {self.off:g}")
        real("min_duration", self.min_duration, minimum=0.0, error=ParameterError)
        real("merge_gap", self.merge_gap, minimum=0.0, error=ParameterError)
        if self.bias_time is not None:
            real("bias_time", self.bias_time, minimum=0.0, strict=True, error=ParameterError)


@dataclass(frozen=True, eq=False)
class ContactEvent:
    """One detected contact.

    Attributes:
        start: Time of its first sample [s] (the log's time base).
        end: Time of the first sample after it [s].
        joints: Indices (0-based, from the base) of the joints whose estimate crossed the
            ``on`` threshold, in increasing order.
        peak: Per joint, the signed estimated external torque of largest magnitude during
            the event, bias removed [Nm], shape (n,).
        peak_score: Largest |τ̂_ext − b| / σ over the event and the joints [–].
    """

    start: float
    end: float
    joints: tuple[int, ...]
    peak: FloatArray = field(repr=False)
    peak_score: float = 0.0

    @property
    def duration(self) -> float:
        """Length of the event [s]."""
        return self.end - self.start

    @property
    def peak_torque(self) -> float:
        """Largest |estimated external torque| over the joints [Nm]."""
        return float(np.max(np.abs(self.peak)))

    @property
    def joint(self) -> int:
        """The joint (0-based) with the largest estimated torque."""
        return int(np.argmax(np.abs(self.peak)))


@dataclass
class _Open:
    """An episode in progress (pending until it crosses ``on``)."""

    start: float
    peak: FloatArray
    score: FloatArray
    confirmed: bool = False


class ContactDetector:
    """Hysteresis contact detector fed once per period (see the module docstring).

    Args:
        n_joints: Number of joints n.
        parameters: Thresholds; keyword arguments override single fields.
    """

    def __init__(
        self, n_joints: int, parameters: ContactParameters | None = None, **overrides: float
    ) -> None:
        parameters = parameters or ContactParameters()
        if overrides:
            unknown = sorted(set(overrides) - set(parameters.__dict__))
            if unknown:
                raise ParameterError(unknown[0], "unknown contact detector parameter")
            parameters = ContactParameters(**{**parameters.__dict__, **overrides})
        self.parameters = parameters
        self.n = int(n_joints)
        self.events: list[ContactEvent] = []
        self.bias = np.zeros(self.n)
        self._open: _Open | None = None
        self._last_t: float | None = None

    @property
    def active(self) -> bool:
        """Whether a confirmed contact is in progress."""
        return self._open is not None and self._open.confirmed

    def update(self, t: float, tau_ext: ArrayLike, std: ArrayLike) -> ContactEvent | None:
        """Feed one period; returns the event that closed at this sample, if any.

        Args:
            t: Time of the sample [s], increasing.
            tau_ext: Estimated external torque [Nm], shape (n,).
            std: Its standard deviation [Nm], shape (n,), > 0.
        """
        tau_ext, std = self._vector(tau_ext, "tau_ext"), self._vector(std, "std")
        residual = tau_ext - self.bias
        score = np.abs(residual) / np.maximum(std, 1e-12)
        p = self.parameters
        closed = None
        if self._open is None:
            if np.any(score > p.off):
                self._open = _Open(t, residual.copy(), score.copy())
            else:
                self._track_bias(t, tau_ext)
        else:
            episode = self._open
            if np.all(score <= p.off):
                closed = self._close(t)
            else:
                larger = np.abs(residual) > np.abs(episode.peak)
                episode.peak = np.where(larger, residual, episode.peak)
                episode.score = np.maximum(episode.score, score)
        if self._open is not None and np.any(score > p.on):
            self._open.confirmed = True
            self._open.score = np.maximum(self._open.score, score)
            larger = np.abs(residual) > np.abs(self._open.peak)
            self._open.peak = np.where(larger, residual, self._open.peak)
        self._last_t = t
        return closed

    def finish(self, t: float | None = None) -> ContactEvent | None:
        """Close an event still open at the end of the data (at ``t`` or the last sample)."""
        if self._open is None:
            return None
        end = t if t is not None else self._last_t
        return self._close(float(end if end is not None else self._open.start))

    def _close(self, t: float) -> ContactEvent | None:
        episode, self._open = self._open, None
        assert episode is not None
        p = self.parameters
        if not episode.confirmed or t - episode.start < p.min_duration:
            return None
        joints = tuple(int(j) for j in np.flatnonzero(episode.score > p.on))
        event = ContactEvent(episode.start, t, joints, episode.peak, float(episode.score.max()))
        if self.events and event.start - self.events[-1].end < p.merge_gap:
            event = _merged(self.events.pop(), event)
        self.events.append(event)
        return event

    def _track_bias(self, t: float, tau_ext: FloatArray) -> None:
        time_constant = self.parameters.bias_time
        if time_constant is None or self._last_t is None:
            return
        weight = min(1.0, (t - self._last_t) / time_constant)
        self.bias += weight * (tau_ext - self.bias)

    def _vector(self, value: ArrayLike, name: str) -> FloatArray:
        array = np.asarray(value, dtype=float)
        if array.shape != (self.n,):
            raise InputShapeError(name, (self.n,), array.shape)
        return array


def _merged(first: ContactEvent, second: ContactEvent) -> ContactEvent:
    """One event spanning two close ones (joints united, peaks of larger magnitude)."""
    larger = np.abs(second.peak) > np.abs(first.peak)
    joints = tuple(sorted(set(first.joints) | set(second.joints)))
    peak = np.where(larger, second.peak, first.peak)
    return ContactEvent(first.start, second.end, joints, peak,
                        max(first.peak_score, second.peak_score))  # fmt: skip
