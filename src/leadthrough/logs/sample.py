"""One sample of a robot's joint sensors, with the robot's own time stamp (SPEC §10).

The one time base of a control period: every component of a controller takes the
time of the period from the sample (``state.t``), whatever its origin (zero at
start-up, or a Unix clock of 1.7e9 s).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import ParameterError
from leadthrough.validation import FloatArray


@dataclass(frozen=True, eq=False)
class JointState:
    """One sample of the joint sensors.

    Attributes:
        t: Time of the sample on the robot's clock [s] (any origin).
        q: Joint readings (encoders, quantised) [rad], shape (n,).
        qd: Joint velocities as the robot reports them (noisy) [rad/s], shape (n,).
        tau_measured: Motor torque actually applied, as measured, arm side [Nm], shape (n,),
            or None (the default) for a robot that measures none.
        enabling: The hand-guiding enabling device that ISO 10218-1 asks of hand
            guiding, as the robot reports it: True while it is held, False while it is
            released, None for a robot without one. One that only a hand on the arm can
            hold (a button on the tool or a handle), not a pendant's: held, active mode
            relies on that hand (``ActiveLaw.use_enabling``).
    """

    t: float
    q: FloatArray
    qd: FloatArray
    tau_measured: FloatArray | None = None
    enabling: bool | None = None


def joint_state(
    state: JointState | ArrayLike,
    qd: ArrayLike | None,
    tau_measured: ArrayLike | None,
    t: float,
) -> JointState:
    """The sample of a controller's ``step(state)`` or ``step(q, qd, tau_measured)``.

    Args:
        state: The robot's sample; or the joint readings q [rad] (positional form).
        qd: Positional form only: joint velocities [rad/s].
        tau_measured: Positional form only: measured motor torque [Nm], or None.
        t: Time stamp of a positional sample [s] (the controller's own clock).

    Raises:
        ParameterError: A JointState with more arguments, or q without qd. Readings that
            are not numbers are returned as given: the safety check names them.
    """
    if isinstance(state, JointState):
        if qd is not None or tau_measured is not None:
            raise ParameterError("step", "give a JointState alone, or q, qd, tau_measured")
        return state
    if qd is None:
        raise ParameterError("step", "needs a JointState, or q and qd")
    tau = None if tau_measured is None else _readings(tau_measured)
    return JointState(t, _readings(state), _readings(qd), tau)


def _readings(value: ArrayLike) -> FloatArray:
    """``value`` as floats; as given when it is not numbers, for the safety check to name.

    The supervisor's check of the sample then latches the fault, as for a JointState.
    """
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return cast(FloatArray, value)


def enabling_state(value: object) -> bool | None:
    """A sample's enabling device as True (held), False (released) or None (no device).

    A driver may give its digital input as a bool, a NumPy bool or the integers 0 / 1.

    Raises:
        ValueError: Anything else (a float, even 1.0; NaN, a string): one line naming it.
    """
    if value is None:
        return None
    if isinstance(value, bool | np.bool_ | int | np.integer) and value in (0, 1):
        return bool(value)
    raise ValueError(f"enabling device reading {value!r} is not True, False or None")
