"""Lead-through control: passive and active, behind the safety supervisor (SPEC §4, §6, §7).

One step, in order, on the robot's sample (its time stamp is the one clock):

1. the supervisor checks the sensor sample (a bad one → the safe stop, this period);
   the model of the arm at it is computed once (:meth:`Dynamics.snapshot`: G, M, Cᵀq̇,
   the TCP Jacobian and pose; G with the start-up calibration's correction) and handed
   to every step below;
2. the Kalman observer estimates ``τ̂_ext`` from the measured torque (or the command
   sent, if the robot measures none), dither removed, each joint alone; the joints'
   estimates are then read together as a force at the tool
   (:mod:`~leadthrough.estimation.tool_force`): a joint that stiction holds takes its
   share of the force the sliding joints read;
3. the operator torque: model error must not become motion (a learned bias and the
   friction the model may overstate removed, the rest weighed by the model's own
   uncertainty; :class:`~leadthrough.control.active_law.ActiveLaw`);
4. active mode: the admittance model turns it (plus virtual constraints) into references,
   tracked by a PD whose gains follow M(q) (thesis eqs. 6.4–6.6; the same
   :class:`~leadthrough.control.active_law.ActiveLaw`);
5. feed-forward ``τ_ff = G(q) + τ_fc(q̇) + dither`` (thesis eq. 6.3, §5.3), the Coulomb
   compensation below the friction surely there minus the gravity error that may be (in
   active mode once a start-up calibration has been accepted, ``follow_push``, a joint
   below the compensation's velocity ramp is compensated as surely, and in the direction,
   as the admittance reads a push);
6. the supervisor limits the command (torque, joint and TCP speed, soft walls).

An exception in any of these latches the supervisor's fault naming the exception and
the component, and the safe stop is sent in the same period.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from leadthrough.compiled import kernel
from leadthrough.control.active_law import ActiveLaw
from leadthrough.control.calibration import (
    Calibration,
    CalibrationParameters,
    CalibrationRun,
    gravity_share,
)
from leadthrough.control.constraints import VirtualConstraint, constraint_torque
from leadthrough.control.feedforward import DelayLine, FeedForwardTorques, PassiveFeedForward
from leadthrough.control.interface_delay import InterfaceDelay
from leadthrough.control.parameters import LeadThroughParameters, Mode
from leadthrough.control.ticks import TickClock
from leadthrough.control.warm_up import exercise
from leadthrough.errors import ParameterError, failure
from leadthrough.estimation.observer import MomentumObserver
from leadthrough.estimation.tool_force import ToolForceFusion
from leadthrough.estimation.wrench import ToolWrench, tool_wrench
from leadthrough.friction.measured_level import MeasuredLevelError
from leadthrough.friction.model import FrictionModel
from leadthrough.logs.sample import JointState, enabling_state, joint_state
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.model.dynamics import Dynamics
from leadthrough.model.snapshot import ModelSnapshot
from leadthrough.safety.checks import seconds
from leadthrough.safety.supervisor import SafetySupervisor, SupervisorState
from leadthrough.validation import real

#: Why a calibration stops when the enabling device is held while it runs: the device is
#: one only a hand on the arm can hold, and the calibration reads the arm alone.
HELD_WHILE_CALIBRATING = ("the enabling device was held while the arm calibrated: was the "
                          "arm touched? Nobody may touch it")  # fmt: skip


class LeadThrough:
    """Hand-guiding controller: ``tau_cmd = ctl.step(state)`` once per period.

    ``state`` is the robot's sample (:class:`~leadthrough.logs.sample.JointState`: t, q,
    q̇, τ_measured) and its time stamp is the controller's one clock: the dither, the
    calibration, the supervisor's events and its safe stop all take time from it. The
    positional form ``step(q, qd, tau_measured=None)`` also works; time is then the
    controller's own count of periods of ``dt``.

    Args:
        robot: The arm (its ``tcp`` is where the tool speed limit, the constraints and
            :attr:`tool_wrench` act).
        mode: ``"passive"`` or ``"active"`` (overrides ``parameters.mode``).
        dt: Control period [s]; must be the robot's (``control_loop`` checks it), and at
            most ``parameters.safety.max_time_gap`` (0.25 s).
        friction: Friction model identified on this arm (``leadthrough identify``): its own
            ``relative_error`` stands on every joint. Default the description's, the robot
            type's model: a joint's level that the start-up calibration did not measure is
            then known to ``parameters.unmeasured_friction_error`` only.
        parameters: All other settings, validated against ``robot`` here.
        constraints: Virtual constraints on the tool.
        calibrate: Run the start-up calibration (``parameters.calibration``) first: the
            arm then moves by itself for :attr:`calibration_time` (nobody may touch it)
            before guiding starts. Off by default: the arm does not move unless asked.

    Raises:
        ParameterError: A setting that does not fit the robot (one line naming it).
    """

    #: The law of active mode (and of the operator torque in both modes); a subclass of
    #: :class:`~leadthrough.control.active_law.ActiveLaw` changes it (experiments).
    law_class: type[ActiveLaw] = ActiveLaw

    def __init__(
        self,
        robot: RobotDescription,
        mode: Mode | None = None,
        dt: float = 0.004,
        friction: FrictionModel | None = None,
        parameters: LeadThroughParameters | None = None,
        constraints: Sequence[VirtualConstraint] = (),
        calibrate: bool = False,
    ) -> None:
        parameters = parameters or LeadThroughParameters()
        if mode is not None and mode != parameters.mode:
            parameters = LeadThroughParameters(**{**parameters.__dict__, "mode": mode})
        parameters.check_robot(robot)
        if calibrate and parameters.calibration is None:
            raise ParameterError("calibrate", "True needs parameters.calibration (it is None)")
        self.parameters = parameters
        self._gravity_std = parameters.gravity_std  # [–], a property: read once
        self._ripple_share = parameters.torque_ripple / math.sqrt(2.0)  # [–] (joint_std)
        self.robot = robot
        #: the description with the payload :meth:`set_payload` gave: what :meth:`reset`
        #: and the calibration build on
        self._carrying = robot
        self.dt = real("dt", dt, minimum=0.0, strict=True, error=ParameterError)
        self._given_friction = friction is not None
        friction = friction or FrictionModel.from_robot(robot)
        if friction.n_joints != robot.n_joints:
            raise ParameterError("friction", f"has {friction.n_joints} joints, the robot "
                                             f"{robot.n_joints}")  # fmt: skip
        #: which joints' friction levels were measured on this arm: those a given model
        #: states (``FrictionModel.identified``), all of one that does not, none of the
        #: description's
        self._identified = np.full(robot.n_joints, self._given_friction)
        if self._given_friction and friction.identified is not None:
            self._identified = friction.identified.copy()
        self.nominal_friction = friction
        self.constraints = tuple(constraints)
        for constraint in self.constraints:
            if not isinstance(constraint, VirtualConstraint):
                raise ParameterError("constraints", f"expected VirtualConstraint objects, got "
                                     f"{type(constraint).__name__}")  # fmt: skip
        self.calibrate = bool(calibrate)
        calibration = parameters.calibration  # at this period: computed once, here
        self._calibration_parameters = (None if calibration is None
                                        else calibration.at_period(self.dt))  # fmt: skip
        # which joints' calibration loops need the prediction: decided here, not in the
        # first control period of the run (~30 linearisations, and SciPy's import)
        self._calibration_damping = None
        if self.calibrate and self._calibration_parameters is not None:
            self._calibration_damping = self._calibration_parameters.decaying_damping(self.dt)
        self.supervisor = SafetySupervisor(Dynamics(robot), dt, parameters.safety)
        self.law = self.law_class(robot, parameters, self.dt, friction)
        self.reset()

    def _build(
        self,
        robot: RobotDescription,
        friction: FrictionModel,
        measured: NDArray[np.bool_] | None = None,
    ) -> None:
        """The model-based parts, for the model of ``robot`` (and a payload) and ``friction``.

        ``measured``: the joints whose friction level was measured on this arm (None: those
        of the friction model the controller was given, all or none).
        """
        measured = self._identified if measured is None else measured
        p = self.parameters
        current = getattr(self, "dynamics", None)  # a calibration without a payload keeps it
        if current is None or current.robot is not robot:
            self.dynamics = Dynamics(robot)
        self.supervisor.use_model(self.dynamics)  # one model: robot and dynamics agree
        self.friction, self._friction_measured = friction, measured
        self.law.use_friction(friction, measured)
        dither = None if p.dither is None else p.dither.for_mode(p.mode)
        self.feed_forward = PassiveFeedForward(self.dynamics, friction, self.dt, p.compensation,
            dither, measurement_delay=None, friction_error=self.law.friction_error,
            gravity_uncertainty=p.gravity_uncertainty,
            limit_zone=p.limit_zone if p.limit_aware else None)  # fmt: skip
        # the observer's band states each level's error as the law bounds it: a level
        # nobody measured on this arm is known to ``unmeasured_friction_error`` only
        known = dataclasses.replace(friction, relative_error=self.law.friction_error)
        self.observer = MomentumObserver(self.dynamics, known, self.dt, p.observer)
        self.fusion = None if p.tool_force is None else ToolForceFusion(friction, p.tool_force)
        # the enabling device's state the law and the compensation were last set for
        # (``_control`` sets them when it changes): none yet on these parts
        self._enabling_in_use: object = _NOT_SET

    # --- state a user may read ---------------------------------------------------------

    @property
    def mode(self) -> Mode:
        """``"passive"`` or ``"active"``."""
        return self.parameters.mode

    @property
    def time(self) -> float:
        """Time of the latest sample [s], on the robot's clock (NaN before the first)."""
        return self._t

    @property
    def tau_ext_hat(self) -> FloatArray:
        """Latest estimated external torque [Nm] (bias not removed).

        The joints' own estimates (``observer.tau_ext_hat``, :attr:`joint_std`) read
        together as a force at the tool (``parameters.tool_force``,
        :mod:`~leadthrough.estimation.tool_force`) once guiding has begun; the joint's own
        during the calibration and with ``tool_force = None``.
        """
        fusion = self.fusion
        if fusion is None or not fusion.updated:
            return self.observer.tau_ext_hat
        return fusion.mean.copy()  # a value: the fusion writes its arrays in place

    @property
    def std(self) -> FloatArray:
        """How far :attr:`tau_ext_hat` may be off, one standard deviation [Nm]."""
        fusion = self.fusion
        if fusion is None or not fusion.updated:
            return self.joint_std
        return fusion.std.copy()

    @property
    def joint_std(self) -> FloatArray:
        """How far each joint's own estimate (``observer.tau_ext_hat``) may be off [Nm].

        The model's three errors at the latest sample, independent: the friction model's
        (the observer's ``error_std``; large at rest, where a push below breakaway is
        unseen; each level's error the law's, ``law.friction_error``), the drives' ripple
        on the last period's motor torque τ, ``parameters.torque_ripple / √2 · |τ|``, and
        the gravity model's, ``parameters.gravity_std · |G(q) − G_cal|``
        (G_cal the gravity the calibration measured at its pose on the joints it
        measured, 0 elsewhere and without one: the error the Coulomb compensation's
        ceiling allows for), with the calibration's own reading of it on the joints it
        measured: ``Calibration.coulomb_spread``, the readings' scatter, which the gravity
        error ``(e₊ + e₋) / 2`` carries as the level's ``(e₊ − e₋) / 2`` does.
        ``observer.std`` is the filter's own covariance.
        """
        model = self.model
        if model is None:
            return np.hypot(self.observer.error_std, self._ripple_share * np.abs(self._applied))
        reference = self._gravity_reference
        if reference is None:
            reference = self._no_gravity_reference
        std = self.observer.error_std  # a copy: written in place
        _joint_std(std, self._applied, self._ripple_share, model.gravity, reference,
                   self._gravity_std, self._gravity_reading_std)  # fmt: skip
        return std

    @property
    def tool_wrench(self) -> ToolWrench:
        """Estimated wrench on the tool at the TCP, world axes, with its covariance.

        ``F̂ = (Jᵀ)⁺ τ̂_ext`` with the TCP Jacobian of the latest sample, each joint's own
        estimate and its :attr:`joint_std` (see :mod:`leadthrough.estimation.wrench`); zero
        before the first.
        """
        model = self.model
        if model is None:
            return ToolWrench(np.zeros(3), np.zeros(3), np.zeros((6, 6)))
        return tool_wrench(model.tool_jacobian, self.observer.tau_ext_hat, self.joint_std)

    @property
    def operator_torque(self) -> FloatArray:
        """What drives the admittance: τ̂_ext − bias, through the dead-zone [Nm]."""
        return self.law.drive.copy()

    @property
    def bias(self) -> FloatArray:
        """Model-error bias learned while nobody guides [Nm] (removed from the estimate)."""
        return self.law.model_error.bias.copy()

    @property
    def gravity_correction(self) -> FloatArray:
        """What the start-up calibration added to the model's G at its pose [Nm] (zeros without).

        The gravity error it measured there (after the payload), ``−bias``: feed-forward,
        observer and supervisor then hold the arm with the corrected model, whose
        correction follows G away from the pose as far as :attr:`gravity_share` explains
        it; there the model may be off by ``parameters.gravity_uncertainty``
        times the change of G (the Coulomb compensation's ceiling); on a joint stiction kept
        the calibration from measuring, by that times all of G, as without a calibration.
        """
        if self.calibration is None or self._gravity_offset is None:
            return np.zeros(self.robot.n_joints)
        return -np.asarray(self.calibration.bias, dtype=float)

    @property
    def gravity_share(self) -> FloatArray:
        """The part of the calibration's gravity error taken as a relative error of G [–].

        ``k`` per joint (:func:`~leadthrough.control.calibration.gravity_share`, zeros
        without a calibration): the model holds the arm with ``(1 − k) G(q) − c``, equal
        to ``G − bias`` at the calibration pose, ``k G`` following G away from it.
        """
        scale = self._gravity_scale
        return np.zeros(self.robot.n_joints) if scale is None else 1.0 - scale

    @property
    def torque_offset(self) -> FloatArray:
        """The measured motor torque's offset the calibration found [Nm] (zeros without).

        ``τ_measured − τ_commanded`` averaged over the calibration: an error of the
        measurement the arm never felt. It is taken off every measured torque after the
        calibration, and added back to the gravity error it read
        (:attr:`Calibration.torque_offset`).
        """
        offset = self._torque_offset
        return np.zeros(self.robot.n_joints) if offset is None else offset.copy()

    @property
    def enabling(self) -> bool | None:
        """The enabling device in the latest sample (``JointState.enabling``).

        True held, False released (and after a reading that was neither, which faulted),
        None for an arm without one.
        """
        return self._enabling

    @property
    def state(self) -> SupervisorState:
        """Supervisor state: teaching, holding or fault."""
        return self.supervisor.state

    @property
    def calibrating(self) -> bool:
        """Whether the start-up calibration is running (nobody may touch the arm)."""
        return self._calibrating

    @property
    def calibration_time(self) -> float:
        """How long the start-up calibration lasts [s] (0 without one)."""
        calibration = self.calibration_parameters
        return calibration.duration if self.calibrate and calibration is not None else 0.0

    @property
    def calibration_parameters(self) -> CalibrationParameters | None:
        """The start-up calibration's settings at this controller's period (None: none).

        ``parameters.calibration`` at 250 Hz and faster; slower, its tracking bandwidth and
        stroke follow the period (:meth:`CalibrationParameters.at_period`, computed when
        the controller is built, not in a control period).
        """
        return self._calibration_parameters

    def reset(self) -> None:
        """Start afresh: nominal model, filters, references, bias and calibration.

        A latched fault is cleared too; the calibration runs again if asked for.
        """
        self._build(self._carrying, self.nominal_friction)
        self.supervisor.correct_gravity(None, None)
        self.supervisor.reset()
        self.supervisor.teach()
        p = self.parameters
        n = self.robot.n_joints
        self.law.reset()
        self._no_constraint = np.zeros(n)  # the constraint torque without constraints [Nm]
        self._no_dither = np.zeros(n)  # the dither sent while the device is released [Nm]
        self._no_gravity_reference = np.zeros(n)  # G_cal without a calibration [Nm]
        self._applied = np.zeros(n)  # the motor torque of the last period [Nm] (its ripple)
        #: which command the measured torque holds, read from the data (starts at the
        #: parameters' ``measurement_delay``)
        # the sign of the measured torque is judged where a command moves by a tenth of
        # the joint's Coulomb level (the drives' ripple is small beside it)
        floor = 0.1 * self.nominal_friction.coulomb  # [Nm]
        self.interface_delay = InterfaceDelay(n, p.measurement_delay, self.dt, floor=floor)
        self._sent = DelayLine((2, n), p.measurement_delay,  # (command, its dither) [Nm]
                               self.interface_delay.longest)  # fmt: skip
        self._own_clock = 0.0  # [s], for the positional form of step, which brings no time
        self._t = float("nan")
        self._enabling: bool | None = None  # the sample's enabling device (JointState)
        self._held_since: float | None = None  # when the device last began to read held [s]
        self._stage = "sample"
        self.model: ModelSnapshot | None = None  # the model at the latest sample
        self.last_feed_forward: FeedForwardTorques | None = None
        self.calibration: Calibration | None = None
        self._gravity_offset: FloatArray | None = None  # [Nm], added to scale · G(q)
        self._gravity_scale: FloatArray | None = None  # [–], G(q) multiplied by it first
        #: The measurement's offset the calibration read, taken off every later measured
        #: torque [Nm] (None: not read)
        self._torque_offset: FloatArray | None = None
        self._gravity_reference: FloatArray | None = None  # G where it was measured [Nm]
        # how far the calibration's reading of the gravity error may be off, per joint [Nm]
        self._gravity_reading_std = np.zeros(n)
        #: How far the friction levels may be off at any pose: those the calibration read,
        #: their readings' scatter where they were read, growing with the travel from
        #: there; an identified model's, its own error over the stroke it was fitted on,
        #: growing beyond it (None: neither; the levels' errors are then constant)
        self.level_error: MeasuredLevelError | None = self._identified_level_error()
        self._level_errors = np.zeros(n)  # its value at the latest sample [–]
        self._calibration_run: CalibrationRun | None = None
        self._calibration_start = 0.0  # [s], the tick of the calibration's first sample
        # the samples' ticks (a driver's stamps may jitter, and lose samples)
        self._ticks = TickClock(self.dt)
        self._periods = 1  # control periods since the sample before (more: samples lost)
        self._calibrating = self.calibrate  # the supervisor stays in TEACHING

    def set_payload(self, mass: float, com: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        """Carry a known payload from now on (``robot.with_payload``): a new model everywhere.

        The feed-forward, the observer and the supervisor all switch to the same model;
        the filters restart (do it while the arm rests). This payload replaces the one a
        start-up calibration weighed; its :attr:`gravity_correction` (what the payload
        did not explain) is kept. :meth:`reset` keeps the payload too, and a calibration
        after it weighs only what the arm carries beyond it.

        Args:
            mass: Payload mass [kg], >= 0.
            com: Its centre of mass in the flange frame [m].
        """
        self._carrying = self.robot.with_payload(mass, com)
        self._build(self._carrying, self.friction, self._friction_measured)

    def warm_up(self) -> float:
        """Compile every kernel the step will call, on replicas of this controller.

        :func:`~leadthrough.runtime.loop.control_loop` calls it before the first sample, so
        that no compilation (seconds) falls into a control period; nothing of this
        controller changes (:mod:`~leadthrough.control.warm_up`): replicas guide, and
        calibrate if this one will. Returns the time it took [s].
        """
        q, limits = self.robot.home(), self.robot.velocity_limits
        took = sum(exercise(self._replica(calibrate), q, limits)
                   for calibrate in {False, self.calibrate})  # fmt: skip
        calibration = self.parameters.calibration
        slope = None if calibration is None else calibration.level_slope
        if self.calibrate and slope is not None:  # what follows a calibration: e(q)
            start, ones = time.perf_counter(), np.ones(self.robot.n_joints)
            MeasuredLevelError(q.copy(), 0.5 * ones, ones, float(slope)).at(q, np.zeros_like(q))
            took += time.perf_counter() - start
        return took

    def _identified_level_error(self) -> MeasuredLevelError | None:
        """An identified model's level error: its own over its stroke, growing beyond it.

        ``leadthrough identify`` fits each level over the stroke its samples slid over,
        and the model holds the end values beyond it; there the level is an
        extrapolation, known no better than the slope a level may change with
        (``CalibrationParameters.level_slope``) allows, up to a level nobody measured
        (``unmeasured_friction_error``). Without it a released elbow guided 0.5–0.9 rad
        beyond its identified stroke, where the held end value overstated the plant's
        level by 16–30 % against a stated 6 %, ran on 370 mrad (no calibration). A level
        without a shape (no position terms, as the identification leaves a joint whose
        stroke was too short to fit one) holds no end value: its error stays its own.
        A joint the identification did not fit (``FrictionModel.identified``) keeps its
        unmeasured error everywhere. None for the nominal model, or without a slope.
        """
        calibration = self.parameters.calibration
        if not self._identified.any() or calibration is None or calibration.level_slope is None:
            return None
        friction, error = self.nominal_friction, self.law.friction_error.copy()
        far = np.maximum(error, self.parameters.unmeasured_friction_error)
        # a level without a shape (no position terms) holds no end value: no stroke; nor
        # does one nobody identified (its error is already ``far``)
        shaped = (friction.position_linear != 0.0) | (friction.position_quadratic != 0.0)
        span = np.where(shaped & self._identified, friction.position_half_range, np.inf)
        return MeasuredLevelError(friction.position_mid.copy(), error, far,
                                  float(calibration.level_slope), span)  # fmt: skip

    def _replica(self, calibrate: bool) -> LeadThrough:
        """A new controller built from this one's robot, friction, parameters, constraints."""
        friction = self.nominal_friction if self._given_friction else None
        return LeadThrough(self.robot, self.mode, self.dt, friction, self.parameters,
                           self.constraints, calibrate)  # fmt: skip

    # --- the control step --------------------------------------------------------------

    def step(
        self,
        q: JointState | ArrayLike,
        qd: ArrayLike | None = None,
        tau_measured: ArrayLike | None = None,
    ) -> FloatArray:
        """Motor torque command [Nm] for this period (always finite, within the limits).

        ``step(q, qd, tau_measured)`` (SPEC §10, keywords too), or ``step(state)`` with
        the robot's whole sample.

        Args:
            q: The joint readings q [rad]; or the robot's sample, a :class:`JointState`
                (t [s], q [rad], q̇ [rad/s], τ_measured [Nm]), and nothing else given.
            qd: Joint velocities [rad/s] (with q only).
            tau_measured: Motor torque measured over the last period [Nm] (with q only),
                if the robot reports one; otherwise the command sent
                ``measurement_delay`` steps ago stands for it.

        An exception inside the step latches the supervisor's fault, naming the exception
        and the component it came from, and the safe stop is returned this period; so
        does a sample that cannot be read (``step(q)`` without q̇).
        """
        supervisor = self.supervisor
        try:
            stamp, q, qd, tau_measured = self._sample(q, qd, tau_measured)
        except Exception as error:  # no readings to trust: hold the last good position
            supervisor.stop(failure("sample", error))
            zeros = np.zeros(self.robot.n_joints)
            return self._send(supervisor.command(None, zeros, zeros * np.nan, zeros), zeros)
        if not supervisor.check(stamp, q, qd, tau_measured):  # the time stamp too
            zeros = np.zeros(self.robot.n_joints)
            return self._send(supervisor.command(stamp, q, qd, zeros), zeros)
        t = self._t  # the stamp, checked: a finite number of seconds
        # the periods since the sample before, on the robot's ticks (more: samples lost;
        # the observer predicts over all of them: over one, a 100 ms gap mid-push read the
        # momentum it built as a push, tests/test_observer.py)
        self._periods = self._ticks.advance(t)
        try:
            self._stage = "model"
            self.model = model = self.dynamics.snapshot(q, qd)
            gravity_offset, gravity_scale = self._gravity_offset, self._gravity_scale
            if gravity_offset is not None and gravity_scale is not None:  # gravity_correction
                np.multiply(model.gravity, gravity_scale, out=model.gravity)
                np.add(model.gravity, gravity_offset, out=model.gravity)
            tau = None if tau_measured is None else np.asarray(tau_measured, dtype=float)
            if self._calibrating:
                desired, dither = self._calibrate(t, model, tau), np.zeros(self.robot.n_joints)
            else:
                desired, dither = self._control(t, model, tau)
            self._stage = "supervisor"
            command = supervisor.command(t, q, qd, desired, model)
        except Exception as error:  # the safe stop this period, and the fault says what failed
            supervisor.stop(failure(self._stage, error), t)
            zeros = np.zeros(self.robot.n_joints)
            command, dither = supervisor.command(t, q, qd, zeros), zeros
        return self._send(command, dither)

    def _sample(
        self, state: JointState | ArrayLike, qd: ArrayLike | None, tau: ArrayLike | None
    ) -> tuple[object, FloatArray, FloatArray, FloatArray | None]:
        """(t, q, q̇, τ) of this period; the positional form counts periods of ``dt``.

        ``t`` as the robot stamped it: the supervisor judges it (a number, finite, no
        gap, no step back), and :attr:`time` takes it only if it is a finite number. The
        positional form's clock goes on from the latest stamp (a session that switches
        from ``JointState`` to positional samples is not a clock that stepped back).
        """
        if not isinstance(state, JointState):
            latest = self._t if math.isfinite(self._t) else self._own_clock
            self._own_clock = latest + self.dt
        sample = joint_state(state, qd, tau, self._own_clock)
        stamp = seconds(sample.t)
        if stamp is not None:
            self._t = stamp
        try:
            self._enabling = self._confirmed(enabling_state(sample.enabling))
        except ValueError as error:  # a reading nobody can trust: the safe stop
            self._enabling = False
            self.supervisor.stop(str(error), self._t)
        return sample.t, sample.q, sample.qd, sample.tau_measured

    def _confirmed(self, reading: bool | None) -> bool | None:
        """The enabling device as the controller takes it: released at once, held once sure.

        Released (False) or no device (None) is taken the period it is read, the safe way;
        held (True) once it has read held for :data:`ENABLING_CONFIRMATION`, released until
        then. A device whose reading flips every period (a loose contact) thus leaves the
        arm released, where it switched the assist on and off each period: up to 4 Nm of
        torque chatter at 500 Hz on a Panda at 1 kHz.
        """
        if reading is not True:
            self._held_since = None
            return reading
        if self._held_since is None or not self._t >= self._held_since:
            self._held_since = self._t
        return self._t - self._held_since >= ENABLING_CONFIRMATION - 0.5 * self.dt

    def _send(self, command: FloatArray, dither: FloatArray) -> FloatArray:
        self._sent.push((command, dither))
        self.interface_delay.record(command)
        return command

    def _measured(self, tau_measured: FloatArray | None) -> tuple[FloatArray, FloatArray]:
        """The motor torque applied over the last period [Nm] and the dither it holds.

        A measured torque less the offset the calibration found in the measurement
        (:attr:`torque_offset`); the command sent then, without one. Which command a
        measured torque holds is read from the data (:attr:`interface_delay`, logged as a
        ``measurement_delay`` event when it changes); without a measured torque it is the
        one ``parameters.measurement_delay`` says.
        """
        if tau_measured is None:
            sent = self._sent.measured  # rows: the command, its dither
            return sent[0], sent[1]
        delay = self.interface_delay.update(tau_measured)
        problem = self.interface_delay.gain_problem()
        if problem is not None:  # not the arm's torque: what the observer reads is not a push
            self.supervisor.stop(problem, self._t)
        if delay != self._sent.delay:
            self.supervisor.log("measurement_delay", f"the measured torque holds the command "
                                f"sent {delay} periods before, not {self._sent.delay}")  # fmt: skip
            self._sent.delay = delay
        sent = self._sent.measured
        if self._torque_offset is None:
            return tau_measured, sent[1]
        return tau_measured - self._torque_offset, sent[1]

    def _calibrate(
        self, t: float, model: ModelSnapshot, tau_measured: FloatArray | None
    ) -> FloatArray:
        """One period of the start-up calibration (:mod:`leadthrough.control.calibration`)."""
        self._stage = "calibration"
        q, qd = model.q, model.qd
        if self._calibration_run is None:
            self._calibration_run = CalibrationRun(self.dynamics, self.friction, q,
                                                   self.calibration_parameters,
                                                   self.parameters.gravity_uncertainty,
                                                   self.dt, self._calibration_damping)  # fmt: skip
            self._calibration_start = self._ticks.tick
        # the time on the robot's ticks: a stamp's jitter is not the arm's (TickClock)
        run, elapsed = self._calibration_run, self._ticks.tick - self._calibration_start
        applied, _ = self._measured(tau_measured)
        # what the drive measured against what it was told (once a command has reached it)
        told = elapsed >= self._sent.delay * self.dt
        discrepancy = None
        if tau_measured is not None and told:
            discrepancy = tau_measured - self._sent.measured[0]
        # warm for guiding, and what tells a hand on the arm (the run reads itself)
        run.check_push(self.observer.update(q, qd, applied, model, periods=self._periods))
        if self._enabling and elapsed < run.duration:  # a hand on the arm while it runs
            run.interrupt(HELD_WHILE_CALIBRATING)
        run.record(elapsed, q, applied, discrepancy)
        command = run.command(elapsed, q, qd)
        if elapsed >= run.duration or run.disturbance is not None:
            self._finish_calibration(run.result(), t)
            if run.disturbance:  # let the arm go at once: hold it against gravity only
                return model.gravity
        return command

    def _finish_calibration(self, calibration: Calibration, t: float) -> None:
        """Use what the calibration measured: payload, friction levels, bias at the pose.

        A refused one leaves the model as given, with wider friction errors where it read
        levels below the model's (:meth:`Calibration.lowered`).
        """
        self.calibration, self._calibrating = calibration, False
        self.supervisor.log("calibration", calibration.summary(), t)
        # an offset of the measurement is the sensor's, whatever the readings were
        self._torque_offset = calibration.torque_offset
        if not calibration.accepted:
            friction = calibration.friction(self.nominal_friction)
            if friction is not self.nominal_friction:
                self._build(self._carrying, friction, self._identified)
                self.level_error = self._identified_level_error()  # the wider errors
            return
        robot = calibration.robot(self._carrying)
        accuracy = self.parameters.calibration.friction_accuracy  # type: ignore[union-attr]
        # the joints that slid at pace long enough: their friction level and gravity were
        # measured; on the others (stiction held them, or they stick-slipped) the level and
        # all of G may be off
        n = self.robot.n_joints
        known = np.ones(n, bool) if calibration.measured is None else calibration.measured
        measured = known | self._identified
        self._build(robot, calibration.friction(self.nominal_friction, accuracy), measured)
        self.level_error = calibration.level_error(
            self.law.friction_error.copy(), self.nominal_friction,
            self.parameters.calibration.level_slope,  # type: ignore[union-attr]
            self.parameters.stiction_margin)  # fmt: skip
        # the gravity error measured at the pose goes into the model, as the payload does:
        # feed-forward, observer and supervisor all hold the arm with G(q) − bias(q), the
        # bias a relative error of G as far as it can be (it follows G), the rest constant
        bias = np.asarray(calibration.bias, dtype=float)
        gravity = self.dynamics.gravity(calibration.pose)
        share = gravity_share(bias, gravity, self.parameters.drive_gain_uncertainty)
        share = np.where(known, share, 0.0)
        self._gravity_scale = 1.0 - share
        self._gravity_offset = share * gravity - bias
        self.supervisor.correct_gravity(self._gravity_scale, self._gravity_offset)
        # where the gravity is known: at the pose on the joints measured (reference 0
        # elsewhere)
        measured_gravity = gravity - bias
        self._gravity_reference = np.where(known, measured_gravity, 0.0)
        # the gravity error is read from the same readings as the level, (e₊ + e₋) / 2
        # against (e₊ − e₋) / 2: as far off as the level's reading is
        spread = calibration.coulomb_spread
        self._gravity_reading_std = np.where(known, 0.0 if spread is None else spread, 0.0)
        self.law.model_error.calibrate(np.zeros(self.robot.n_joints), self._gravity_reference)

    def _follow_level_error(self, q: FloatArray) -> None:
        """Each friction level's error at ``q``, everywhere it is used [–].

        A level the calibration read is known to its readings' scatter where it was read
        and less well the farther its joint travels from there
        (:mod:`~leadthrough.friction.measured_level`): the law's friction margin and the
        learned bias' bound, the compensation's ceiling and the observer's band follow it.
        """
        errors = self.level_error.at(q, self._level_errors)  # type: ignore[union-attr]
        self.law.set_friction_error(errors)
        self.observer.set_level_error(errors)
        self.feed_forward.friction_error[:] = errors

    def _control(
        self, t: float, model: ModelSnapshot, tau_measured: FloatArray | None
    ) -> tuple[FloatArray, FloatArray]:
        """The guiding command [Nm] and the dither it holds [Nm]."""
        q, qd = model.q, model.qd
        enabling = self._law_enabling()
        if enabling is not self._enabling_in_use:  # the law's and the compensation's settings
            self.law.use_enabling(enabling)
            self.feed_forward.use_fraction(self._compensated_fraction(enabling))
            self._enabling_in_use = enabling
        if self.level_error is not None:
            self._follow_level_error(q)
        applied, dither = self._measured(tau_measured)
        self._applied[:] = applied  # the drives' ripple on it: joint_std
        self._stage = "observer"
        estimate = self.observer.update(q, qd, applied - dither, model, periods=self._periods)
        if self.fusion is not None:
            self._stage = "tool force"
            own_std = self.joint_std
            estimate = self.fusion.update(estimate, own_std, model.tool_jacobian)
            self.law.narrow(self.fusion.std, own_std)
        self._stage = "operator torque"
        self.law.operator_torque(estimate, q, qd, model.gravity)
        self._stage = "constraints"
        constraint = self._no_constraint
        if self.constraints:
            constraint, _ = constraint_torque(self.constraints, self.dynamics, q, qd, model)
        if self.mode == "passive":
            torque, dither = self._for_the_hand(self._feed_forward(t, model, None))
            return (torque + constraint if self.constraints else torque), dither
        self._stage = "admittance"
        tracking = self.law.tracking(q, qd, constraint, model.mass)
        # follow_push: a joint below its compensation's velocity ramp is compensated as
        # surely, and in the direction, as the admittance reads a push on it
        push = self.law.signed_weight if self.follows_push else None
        torque, dither = self._for_the_hand(self._feed_forward(t, model, push))
        return torque + tracking, dither

    def _law_enabling(self) -> bool | None:
        """The enabling device as the active law takes it (``ActiveLaw.use_enabling``).

        Released, always: nobody guides. Held, the law lets go of what it keeps for a
        released arm (the friction margin, the damping that rises) only on a model whose
        friction a start-up calibration measured on this arm, as the compensation follows
        the push only there (:attr:`follows_push`): unmeasured, the levels may be off by far
        more than their stated error (0.5–1.5 of the model's refused 4 of 8 plants'
        calibrations, and held without the margin those plants shook up to 2.1× passive).
        """
        if self._enabling and not self._calibrated:
            return None
        return self._enabling

    def _compensated_fraction(self, enabling: bool | None) -> float:
        """ε this period [–]: ``held_fraction`` while the law takes the device as held.

        Held on a calibrated model, the released arm's stop is the device's (gravity alone
        once it is let go), not the friction the thesis' ε leaves: active mode may then
        compensate more of it, up to the ceiling (``CoulombCompensationParameters``; None,
        the default, keeps the thesis' ε). Passive mode keeps the thesis' law, with or
        without a device.
        """
        compensation = self.parameters.compensation
        held = compensation.held_fraction
        if self.mode == "active" and enabling and held is not None:
            return held
        return compensation.fraction

    def _for_the_hand(self, feed_forward: FeedForwardTorques) -> tuple[FloatArray, FloatArray]:
        """The feed-forward and its dither; gravity alone while the device is released.

        The Coulomb compensation and the dither are there for the hand that guides: with
        the device released nobody does, and compensation of a level the model overstates
        would carry the arm on (levels 0.5 of the model's, uncalibrated: 0.96 rad).
        """
        if self._enabling is False:
            return feed_forward.gravity, self._no_dither
        return feed_forward.total, feed_forward.dither

    @property
    def _calibrated(self) -> bool:
        """Whether a start-up calibration was accepted (the model's friction measured)."""
        return self.calibration is not None and self.calibration.accepted

    @property
    def follows_push(self) -> bool:
        """Whether active mode's compensation follows the push the admittance reads.

        ``CoulombCompensationParameters.follow_push``: ``"always"``, ``"never"``, or
        (the default) ``"calibrated"``, once a start-up calibration has been accepted.
        """
        setting = self.parameters.compensation.follow_push
        return self.mode == "active" and (
            setting == "always" or (setting == "calibrated" and self._calibrated)
        )

    def _feed_forward(
        self, t: float, model: ModelSnapshot, push: FloatArray | None
    ) -> FeedForwardTorques:
        """Gravity, Coulomb compensation and dither of this period (thesis eq. 6.3) [Nm]."""
        self._stage = "feed-forward"
        self.last_feed_forward = self.feed_forward.step(model.q, model.qd, model, t,
                                                        self._gravity_reference, push)  # fmt: skip
        return self.last_feed_forward


#: ``LeadThrough._enabling_in_use`` before the law is set for any state of the device.
_NOT_SET = object()
#: How long the enabling device must read held before it is taken as held [s] (a switch's
#: bounce lasts a few ms): the next period at 250 Hz, 5 ms at 1 kHz. A release is taken at
#: once (``LeadThrough._confirmed``). 20 ms made dry #3's relaxed sideways line with a
#: device 4 % heavier, one period changed nothing.
ENABLING_CONFIRMATION = 0.005


@kernel
def _joint_std(friction, applied, ripple, gravity, reference, gravity_std, reading):
    """:attr:`LeadThrough.joint_std`, in place of ``friction`` [Nm].

    ``√(friction² + (ripple · |τ|)² + (gravity_std · |G − G_cal|)² + reading²)`` per joint:
    ``friction`` the observer's ``error_std``, ``applied`` the motor torque τ of the last
    period, ``reading`` how far the calibration's reading of G_cal may be off [Nm].
    """
    for i in range(friction.shape[0]):
        measured = math.hypot(friction[i], ripple * abs(applied[i]))
        model = math.hypot(gravity_std * abs(gravity[i] - reference[i]), reading[i])
        friction[i] = math.hypot(measured, model)
