"""The law of active lead-through and its state: operator torque, admittance, tracking.

Per period, after the observer (thesis §6.2, SPEC §6):

1. :meth:`ActiveLaw.operator_torque`: model error must not become motion. A bias learned
   while nobody guides is removed from ``τ̂_ext`` (it can silence a reading, never create
   one), and so is the friction the model may overstate, along the motion; what remains is
   weighed smoothly by how far it stands out of the model's own uncertainty (friction
   error and noise, gravity error; :func:`~leadthrough.control.admittance.operator_weight`),
   a resting joint's friction band narrowed as far as the joints read together know its
   push (:meth:`ActiveLaw.narrow`).
2. :meth:`ActiveLaw.tracking`: the admittance model (virtual inertia k_M M(q) heavier than
   the arm, damping that rises once no push starts or sustains a joint's motion) turns
   that torque plus the virtual constraints' into references that stay clear of the
   joint limits, tracked by a PD whose gains follow M(q) (thesis eqs. 6.4–6.6); a joint
   that rests with no push has its reference drawn to where it is, so the PD's spring
   never holds a stopped joint against stiction; near an end-stop a push *away* from it
   is taken for the stop's reaction, not the operator's (the failure of thesis §6.3.2).

Both run compiled (:mod:`leadthrough.control.fused`) unless :attr:`ActiveLaw.compiled` is
False: the readable NumPy methods below are the reference the tests hold them to. The
passive mode runs step 1 too (the operator torque is a readout there).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from leadthrough.control.admittance import (
    AdmittanceState,
    admittance_step,
    braking_cap,
    damping_weight,
    dead_zone,
    keep_within,
    motion_sign,
    operator_weight,
    reanchored,
    relieved_margin,
    settled_reference,
    signed_push_weight,
    tracking_torque,
    unwound,
    virtual_damping,
)
from leadthrough.control.bias import ModelErrorBias
from leadthrough.control.fused import (
    ADMITTANCE_SCALARS,
    admittance_law,
    operator_drive,
    rest_narrowing,
    sliding_velocity,
)
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.friction.model import FrictionModel
from leadthrough.model.description import FloatArray, RobotDescription

BoolArray = NDArray[np.bool_]
#: Where the compiled admittance reads the rest damping's scale (``rest_damping``).
_REST_DAMPING = ADMITTANCE_SCALARS.index("rest_damping")


class ActiveLaw:
    """Operator torque and admittance of one arm, with their state.

    Args:
        robot: The arm (joint limits, speed limits).
        parameters: The controller's settings.
        dt: Control period [s].
        nominal_friction: The friction model before any calibration (nothing of it
            measured on this arm).

    Attributes:
        friction_error: Relative error of the friction levels in use, per joint [–] (the
            model's, or ``friction_uncertainty``; at least ``stiction_margin``).
        margin_error: The relative error the friction margin removes of the Coulomb
            part [–] (:meth:`_friction_margin`): :attr:`margin_share` of
            :attr:`friction_error` (0 while the enabling device is held).
        enabling: The enabling device this period (:meth:`use_enabling`): True held,
            False released, None without one.
        viscous_margin_error: The same of the viscous part [–]: that of the friction
            model in use (:meth:`use_friction`), which a reading of the level at one
            speed does not narrow (:meth:`set_friction_error` leaves it).
        model_error: The bias learned while nobody guides (and by the calibration).
        drive: Operator torque that drives the admittance [Nm].
        weight: Operator weight of every joint [–].
        residual: The operator torque before its weight [Nm].
        signed_weight: How surely, and which way, the push (residual plus the constraints'
            torque) drives each joint [–], in [−1, 1], averaged over ``push_time`` as
            :attr:`sustained` is (:func:`~leadthrough.control.admittance.signed_push_weight`;
            a stiff hand's oscillation must not swing it). With ``follow_push`` the
            Coulomb compensation of a joint below its velocity ramp follows it
            (:mod:`~leadthrough.friction.compensation`).
        uncertainty: What the model may read without an operator, per joint [Nm]: the
            scale of :attr:`weight` and :attr:`damping_weight`.
        sustained: The push (residual plus constraints' torque) along each joint's
            motion, averaged over ``push_time`` [Nm].
        damping_weight: Weight of the push that starts or sustains each joint's motion
            [–] (:func:`~leadthrough.control.admittance.damping_weight`): sets D̃.
        feedback: The last tracking torque [Nm].
        references: The admittance's references (None until the first active period).
        narrowing: What the joints read together leave of each joint's Coulomb
            uncertainty [–], ≤ 1 (:meth:`narrow`; ones while each joint is read alone).
    """

    #: Run the law compiled (:mod:`leadthrough.control.fused`); False runs the readable
    #: NumPy reference (:meth:`_update_drive`, :meth:`_admittance`).
    compiled = True
    #: Share of the level's error the friction margin removes (:attr:`margin_error`): all
    #: of it. The weight's scale is soft (a residual of its size passes 0.8 of itself), so
    #: no share may be left to it: with ¾, just beyond the plant family, released arms ran
    #: on (docs/guiding_results.md, *Beyond the family*). Experiments set less on a subclass.
    margin_share = 1.0
    #: Relieve the friction margin where the reading along the motion exceeds it
    #: (:func:`~leadthrough.control.admittance.relieved_margin`): lighter on the plant
    #: family, but a released arm whose friction the model overstates by more than the
    #: margin runs on much farther (design log). An experiment: off; set it on a subclass
    #: (the compiled law reads it when the law is built).
    margin_relief = False

    def __init__(
        self,
        robot: RobotDescription,
        parameters: LeadThroughParameters,
        dt: float,
        nominal_friction: FrictionModel,
    ) -> None:
        # the velocity loop softened below 250 Hz (LeadThroughParameters.at_period)
        self.robot, self.parameters, self.dt = robot, parameters.at_period(dt), dt
        self.n = robot.n_joints
        p = self.parameters  # the scalars of the compiled law (fused.DRIVE/ADMITTANCE_SCALARS)
        self._reference_low = robot.q_min + p.limit_zone
        self._reference_high = robot.q_max - p.limit_zone
        self._speed_cap = p.assist_speed_fraction * robot.velocity_limits
        self._push_average = dt / (p.push_time + dt)  # the average over push_time
        self._settle_rate = dt / (p.settle_time + dt)  # a resting reference's, settle_time
        # a lagging joint's velocity reference's, unwind_time (None: never)
        self._unwind_rate = 0.0 if p.unwind_time is None else dt / (p.unwind_time + dt)
        self._drive_scalars = np.array([p.gravity_uncertainty, dt, p.bias_time,
                                        p.drive_gain_uncertainty, p.assist_knee,
                                        float(self.margin_relief)])  # fmt: skip
        self._admittance_scalars = np.array([float(p.limit_aware), p.reanchor_error,
            p.damping_time, p.rest_damping, p.inertia_scale, dt,
            (2.0 * np.pi * p.position_bandwidth) ** 2, p.velocity_time, p.assist_knee,
            p.rest_velocity, self._push_average, self._settle_rate, p.limit_zone,
            self._unwind_rate])  # fmt: skip
        self._terms = np.zeros((4, self.n))  # the friction terms of a period (terms_into)
        self._term_rows = tuple(self._terms)  # its rows (views), for the compiled drive
        self.enabling: bool | None = None
        self._no_push = np.zeros(self.n)  # what drives the admittance while released
        self._margin_applied = self.margin_share  # 0 while the enabling device is held
        self.use_friction(nominal_friction)
        self.reset()

    def use_friction(self, friction: FrictionModel, measured: BoolArray | None = None) -> None:
        """The per-joint margins and tolerances for ``friction`` (nominal or calibrated).

        Args:
            friction: The friction model in use (the law takes it without its stiction
                excess).
            measured: The joints whose Coulomb level was measured on this arm (the
                start-up calibration's); None: none. The others' error is at least
                ``unmeasured_friction_error`` (unless ``friction_uncertainty`` says).
        """
        p = self.parameters
        # the thesis' band: a stiction excess makes the friction higher than the model's
        # mean, which reads as drag against the motion, never as a push along it, so it
        # widens no band a push is weighed against (FrictionModel.stiction_excess)
        self.friction = friction.without_stiction_excess()
        if p.friction_uncertainty is None:
            unmeasured = np.maximum(friction.relative_error, p.unmeasured_friction_error)
            relative = (unmeasured if measured is None
                        else np.where(measured, friction.relative_error, unmeasured))  # fmt: skip
        else:
            relative = np.full(self.n, p.friction_uncertainty)
        relative = np.maximum(relative, p.stiction_margin)
        self.friction_error = relative
        self._noise_band = 2.0 * friction.noise_std
        rest_tolerance = p.stiction_margin * friction.coulomb + self._noise_band
        self._viscous_error = relative.copy()
        self._joint_constants = np.array([relative * friction.coulomb + self._noise_band,
            self._reference_low, self._reference_high, self._margin_applied * relative,
            rest_tolerance, self._speed_cap, self._margin_applied * relative,
        ])  # fused.JOINT_ROWS  # fmt: skip
        # views of its rows: set_friction_error changes them in place
        self._friction_tolerance = self._joint_constants[0]
        self.margin_error = self._joint_constants[3]
        self._rest_tolerance = self._joint_constants[4]
        self.viscous_margin_error = self._joint_constants[6]

    def set_friction_error(self, relative: FloatArray) -> None:
        """This period's relative error of each friction level [–], in place.

        Where a level was read (the start-up calibration), its error grows with the
        joint's travel from where it was read (:mod:`~leadthrough.friction.measured_level`);
        the friction margin's Coulomb part and the bound of the learned bias (its
        tolerance) follow it. Its viscous part keeps the error :meth:`use_friction` set:
        a reading of the level says nothing of the viscous coefficient. ``relative`` is at
        least ``stiction_margin`` (as :meth:`use_friction` makes it).
        """
        self.friction_error[:] = relative
        np.multiply(self._margin_applied, relative, out=self.margin_error)
        np.multiply(relative, self.friction.coulomb, out=self._friction_tolerance)
        self._friction_tolerance += self._noise_band

    def use_enabling(self, enabling: bool | None) -> None:
        """The hand-guiding enabling device's state this period (``JointState.enabling``).

        The friction margin is there so that a released arm stops: a friction level the
        model overstates reads, once the hand has let go, exactly as a push along the
        motion would (docs/guiding_results.md, *Where the effort goes*). An enabling
        device says directly whether a hand is on the arm, so:

        - held (True): the margin is not subtracted (:attr:`margin_error` 0), and the
          virtual damping stays at its guiding value instead of rising where nothing
          starts or sustains a joint's motion (``rest_damping``, there so that a released
          arm stops and model error that leaks through moves it slower). The level's
          error then passes as assist, which the hand on the arm resists; the weight
          still scales every reading by the model's uncertainty. So the device must be
          one that only a hand on the arm can hold (on the tool or a handle): held with
          nobody at the arm, the law has nothing to stop it.
        - released (False): nobody guides. No push drives the admittance
          (:meth:`tracking`; :attr:`drive` stays the readout; the virtual constraints
          still act), so its damping rises to the rest damping and the arm stops (the
          controller sends no Coulomb compensation then: ``LeadThrough``). The margin is
          back for the next grab.
        - None (no device): the margin guarantees the stop, as without this.
        """
        self.enabling = enabling
        # held, the damping stays at guiding: it rises where nothing pushes for the same
        # reason the margin is there, a released arm
        self._admittance_scalars[_REST_DAMPING] = 0.0 if enabling else self.parameters.rest_damping
        applied = 0.0 if enabling else self.margin_share
        if applied != self._margin_applied:
            self._margin_applied = applied
            np.multiply(applied, self.friction_error, out=self.margin_error)
            np.multiply(applied, self._viscous_error, out=self.viscous_margin_error)

    def reset(self) -> None:
        """Forget the bias, the weights and the references."""
        p, n = self.parameters, self.n
        self.model_error = ModelErrorBias(n, p.bias_time, p.gravity_uncertainty)
        self.drive = np.zeros(n)
        self.weight = np.zeros(n)
        self.residual = np.zeros(n)
        self.signed_weight = np.zeros(n)
        self.uncertainty = np.zeros(n)
        self.sustained = np.zeros(n)
        self.damping_weight = np.zeros(n)
        self.feedback = np.zeros(n)
        self.references: AdmittanceState | None = None
        self._work = np.zeros((n, n + 1))  # the compiled admittance's scratch space
        self._sliding = np.zeros(n)  # the compiled sliding velocity
        self.narrowing = np.ones(n)

    def narrow(self, fused_std: FloatArray, own_std: FloatArray) -> None:
        """Narrow each joint's Coulomb uncertainty as the joints read together do [–].

        At rest friction may hold any push below breakaway unseen, so a joint's own
        reading may miss up to ≈ τ_C of it; read with the other joints as one force at the
        tool (:mod:`~leadthrough.estimation.tool_force`), its torque is known to the fused
        std. The Coulomb band of :attr:`uncertainty` shrinks by the same ratio,
        ``fused_std / own_std`` (at most 1): a resting joint whose push the moving joints
        determine passes it, one they cannot see keeps its whole band.

        Args:
            fused_std: The fused estimate's std [Nm].
            own_std: The joint's own estimate's std [Nm].
        """
        if self.compiled:
            rest_narrowing(fused_std, own_std, self.narrowing)
            return
        np.divide(fused_std, np.maximum(own_std, 1e-9), out=self.narrowing)
        np.minimum(self.narrowing, 1.0, out=self.narrowing)

    def sliding_velocity(self, qd: FloatArray) -> FloatArray:
        """``sign(q̇) · max(|q̇| − v_rest, 0)`` [rad/s]: the speed the law's friction sees.

        A joint slower than ``rest_velocity`` is at rest (the project's one definition):
        no friction margin, the whole stiction band as uncertainty. Without it the dither's
        twitch of a resting joint (±0.4 mrad/s at 15 Hz) swung the margin and the
        uncertainty with its phase, and the weight passed the drag of one phase more than
        the other: a rectified drive that crept a released joint 1.2 mrad in 4 s.
        """
        if self.compiled:
            sliding_velocity(qd, self.parameters.rest_velocity, self._sliding)
            return self._sliding
        return dead_zone(qd, self.parameters.rest_velocity)

    def operator_torque(
        self, estimate: FloatArray, q: FloatArray, qd: FloatArray, gravity: FloatArray
    ) -> FloatArray:
        """Update :attr:`drive` and :attr:`weight` from the observer's estimate [Nm].

        The friction margin and uncertainty are the model's at the
        :meth:`sliding_velocity`, not at the measured one.

        Args:
            estimate: τ̂_ext [Nm].
            q: Joint positions [rad].
            qd: Joint velocities [rad/s].
            gravity: G(q) [Nm].
        """
        qd = self.sliding_velocity(qd)  # a method: an experiment's law may see another
        if not self.compiled:
            self._update_drive(estimate, q, qd, gravity)
            return self.drive
        self.friction.terms_into(qd, q, self._terms)  # the rows the compiled drive reads
        bias, (level, viscous, upper, lower) = self.model_error, self._term_rows
        operator_drive(estimate, q, gravity, level, viscous, upper, lower,
            self._joint_constants, self._drive_scalars, self.narrowing, bias.bias,
            bias.gravity_learned, bias.confidence, self.weight, self.drive, self.feedback,
            self.residual, self.uncertainty)  # fmt: skip
        return self.drive

    def tracking(
        self, q: FloatArray, qd: FloatArray, constraint: FloatArray, mass: FloatArray
    ) -> FloatArray:
        """The PD torque [Nm] that tracks the admittance driven by drive + ``constraint``.

        Args:
            q: Joint positions [rad].
            qd: Joint velocities [rad/s].
            constraint: Virtual constraints' torque [Nm].
            mass: M(q) [kg m²].
        """
        drive, residual = self.drive, self.residual
        if self.references is None:
            self.references = AdmittanceState(q.copy(), qd.copy())
        references = self.references
        if self.enabling is False:  # released: nobody guides, whatever the observer reads
            drive = residual = self._no_push
        if not self.compiled:
            return self._admittance(q, qd, drive + constraint, mass, residual + constraint)
        admittance_law(q, qd, drive, constraint, mass, residual, self.uncertainty,
                       self._joint_constants, self._admittance_scalars, references.q_ref,
                       references.qd_ref, self.sustained, self.damping_weight,
                       self.signed_weight, self.feedback, self._work)  # fmt: skip
        return self.feedback

    def _update_drive(
        self, estimate: FloatArray, q: FloatArray, qd: FloatArray, gravity: FloatArray
    ) -> None:
        """Remove the bias and the friction the model may overstate; weigh what remains.

        The weight compares the residual with what the model may still read without an
        operator: the gravity error (:class:`ModelErrorBias`), the stiction no sigmoid
        describes, the friction noise, and the Coulomb uncertainty of the friction model
        (≈ τ_C at rest, where friction may hold any push of that size unseen, → 0 moving).
        """
        p = self.parameters
        plausible = self._friction_tolerance + p.gravity_uncertainty * np.abs(gravity)
        clear_of_limits = bool(np.all((q > self._reference_low) & (q < self._reference_high)))
        unguided = (1.0 - float(np.max(self.weight))) ** 2 if clear_of_limits else 0.0
        _, _, upper, lower = self.friction.sigmoid_terms(qd, q)
        sliding = 1.0 - 0.5 * (upper - lower)  # 0 at rest, 1 where the level is known
        self.model_error.update(estimate, gravity, self.dt, 2.0 * plausible, sliding, unguided)
        residual = dead_zone(estimate, 0.0, self.model_error.bias)
        margin = self._friction_margin(q, qd)
        if self.margin_relief:
            margin = relieved_margin(residual, margin)
        residual = residual - margin - p.drive_gain_uncertainty * self.feedback
        uncertainty = (self._rest_tolerance + self.model_error.tolerance(gravity)
                       + self._coulomb_uncertainty(q, qd))  # fmt: skip
        self.weight = operator_weight(residual, uncertainty, p.assist_knee)
        self.drive = residual * self.weight
        self.residual, self.uncertainty = residual, uncertainty

    def _coulomb_uncertainty(self, q: FloatArray, qd: FloatArray) -> FloatArray:
        """What the friction model leaves open at (q̇, q) [Nm]: ≈ τ_C at rest, → 0 moving.

        Times :attr:`narrowing`: what reading the joints together leaves of it.
        """
        return self.friction.coulomb_uncertainty(qd, q) * self.narrowing

    def _friction_margin(self, q: FloatArray, qd: FloatArray) -> FloatArray:
        """The friction the model may overstate, along the motion [Nm].

        Removed from the estimate, it makes a friction error read as friction (against
        the motion), not as a push along it: a released arm cannot run away on a model
        whose friction is too high. The Coulomb part with the joint's :attr:`margin_error`,
        the whole :attr:`friction_error` (a measured level's, or the spread of units where
        nothing was measured; :attr:`margin_share`), the viscous part with
        :attr:`viscous_margin_error`.
        """
        viscous = self.friction.viscous * qd
        coulomb = self.friction.mean(qd, q) - viscous
        return self.margin_error * coulomb + self.viscous_margin_error * viscous

    def _admittance(
        self, q: FloatArray, qd: FloatArray, drive: FloatArray, mass: FloatArray,
        push: FloatArray,
    ) -> FloatArray:  # fmt: skip
        """References from the admittance model, and the PD torque that tracks them.

        Virtual inertia k_M M(q) and damping :func:`virtual_damping` (``drive`` the
        admittance's input, ``push`` the same before the operator weight); the PD gains
        follow the joint inertias m_ii(q). A joint whose tracking is lost (an end-stop, a
        collision, a joint that runs ahead) has its references re-anchored
        (:func:`~leadthrough.control.admittance.reanchored`), one that lags behind them has
        its velocity reference relaxed towards its own
        (:func:`~leadthrough.control.admittance.unwound`), and one that rests with no
        push has its position reference drawn to where it is
        (:func:`~leadthrough.control.admittance.settled_reference`): nothing winds up.
        """
        p = self.parameters
        if p.limit_aware:
            reaction = self._end_stop_reaction(q, drive)
            drive, push = np.where(reaction, 0.0, drive), np.where(reaction, 0.0, push)
        inertia = np.diag(mass)
        references = self.references or AdmittanceState(q.copy(), qd.copy())
        lost = np.abs(references.q_ref - q) > p.reanchor_error
        references = reanchored(references, q, qd, lost)
        references = AdmittanceState(references.q_ref,
                                     unwound(references.qd_ref, qd, self._unwind_rate))  # fmt: skip
        moving = motion_sign(references.qd_ref, p.rest_velocity)
        self.damping_weight = self._damping_weight(push, moving)
        pushed = signed_push_weight(push, self.uncertainty, p.assist_knee)
        self.signed_weight = self.signed_weight + self._push_average * (pushed - self.signed_weight)
        q_ref = settled_reference(references.q_ref, q, moving, self.damping_weight,
                                  self._settle_rate, motion_sign(qd, p.rest_velocity))  # fmt: skip
        references = AdmittanceState(q_ref, references.qd_ref)
        rest = self._admittance_scalars[_REST_DAMPING]  # 0 while the device is held
        damping = virtual_damping(mass, p.damping_time, rest, self.damping_weight)
        velocity = admittance_step(references, drive, mass, p.inertia_scale, damping,
                                   self.dt).qd_ref  # fmt: skip
        if p.limit_aware:
            # a joint the operator holds inside the limit zone is held where it is, not
            # pulled back out: keeping it out of the zone is the supervisor's soft wall
            low = np.minimum(self._reference_low, q)
            high = np.maximum(self._reference_high, q)
            velocity = braking_cap(references.q_ref, velocity, low, high, self._speed_cap,
                                   p.limit_zone)  # fmt: skip
            references = keep_within(
                AdmittanceState(references.q_ref + self.dt * velocity, velocity), low, high
            )
        else:
            velocity = np.clip(velocity, -self._speed_cap, self._speed_cap)
            references = AdmittanceState(references.q_ref + self.dt * velocity, velocity)
        self.references = references
        kp = inertia * (2.0 * np.pi * p.position_bandwidth) ** 2
        self.feedback = tracking_torque(references, q, qd, kp, inertia / p.velocity_time)
        return self.feedback

    def _damping_weight(self, push: FloatArray, moving: FloatArray) -> FloatArray:
        """Weight of the push that starts or sustains each motion; updates the average.

        The whole push at rest, its average along the motion while a joint moves: the
        drag the law reads once nobody holds the arm raises D̃
        (:func:`~leadthrough.control.admittance.damping_weight`). ``moving`` is the
        :func:`~leadthrough.control.admittance.motion_sign` of the reference velocity.
        """
        self.sustained = self.sustained + self._push_average * (push * moving - self.sustained)
        return damping_weight(push, self.sustained, moving, self.uncertainty,
                              self.parameters.assist_knee)  # fmt: skip

    def _end_stop_reaction(self, q: FloatArray, drive: FloatArray) -> BoolArray:
        """Where a torque near a limit pushes away from it: the end-stop's reaction."""
        near_high = q > self._reference_high
        near_low = q < self._reference_low
        return (near_high & (drive < 0)) | (near_low & (drive > 0))
