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

import numpy as np

from leadthrough.control.calibration import CalibrationParameters
from leadthrough.control.dither import DitherParameters
from leadthrough.control.feedforward import measurement_delay
from leadthrough.control.tracking import period_bandwidth
from leadthrough.errors import ParameterError
from leadthrough.estimation.observer import ObserverParameters
from leadthrough.estimation.tool_force import ToolForceParameters
from leadthrough.friction.compensation import CoulombCompensationParameters
from leadthrough.model.description import RobotDescription
from leadthrough.safety.supervisor import SafetyParameters
from leadthrough.validation import real, short

Mode = Literal["passive", "active"]


@dataclass(frozen=True)
class LeadThroughParameters:
    """Parameters of lead-through control.

    Gains are per joint, scaled by the joint's inertia m_ii(q) at the current pose, so
    that every joint responds alike in every pose. Validated here for themselves, and
    against the robot by :meth:`check_robot` when a controller is built.

    Attributes:
        mode: ``"passive"`` (feed-forward only) or ``"active"`` (admittance on top).
        compensation: Coulomb compensation law (ε, q̇₀, q̇₁), thesis §4.2.2.
        dither: Dither settings, or None for no dithering (thesis §5.3).
        calibration: Settings of the start-up calibration (payload, friction levels, gravity
            bias). It only runs when asked for: ``LeadThrough(..., calibrate=True)`` (the
            arm then moves by itself for ``calibration.duration``).
        observer: Kalman observer tuning (thesis §5.2.1, but Q_τ = 100 instead of 10: an
            estimate that lags less leaves the admittance more stability margin, see
            :mod:`leadthrough.experiments.stability`; and no sliding joint lagging a
            torque ramp by more than 20 ms, ``max_lag``: the YuMi's and the Panda's joints
            lag 14–16 ms with Q_τ = 100, the UR10e's shoulder joints, whose friction noise
            is 7× the YuMi's, would lag 52 ms and take Q_τ = 763 instead).
        safety: Safety supervisor limits (SPEC §7).
        tool_force: The joints' estimates read together as a force at the tool
            (:mod:`leadthrough.estimation.tool_force`): a joint that stiction holds takes
            its share of the force the sliding joints read. None keeps each joint's own
            estimate (an operator who pushes the links, not the tool).
        inertia_scale: k_M of M̃ = k_M M(q) [–]. Above 1 on purpose: the estimated operator
            torque lags the true one (observer bandwidth, delay), and an admittance lighter
            than the arm turns that lag into negative damping that a stiff hand makes
            unstable (see :mod:`leadthrough.experiments.stability`). Inertia costs the
            operator little at teaching speeds; damping is what they feel.
        damping_time: D̃ = M(q) / damping_time while guiding (D̃_ii = m_ii(q) / damping_time;
            :func:`~leadthrough.control.admittance.virtual_damping`) [s]: the force the operator
            needs for a given speed; smaller is heavier.
        rest_damping: Once nobody pushes a joint on (its damping weight → 0) its D̃ rises
            smoothly to (1 + rest_damping) times its guiding value [–]: the released arm
            stops instead of coasting, and model error read at rest moves it that much slower.
        push_time: Time over which a push along a joint's motion is averaged to decide
            whether it sustains the motion [s]
            (:func:`~leadthrough.control.admittance.damping_weight`): a residual *against*
            the motion for longer (the operator braking, or the friction the model may
            overstate, which the law reads as drag once the hand lets go) raises the
            damping, so the arm stops instead of coasting on its virtual inertia. Shorter
            than a release's stop, longer than a stiff hand's oscillation (0.2 s at 5 Hz),
            whose alternating sign must not modulate the damping.
        settle_time: Time over which the position reference of a resting joint whose
            admittance rests with no push is drawn to where the joint is [s]
            (:func:`~leadthrough.control.admittance.settled_reference`): the tracking
            spring lets go of the push left when the motion ended, and holds the joint
            where it stopped against a slower creep (a joint that moves on its own is not
            followed).
        unwind_time: Time constant with which the velocity reference of a joint that lags
            behind it (stiction holds the joint, a contact, an end-stop) relaxes towards
            the joint's velocity [s] (:func:`~leadthrough.control.admittance.unwound`):
            the admittance cannot wind up against a joint that does not follow, so the
            PD has no stored push to release when the joint breaks away (stick-slip).
            None never unwinds (the thesis). At 250 Hz and faster; slower, it keeps its
            ratio to ``velocity_time`` (:meth:`at_period`).
        assist_knee: Residual torque, in multiples of the model's uncertainty, of which half
            passes to the admittance [–] (:func:`~leadthrough.control.admittance.operator_weight`);
            0 passes everything (the thesis).
        drive_gain_uncertainty: Relative error of the drives' torque constants [–]: a drive
            that applies 10 % more than it reports makes 10 % of the tracking torque read
            as a push along it (positive feedback); that much of the last tracking torque
            is taken off the estimate, so the error reads as drag instead. (A drive that
            applies less than it reports reads a *braking* tracking torque as a push along
            the motion, which this signed term adds to: design log, *The drive-gain term*.)
            The gravity feed-forward is off by as much (:attr:`gravity_uncertainty`).
        position_bandwidth: K_P_ii = m_ii(q) (2π f)² [Hz]; 0 is damping control (§6.3.1).
        velocity_time: K_D_ii = m_ii(q) / velocity_time [s]: 20 rad/s, below the bandwidth
            of a differenced, filtered velocity (15–40 Hz); a stiffer velocity loop on that
            lagging signal oscillates. At 250 Hz and faster; at a slower rate the
            controller softens it as its delay requires (:meth:`at_period`).
        stiction_margin: Relative Coulomb error at rest that no sigmoid model describes
            (stiction, Stribeck) [–]; part of what the model may read without an operator,
            and the smallest friction error assumed.
        mass_uncertainty: Relative error of the link masses [–]; with the drive gains', the
            gravity error the model may read without an operator
            (:attr:`gravity_uncertainty`). The Coulomb compensation stays below
            ``(1 − friction error) τ_C − gravity_uncertainty |G(q) − G_ref|`` (G_ref: G at
            the calibration's pose on the joints it measured, 0 elsewhere and without one),
            so that a released arm stops.
        torque_ripple: Amplitude of the drives' torque ripple relative to the torque they
            carry [–] (cogging, the gear's kinematic error): a position-periodic error of
            the torque applied that no model of the arm has, part of how far the estimate
            may be off (``LeadThrough.joint_std``: its std, ``torque_ripple / √2`` times the
            motor torque). Not part of what the law may read without an operator: it
            averages out over the admittance's second and runs nothing away (in the law it
            made the Panda heavier, 1.18 → 1.30). 2 %: the benchmark's drives ripple 1–3 %;
            without it the band covered 78 % of the Panda's moving samples (98 % with it)
            and 86 % of a Baxter arm's, whose shoulder carries 43 Nm (96 %).
        friction_uncertainty: Relative error of the friction levels [–]; None takes the
            friction model's own (``FrictionModel.relative_error``). That much of the
            modelled friction is taken off the estimate along the motion, so that a model
            whose friction is too high reads friction, never a push (no runaway).
        unmeasured_friction_error: Relative error of a Coulomb level that nothing measured
            on this arm [–]: how far a robot type's model may be off one unit of it (on
            the plant family, levels ±20 % that vary ±15 % along a joint's travel: 0.68–1.38
            of the model's). With ``friction_uncertainty`` None, a joint the start-up
            calibration did not measure (none without one) takes the larger of this and the
            model's own error; a measured level carries ``calibration.friction_accuracy``.
            A friction model given to the controller counts as identified on this arm (its
            own error stands); 0 trusts the description's model as well.
        bias_time: Time constant of the learned model-error bias [s].
        reanchor_error: Tracking error that re-anchors the references [rad]
            (:func:`~leadthrough.control.admittance.reanchored`).
        limit_zone: Near a joint limit (within this of the hard limit) the references
            stay out and a push *away* from the limit is not taken for the operator's
            (it is the end-stop's reaction) [rad]; in both modes the Coulomb compensation
            fades from two zone widths to one before a limit it pushes a joint towards
            (:class:`~leadthrough.friction.compensation.LimitZone`).
        limit_aware: Whether the controller respects ``limit_zone`` (False reproduces the
            failure of thesis §6.3.2, and compensates up to the limits).
        assist_speed_fraction: The admittance never asks a joint for more than this
            fraction of its speed limit [–] (teaching is slow; the tool speed limit of the
            supervisor stays the last word).
        measurement_delay: Control steps from sending a command to measuring it, an
            integer ≥ 1 [–] (2 on the twin and the thesis' interface: applied one period
            late, measured over the period after). Where the robot measures its motor
            torque, the delay its measurements show replaces it
            (:mod:`~leadthrough.control.interface_delay`, up to 8 periods).
        rest_velocity: A joint slower than this is at rest [rad/s]: the one definition
            of "at rest" (the dither comes on after ``dither.rest_time`` at rest, the
            friction compensation's dead-band widens to it while dithering, and the
            supervisor takes a joint repeating its readings above it for a frozen encoder:
            ``safety.stale_speed``).
    """

    mode: Mode = "active"
    compensation: CoulombCompensationParameters = field(
        default_factory=CoulombCompensationParameters
    )
    dither: DitherParameters | None = field(default_factory=DitherParameters)
    calibration: CalibrationParameters | None = field(default_factory=CalibrationParameters)
    observer: ObserverParameters = field(
        default_factory=lambda: ObserverParameters(torque_noise=100.0, max_lag=0.02)
    )
    safety: SafetyParameters = field(default_factory=SafetyParameters)
    tool_force: ToolForceParameters | None = field(default_factory=ToolForceParameters)
    inertia_scale: float = 2.0
    damping_time: float = 0.5
    push_time: float = 0.1
    settle_time: float = 0.3
    unwind_time: float | None = 0.05
    rest_damping: float = 20.0
    assist_knee: float = 0.5
    drive_gain_uncertainty: float = 0.1
    position_bandwidth: float = 1.0
    velocity_time: float = 0.05
    mass_uncertainty: float = 0.05
    torque_ripple: float = 0.02
    friction_uncertainty: float | None = None
    unmeasured_friction_error: float = 0.35
    stiction_margin: float = 0.05
    bias_time: float = 1.0
    reanchor_error: float = 0.05
    limit_zone: float = 0.2
    limit_aware: bool = True
    assist_speed_fraction: float = 0.3
    measurement_delay: int = 2
    rest_velocity: float = 0.01

    def __post_init__(self) -> None:
        if self.mode not in ("passive", "active"):
            raise ParameterError("mode", f"'passive' or 'active', got {self.mode!r}")
        if not isinstance(self.limit_aware, bool | np.bool_):  # "no" would read as True
            raise ParameterError(
                "limit_aware", f"expected true or false, got {short(self.limit_aware)}"
            )
        positive = ("inertia_scale", "damping_time", "push_time", "settle_time",
                    "velocity_time", "bias_time", "reanchor_error", "limit_zone",
                    "assist_speed_fraction")  # fmt: skip
        for name in positive:
            real(name, getattr(self, name), minimum=0.0, strict=True, error=ParameterError)
        measurement_delay(self.measurement_delay)
        real("rest_velocity", self.rest_velocity, minimum=0.0, strict=True, error=ParameterError)
        if self.assist_speed_fraction > 1.0:
            raise ParameterError("assist_speed_fraction", f"must be in (0, 1], got "
                                 f"{self.assist_speed_fraction:g}")  # fmt: skip
        for name in (
            "position_bandwidth",
            "mass_uncertainty",
            "stiction_margin",
            "rest_damping",
            "assist_knee",
            "drive_gain_uncertainty",
            "unmeasured_friction_error",
            "torque_ripple",
        ):
            real(name, getattr(self, name), minimum=0.0, error=ParameterError)
        if self.unwind_time is not None:
            real("unwind_time", self.unwind_time, minimum=0.0, strict=True, error=ParameterError)
        if self.friction_uncertainty is not None:
            real("friction_uncertainty", self.friction_uncertainty, minimum=0.0,
                 error=ParameterError)  # fmt: skip
        self._check_rest_velocity()

    def _check_rest_velocity(self) -> None:
        """``rest_velocity`` is the one definition of at rest: the dither's, the supervisor's.

        ``dither.moving_velocity`` and ``safety.stale_speed`` follow it; either set to
        another value than its default is refused.
        """
        self._follow_rest_velocity("dither", "moving_velocity", DitherParameters.moving_velocity)
        self._follow_rest_velocity("safety", "stale_speed", SafetyParameters.stale_speed)

    def _follow_rest_velocity(self, table: str, name: str, default: float) -> None:
        """Set ``table.name`` to ``rest_velocity`` unless it was set to something else."""
        settings = getattr(self, table)
        if settings is None or getattr(settings, name) == self.rest_velocity:
            return
        if getattr(settings, name) != default:
            raise ParameterError(f"{table}.{name}", f"{getattr(settings, name):g} differs from "
                                 f"rest_velocity {self.rest_velocity:g}: set rest_velocity only "
                                 "(one definition of at rest)")  # fmt: skip
        object.__setattr__(self, table, dataclasses.replace(settings, **{name: self.rest_velocity}))

    def at_period(self, dt: float) -> LeadThroughParameters:
        """These settings for a control period ``dt`` [s]: the same at 250 Hz and faster.

        The active law tracks its references with ``K_P = m_ii (2π position_bandwidth)²``
        and ``K_D = m_ii / velocity_time``, on a velocity that arrives a period late and
        low-passed. At a slower rate the same gains leave that loop less phase: linearised
        (:func:`~leadthrough.control.tracking.loop_damping`), its least damping ratio falls
        from 0.79 at 250 Hz to 0.66 at 125 Hz and 0.61 at 100 Hz, and the guiding shook up
        to 1.48× and 1.73× passive there (seeds 1–4, the YuMi). So the velocity loop's rate
        ``1 / velocity_time`` is treated as a bandwidth that follows the period
        (:func:`~leadthrough.control.tracking.period_bandwidth`, as the calibration's and
        the replay's do): the fastest up to the one asked for that keeps the damping it
        has at 250 Hz, or, where none does, the most any keeps. With the defaults:
        0.05 s at 250 Hz and faster, 0.081 s at 200 Hz, 0.111 s at 125 Hz, 0.118 s at
        100 Hz. ``unwind_time`` keeps its ratio to it (equal with the defaults): the push
        the PD stores against a joint that does not follow, about ``unwind_time /
        velocity_time`` times the drive over k_M, stays what it is at 250 Hz (with the
        unwinding left at 0.05 s it halved; seeds 5–8 then shook 1.53× and 1.55× passive
        at 125 and 100 Hz, 1.37× and 1.32× with it kept). Apply it once, to the settings
        as given (the controller does: its law's ``parameters`` are the result): the
        damping kept is that of ``velocity_time`` at 250 Hz, so settings already softened
        would be softened again.

        Damping control (``position_bandwidth`` 0, :meth:`damping_control`) is left as
        given: without position feedback the loop's least damping ratio rises without a
        peak as its velocity loop softens, and keeping 250 Hz's would take 0.23 s at 125
        Hz, 0.38 s at 100 Hz and 2 s at 50 Hz, a loop that hardly tracks (not measured).
        """
        if self.position_bandwidth == 0.0:
            return self
        ceiling = 1.0 / (2.0 * np.pi * self.velocity_time)  # the velocity loop's rate [Hz]
        rate = period_bandwidth(ceiling, dt, self.tracking_gains)
        if rate == ceiling:
            return self
        velocity_time = 1.0 / (2.0 * np.pi * rate)
        unwind = self.unwind_time
        if unwind is not None:
            unwind *= velocity_time / self.velocity_time
        return dataclasses.replace(self, velocity_time=velocity_time, unwind_time=unwind)

    def tracking_gains(self, omega: float) -> tuple[float, float, float]:
        """The active law's tracking gains per unit inertia, velocity loop at ``omega`` [1/s].

        ``((2π position_bandwidth)², ω, 0)``: K_P [1/s²], K_D [1/s], no integral
        (:data:`~leadthrough.control.tracking.LoopGains`).
        """
        return (2.0 * np.pi * self.position_bandwidth) ** 2, omega, 0.0

    @property
    def gravity_uncertainty(self) -> float:
        """Relative error of the gravity torque the drives apply [–]: masses and drive gains.

        ``mass_uncertainty + drive_gain_uncertainty``: a torque constant 10 % off applies
        10 % less (or more) of the gravity feed-forward than the model says. The model
        error the operator torque tolerates, the bias may learn, and the Coulomb
        compensation leaves room for is this times G(q) (or its change since the
        calibration measured the error).
        """
        return self.mass_uncertainty + self.drive_gain_uncertainty

    @property
    def gravity_std(self) -> float:
        """Standard deviation of the same relative error [–], for error bands.

        The two bounds are independent errors, each anywhere within ±its bound: the std
        of their sum is ``√(mass² + drive_gain²) / √3`` (0.065 with the defaults, against
        the bound 0.15 that safety margins use).
        """
        return float(np.hypot(self.mass_uncertainty, self.drive_gain_uncertainty) / np.sqrt(3.0))

    def check_robot(self, robot: RobotDescription) -> None:
        """Raise ParameterError (one line) for a setting that does not fit ``robot``.

        The reference bounds ``q_min + limit_zone`` and ``q_max − limit_zone`` must not
        cross, nor the supervisor's soft walls (``safety.soft_limit_margin``).
        """
        span = robot.q_max - robot.q_min
        margins = {"limit_zone": self.limit_zone,
                   "safety.soft_limit_margin": self.safety.soft_limit_margin}  # fmt: skip
        for name, margin in margins.items():
            crossed = np.flatnonzero(2.0 * margin >= span)
            if crossed.size:
                j = crossed[0]
                raise ParameterError(name, f"{margin:g} rad from each limit leaves nothing of "
                                     f"joint {j + 1}'s range of {span[j]:.4g} rad (the bounds "
                                     "would cross)")  # fmt: skip

    @classmethod
    def damping_control(cls, **changes: Any) -> LeadThroughParameters:
        """Preset of thesis §6.3.1: no position feedback (K_P = 0), only damping."""
        return cls(position_bandwidth=0.0, **changes)

    @classmethod
    def thesis_unstable(cls, **changes: Any) -> LeadThroughParameters:
        """The settings of thesis §6.3.2 that turn an end-stop into a runaway.

        Very low virtual damping, full virtual inertia, high PD gains, the whole estimate
        fed to the admittance, no bias learning and references free to run into the
        end-stop.
        """
        return cls(inertia_scale=1.0, damping_time=20.0, rest_damping=0.0, assist_knee=0.0,
                   position_bandwidth=6.0, velocity_time=0.008, mass_uncertainty=0.0,
                   friction_uncertainty=0.0, stiction_margin=0.0, drive_gain_uncertainty=0.0,
                   torque_ripple=0.0, bias_time=1e6,
                   reanchor_error=1e6, unwind_time=None,
                   limit_aware=False, dither=None, **changes)  # fmt: skip

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
           "calibration": CalibrationParameters, "tool_force": ToolForceParameters}  # fmt: skip


