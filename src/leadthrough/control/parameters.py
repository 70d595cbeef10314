"""Every parameter of :class:`~leadthrough.control.lead_through.LeadThrough`, declared once.

One frozen, validated dataclass (nested for the components), loadable from TOML::

    mode = "active"
    inertia_scale = 0.3
    [compensation]
    fraction = 0.7
    [dither]
    frequency = 15.0
    [observer]
    variant = "time_varying"
    [safety]
    tool_speed_limit = 0.25
"""

from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from leadthrough.control.calibration import CalibrationParameters
from leadthrough.control.dither import DitherParameters
from leadthrough.errors import ParameterError
from leadthrough.estimation.observer import ObserverParameters
from leadthrough.friction.compensation import CoulombCompensationParameters
from leadthrough.safety.supervisor import SafetyParameters
from leadthrough.validation import real

Mode = Literal["passive", "active"]


@dataclass(frozen=True)
class LeadThroughParameters:
    """Parameters of lead-through control.

    Gains are per joint, scaled by the joint's inertia m_ii at the home pose so that
    every joint responds alike.

    Attributes:
        mode: ``"passive"`` (feed-forward only) or ``"active"`` (admittance on top).
        compensation: Coulomb compensation law (ε, q̇₀, q̇₁), thesis §4.2.2.
        dither: Dither settings, or None for no dithering (thesis §5.3).
        calibration: Start-up calibration (payload, friction levels, gravity bias), or None
            to start guiding at once with the model as given.
        observer: Kalman observer tuning (thesis §5.2.1).
        safety: Safety supervisor limits (SPEC §7).
        inertia_scale: k_M of M̃ = k_M M(q) [–]: how heavy the arm feels.
        damping_time: D̃_ii = m_ii / damping_time [s]: how long the virtual arm coasts;
            smaller is more damped.
        position_bandwidth: K_P_ii = m_ii (2π f)² [Hz]; 0 is damping control (§6.3.1).
        velocity_time: K_D_ii = m_ii / velocity_time [s].
        coulomb_speed: Floor of the virtual damping, D̃_ii ≥ τ_C,i / coulomb_speed [rad/s]: a
            push of one Coulomb level never asks for more than this speed (keeps the light
            wrist joints from twitching on small estimation errors).
        stiction_margin: Smallest relative Coulomb error the dead-zone assumes [–]: the
            stiction and Stribeck rise that no sigmoid model describes.
        mass_uncertainty: Relative error of the link masses the dead-zone tolerates [–].
        friction_uncertainty: Relative error of the Coulomb levels the dead-zone tolerates
            [–]; None takes the friction model's own (``FrictionModel.relative_error``).
        bias_time: Time constant of the learned model-error bias [s].
        reanchor_error: Tracking error that re-anchors the references [rad].
        limit_zone: Near a joint limit (within this of the hard limit) the references
            stay out and a push *away* from the limit is not taken for the operator's
            (it is the end-stop's reaction) [rad].
        limit_aware: Whether the admittance respects ``limit_zone`` (False reproduces the
            failure of thesis §6.3.2).
        assist_only: The feedback only ever pushes the way the operator pushes; braking is
            left to friction, as in passive mode (False: the thesis' PD, which also brakes
            when the virtual damping asks for it, Fig. 6.4).
        assist_speed_fraction: The admittance never asks a joint for more than this
            fraction of its speed limit [–] (teaching is slow; the tool speed limit of the
            supervisor stays the last word).
        release_time: No operator torque on any joint for this long means the operator let
            go: the arm is braked to a stop [s].
        require_motion: Assist only joints moving the way the estimate pushes and, while
            one does, joints at rest (at rest the observer is nearly blind and reads model
            error, end-stops and contacts: with nothing moving, nothing is assisted).
        measurement_delay: Control steps from sending a command to measuring it [–].
    """

    mode: Mode = "active"
    compensation: CoulombCompensationParameters = field(
        default_factory=CoulombCompensationParameters
    )
    dither: DitherParameters | None = field(default_factory=DitherParameters)
    calibration: CalibrationParameters | None = field(default_factory=CalibrationParameters)
    observer: ObserverParameters = field(default_factory=ObserverParameters)
    safety: SafetyParameters = field(default_factory=SafetyParameters)
    inertia_scale: float = 0.3
    damping_time: float = 3.0
    position_bandwidth: float = 1.0
    velocity_time: float = 0.02
    mass_uncertainty: float = 0.05
    friction_uncertainty: float | None = None
    coulomb_speed: float = 10.0
    stiction_margin: float = 0.05
    bias_time: float = 1.0
    reanchor_error: float = 0.05
    limit_zone: float = 0.2
    limit_aware: bool = True
    assist_only: bool = True
    assist_speed_fraction: float = 0.3
    release_time: float = 0.15
    require_motion: bool = True
    measurement_delay: int = 2

    def __post_init__(self) -> None:
        if self.mode not in ("passive", "active"):
            raise ParameterError("mode", f"'passive' or 'active', got {self.mode!r}")
        positive = ("inertia_scale", "damping_time", "velocity_time", "bias_time",
                    "reanchor_error", "limit_zone", "coulomb_speed",
                    "assist_speed_fraction", "release_time")  # fmt: skip
        for name in positive:
            real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)
        for name in (
            "position_bandwidth",
            "mass_uncertainty",
            "measurement_delay",
            "stiction_margin",
        ):
            real(name, getattr(self, name), minimum=0.0, error=ParameterError)
        if self.friction_uncertainty is not None:
            real("friction_uncertainty", self.friction_uncertainty, minimum=0.0,
                 error=ParameterError)  # fmt: skip

    @classmethod
    def damping_control(cls, **changes: Any) -> LeadThroughParameters:
        """Preset of thesis §6.3.1: no position feedback (K_P = 0), only damping."""
        return cls(position_bandwidth=0.0, **changes)

    @classmethod
    def thesis_unstable(cls, **changes: Any) -> LeadThroughParameters:
        """The settings of thesis §6.3.2 that turn an end-stop into a runaway.

        Very low virtual damping, full virtual inertia, high PD gains, no dead-zone, no
        bias learning and references free to run into the end-stop.
        """
        return cls(inertia_scale=1.0, damping_time=20.0, position_bandwidth=6.0,
                   velocity_time=0.008, mass_uncertainty=0.0, friction_uncertainty=0.0,
                   bias_time=1e6, reanchor_error=1e6, limit_aware=False, dither=None,
                   assist_only=False, require_motion=False, release_time=1e6,
                   **changes)  # fmt: skip

    @classmethod
    def from_toml(cls, path: str | Path) -> LeadThroughParameters:
        """Load from a TOML file; unknown keys and bad values name the field."""
        try:
            data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
            raise ParameterError(str(path), f"cannot read parameters: {error}") from None
        return from_dict(cls, data, str(path))


_NESTED = {"compensation": CoulombCompensationParameters, "dither": DitherParameters,
           "observer": ObserverParameters, "safety": SafetyParameters,
           "calibration": CalibrationParameters}  # fmt: skip
#: Nested tables that ``false`` switches off.
_OPTIONAL = ("dither", "calibration")


def from_dict(kind: type, data: dict[str, Any], where: str) -> Any:
    """Build the dataclass ``kind`` from ``data``, nested tables included."""
    known = {item.name for item in dataclasses.fields(kind)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise ParameterError(f"{where}: {unknown[0]}", "unknown parameter")
    values = {}
    for name, value in data.items():
        nested = _NESTED.get(name) if kind is LeadThroughParameters else None
        if nested is not None and isinstance(value, dict):
            value = from_dict(nested, value, f"{where}: {name}")
        if name in _OPTIONAL and value is False:
            value = None
        values[name] = value
    try:
        return kind(**values)
    except TypeError as error:
        raise ParameterError(where, str(error)) from None