def from_dict(kind: type, data: dict[str, Any], where: str, base: Any = None) -> Any:
    """Build the dataclass ``kind`` from ``data``, nested tables included.

    TOML has no null: ``false`` sets a field that may be None to None (a table switched
    off, ``dither = false``, or a setting that is off, ``[dither] creep = false``). Bad
    values name the file and the field. A nested table changes the fields it names of the
    controller's own default for it (``[observer] variant = "two_level"`` keeps the
    guiding observer's Q_τ = 100 and ``max_lag``, not the thesis' ``ObserverParameters()``);
    ``base`` is that default.
    """
    fields = {item.name: item for item in dataclasses.fields(kind)}
    unknown = sorted(set(data) - set(fields))
    if unknown:
        raise ParameterError(f"{where}: {unknown[0]}", "unknown parameter")
    values = {}
    for name, value in data.items():
        nested = _NESTED.get(name) if kind is LeadThroughParameters else None
        if nested is not None and isinstance(value, dict):
            value = from_dict(nested, value, f"{where}: {name}", _default(fields[name]))
        if value is False and _may_be_none(fields[name]):
            value = None
        elif nested is not None and not isinstance(value, nested):
            raise ParameterError(
                f"{where}: {name}",
                f"expected a table [{name}]" + (" or false" if _may_be_none(fields[name]) else ""),
            )
        values[name] = value
    try:
        return kind(**values) if base is None else dataclasses.replace(base, **values)
    except (TypeError, ValueError) as error:
        raise ParameterError(where, str(error)) from None
    except ParameterError as error:
        if error.parameter.startswith(where):
            raise
        raise ParameterError(f"{where}: {error.parameter}", error.reason) from None


def _default(item: dataclasses.Field[Any]) -> Any:
    """The default of a dataclass field (its factory's value), None if it has none."""
    if item.default_factory is not dataclasses.MISSING:
        return item.default_factory()
    return None if item.default is dataclasses.MISSING else item.default


def _may_be_none(item: dataclasses.Field[Any]) -> bool:
    """Whether a dataclass field is annotated ``… | None`` (annotations are strings here)."""
    return "None" in str(item.type).replace(" ", "").split("|")
