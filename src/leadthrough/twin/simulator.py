"""The digital twin: a MuJoCo plant of the arm behind the robot interface of the lab.

Timing follows the thesis' set-up (§3.1.2): physics at 2 kHz, the controller at
250 Hz. A command is held (zero-order hold) and reaches the motors ``delay_periods``
control periods after it was sent. Every physics step applies, as joint torques:

    τ_motor (saturated, rippling) + τ_friction (LuGre, position dependent) + τ_operator

and MuJoCo adds contact with the table and the joint end-stops. Controllers see only
:meth:`read_state` and :meth:`send_torque`; the ground truth (true external torque,
the operator's effort, a wrist force/torque sensor) is in :attr:`truth`, for logs
and tests, never for controllers.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from leadthrough.errors import InputShapeError, LeadthroughError, ParameterError
from leadthrough.model.description import FloatArray, RobotDescription
from leadthrough.runtime.interface import JointState, RobotInterface
from leadthrough.twin.dry_friction import DryFriction, DryFrictionParameters
from leadthrough.twin.friction import (
    LuGreFriction,
    TwinFrictionParameters,
    smallest_effective_inertia,
)
from leadthrough.twin.mjcf import FLANGE_SITE, TOOL_GEOM, TableSurface, mjcf_from_description
from leadthrough.twin.model_error import ModelError, perturbed_robot
from leadthrough.twin.operator import Operator
from leadthrough.twin.sensors import Drives, SensorModel, Sensors
from leadthrough.validation import real

#: The last row of a homogeneous transform, and an identity to fill in.
_HOMOGENEOUS = np.eye(4)
_HOMOGENEOUS.setflags(write=False)


class TwinError(LeadthroughError, RuntimeError):
    """The twin cannot go on (a bad configuration or a MuJoCo failure)."""


@dataclass(frozen=True)
class TwinConfig:
    """Everything that makes the twin what it is, seeded.

    Attributes:
        physics_dt: Physics step [s] (2 kHz, the joint loops of the thesis' robot).
        control_dt: Control period [s] (250 Hz, the research interface).
        delay_periods: Control periods between sending a command and its effect [–].
        sensors: Sensor and drive imperfections.
        model_error: How the true robot differs from the description.
        friction: True friction; default derived from the description (Table 4.1 plus
            stiction, Stribeck, pre-sliding and cable effect). Its type follows
            ``friction_physics``.
        friction_physics: ``"lugre"`` (the twin's LuGre torque, default) or ``"dry"``
            (MuJoCo's ``frictionloss`` constraint, :mod:`~leadthrough.twin.dry_friction`).
        table: Optional table surface for contact.
        ft_noise_std: Noise of the wrist force/torque sensor, (force [N], moment [Nm]).
        seed: Seed of every random draw of this twin.
        enabling_device: Whether the arm has a hand-guiding enabling device: then each
            sample reports it held while the operator holds the arm
            (:meth:`~leadthrough.twin.operator.Operator.holds`), released otherwise;
            without one, ``JointState.enabling`` is None.
    """

    physics_dt: float = 0.0005
    control_dt: float = 0.004
    delay_periods: int = 1
    sensors: SensorModel = field(default_factory=SensorModel)
    model_error: ModelError = field(default_factory=ModelError)
    friction: TwinFrictionParameters | DryFrictionParameters | None = None
    friction_physics: str = "lugre"
    table: TableSurface | None = None
    ft_noise_std: tuple[float, float] = (0.02, 0.0005)
    seed: int = 0
    enabling_device: bool = False

    def __post_init__(self) -> None:
        real("physics_dt", self.physics_dt, minimum=0.0, strict=True, error=ParameterError)
        real("control_dt", self.control_dt, minimum=self.physics_dt, error=ParameterError)
        ratio = self.control_dt / self.physics_dt
        if abs(ratio - round(ratio)) > 1e-9:
            raise TwinError(f"control_dt {self.control_dt} is not a multiple of physics_dt")
        real("delay_periods", self.delay_periods, minimum=0.0, error=ParameterError)
        expected = {"lugre": TwinFrictionParameters, "dry": DryFrictionParameters}
        if self.friction_physics not in expected:
            raise TwinError(
                f"friction_physics must be 'lugre' or 'dry', got {self.friction_physics!r}"
            )
        if self.friction is not None and not isinstance(
            self.friction, expected[self.friction_physics]
        ):
            kind = type(self.friction).__name__
            raise TwinError(f"friction is {kind}, not the parameters of {self.friction_physics!r}")

    @property
    def substeps(self) -> int:
        """Physics steps per control period."""
        return round(self.control_dt / self.physics_dt)


@dataclass
class Truth:
    """Ground truth at the latest sample, never shown to controllers (all arm side, world).

    Attributes:
        q: True joint angles [rad].
        qd: True joint velocities [rad/s].
        tau_ext: True external joint torque: operator, contacts and end-stops [Nm].
        tau_operator: The operator's share of ``tau_ext`` [Nm].
        operator_wrench: The wrench the hand applies at the flange, world axes [N, Nm].
        ft_wrench: Wrist sensor reading: external wrench on the tool in the flange frame,
            gravity compensated, with sensor noise [N, Nm].
        tau_motor: Motor torque that reached the joints (saturated, rippling) [Nm].
        tau_friction: Friction torque the joints felt [Nm].
        flange_pose: Flange pose in the world [4×4].
    """

    q: FloatArray
    qd: FloatArray
    tau_ext: FloatArray
    tau_operator: FloatArray
    operator_wrench: FloatArray
    ft_wrench: FloatArray
    tau_motor: FloatArray
    tau_friction: FloatArray
    flange_pose: FloatArray


class DigitalTwin(RobotInterface):
    """The simulated robot: implements :class:`RobotInterface`, exposes :attr:`truth`.

    Args:
        robot: The robot description the controllers use (the nominal one).
        config: Twin configuration (timing, sensors, model error, friction, table, seed).
        operator: Who touches the arm (default: nobody).
        q0: Initial joint angles [rad] (default: the description's home pose).
    """

    def __init__(
        self,
        robot: RobotDescription,
        config: TwinConfig | None = None,
        operator: Operator | None = None,
        q0: ArrayLike | None = None,
    ) -> None:
        self.config = config or TwinConfig()
        self.robot = robot
        self.operator = operator or Operator()
        self.dt = self.config.control_dt
        self.n_joints = robot.n_joints
        rng = np.random.default_rng(self.config.seed)
        self.true_robot = perturbed_robot(robot, self.config.model_error, rng)
        self.model, self.data = self._build_physics()
        self._sensor_rng = np.random.default_rng(rng.integers(2**63))
        self.sensors = Sensors(robot, self.config.sensors, self._sensor_rng, self.config.control_dt)
        self.drives = Drives(self.true_robot, self.config.sensors)
        self.friction = self._friction_physics()
        self._qpos, self._qvel = self.data.qpos, self.data.qvel  # views, valid for data's life
        self._joint_torque = np.zeros(self.n_joints)
        self._ft_noise = np.repeat(self.config.ft_noise_std, 3)
        self._flange_site = self.model.site(FLANGE_SITE).id
        self._flange_body = self.model.site_bodyid[self._flange_site]
        self._tool_geom = self.model.geom(TOOL_GEOM).id
        self._jacobian = np.zeros((6, self.n_joints))
        self._friction_step = self.friction.bind(
            self._qpos, self._qvel, self._joint_torque, self.data.qfrc_applied
        )
        self.reset(q0)

    def _build_physics(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        xml = mjcf_from_description(
            self.true_robot,
            physics_dt=self.config.physics_dt,
            table=self.config.table,
            payload=self.config.model_error.payload,
        )
        try:
            model = mujoco.MjModel.from_xml_string(xml)
        except ValueError as error:
            raise TwinError(f"MuJoCo rejected the generated model: {error}") from None
        return model, mujoco.MjData(model)

    def _friction_physics(self) -> LuGreFriction | DryFriction:
        config = self.config
        if config.friction_physics == "dry":
            params = config.friction
            if params is None:
                scale = config.model_error.friction_scale
                params = DryFrictionParameters.from_robot(self.true_robot, scale=scale)
            assert isinstance(params, DryFrictionParameters)
            return DryFriction(params, self.model, self.data)
        return LuGreFriction(self._friction_parameters(), config.physics_dt)

    def _friction_parameters(self) -> TwinFrictionParameters:
        if self.config.friction is not None:
            assert isinstance(self.config.friction, TwinFrictionParameters)
            return self.config.friction
        return TwinFrictionParameters.from_robot(
            self.true_robot,
            inertia=smallest_effective_inertia(self.true_robot),
            dt=self.config.physics_dt,
            scale=self.config.model_error.friction_scale,
        )

    @property
    def operator(self) -> Operator:
        """Who touches the arm; may be replaced between periods."""
        return self._operator

    @operator.setter
    def operator(self, operator: Operator) -> None:
        self._operator = operator
        self._operator_acts = type(operator) is not Operator
        # a hand that only pulls the flange adds no joint torque (Operator's zeros)
        self._turns_joints = type(operator).joint_torque is not Operator.joint_torque

    # --- the robot interface -------------------------------------------------------------

    def reset(self, q0: ArrayLike | None = None) -> None:
        """Put the arm at rest at ``q0`` (default home), held by its gravity torque."""
        q0 = self.robot.home() if q0 is None else np.asarray(q0, dtype=float)
        if q0.shape != (self.n_joints,):
            raise InputShapeError("q0", (self.n_joints,), q0.shape)
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[:] = q0
        mujoco.mj_forward(self.model, self.data)
        self.friction.reset()
        self.sensors.reset()
        holding = self.data.qfrc_bias.copy()
        self._pending = deque([holding] * max(self.config.delay_periods, 1))
        self._tau_motor = holding.copy()
        self.time = 0.0
        rest = np.zeros(self.n_joints)
        self.truth = self._sample_truth(rest, np.zeros(6), rest)

    def read_state(self) -> JointState:
        """Encoder angles, noisy velocities, measured motor torque and enabling device, now.

        The measured torque only when the drives report one (``SensorModel.torque_sensor``),
        the enabling device only when the arm has one (``TwinConfig.enabling_device``).
        """
        enabling = None
        if self.config.enabling_device:
            enabling = self._operator_acts and self._operator.holds(self.time)
        return JointState(
            t=self.time,
            q=self.sensors.joint_position(self.data.qpos),
            qd=self.sensors.joint_velocity(self.data.qvel, self.data.qpos),
            tau_measured=self._measured_torque(),
            enabling=enabling,
        )

    def _measured_torque(self) -> FloatArray | None:
        if not self.config.sensors.torque_sensor:
            return None
        return self.sensors.motor_torque(self._tau_motor)

    def send_torque(self, tau: ArrayLike) -> None:
        """Queue ``tau`` [Nm] and simulate one control period.

        Raises:
            InputShapeError: ``tau`` is not of shape (n,).
            TwinError: ``tau`` is not finite (a real drive would fault).
        """
        tau = np.asarray(tau, dtype=float)
        if tau.shape != (self.n_joints,):
            raise InputShapeError("tau", (self.n_joints,), tau.shape)
        if np.count_nonzero(np.isfinite(tau)) != tau.size:  # any NaN or ±Inf
            raise TwinError(f"non-finite torque command {tau}")
        self._pending.append(tau.copy())
        command = self._pending.popleft() if self.config.delay_periods else self._pending.pop()
        self._simulate_period(command)

    # --- one control period of physics ---------------------------------------------------

    def _simulate_period(self, command: FloatArray) -> None:
        """Hold the motor and operator torques for one period; friction acts every step."""
        tau_operator, wrench = self._operator_torque()
        self._tau_motor = self.drives.applied(command, self._qpos)
        np.add(self._tau_motor, tau_operator, out=self._joint_torque)
        model, data, friction_step, physics_step = (
            self.model,
            self.data,
            self._friction_step,
            mujoco.mj_step,
        )
        for _ in range(self.config.substeps):
            friction_step()  # qfrc_applied = motor + operator + friction
            physics_step(model, data)
        if not np.isfinite(self._qpos.sum()):
            raise TwinError(f"the simulation diverged at t = {self.time:.3f} s")
        self.time += self.config.control_dt
        if isinstance(self.friction, DryFriction):
            friction = self.friction.torque()
            constraint = data.qfrc_constraint - (friction + model.dof_damping * self._qvel)
        else:
            friction = data.qfrc_applied - self._joint_torque
            constraint = data.qfrc_constraint
        self.truth = self._sample_truth(tau_operator, wrench, friction, constraint)

    def _flange_pose(self) -> FloatArray:
        pose = _HOMOGENEOUS.copy()
        pose[:3, :3].flat = self.data.site_xmat[self._flange_site]
        pose[:3, 3] = self.data.site_xpos[self._flange_site]
        return pose

    def _operator_torque(self) -> tuple[FloatArray, FloatArray]:
        """Joint torque of the operator for this period, and the hand wrench [N, Nm]."""
        if not self._operator_acts:
            return np.zeros(self.n_joints), np.zeros(6)
        jacobian = self._jacobian
        mujoco.mj_jacSite(self.model, self.data, jacobian[:3], jacobian[3:], self._flange_site)
        velocity = jacobian @ self._qvel
        wrench = np.asarray(self.operator.wrench(self.time, self._flange_pose(), velocity), float)
        tau = jacobian.T @ wrench
        if self._turns_joints:
            tau += np.asarray(self.operator.joint_torque(self.time, self._qpos, self._qvel), float)
        return tau, wrench

    def _sample_truth(
        self,
        tau_operator: FloatArray,
        wrench: FloatArray,
        friction: FloatArray,
        constraint: FloatArray | None = None,
    ) -> Truth:
        """The truth now; ``constraint`` is the contact and end-stop torque [Nm]."""
        data = self.data
        pose = self._flange_pose()
        external = wrench + self._tool_contact_wrench(pose[:3, 3]) if data.ncon else wrench
        rotation_t = pose[:3, :3].T
        ft = np.concatenate([rotation_t @ external[:3], rotation_t @ external[3:]])
        ft += self._sensor_rng.normal(0.0, 1.0, 6) * self._ft_noise
        return Truth(
            q=data.qpos.copy(),
            qd=data.qvel.copy(),
            tau_ext=tau_operator + (data.qfrc_constraint if constraint is None else constraint),
            tau_operator=tau_operator.copy(),
            operator_wrench=wrench.copy(),
            ft_wrench=ft,
            tau_motor=self._tau_motor.copy(),
            tau_friction=friction,
            flange_pose=pose,
        )

    def _tool_contact_wrench(self, flange_position: FloatArray) -> FloatArray:
        """Wrench of the table on the tool at the flange origin, world axes [N, Nm]."""
        total = np.zeros(6)
        local = np.zeros(6)
        for i in range(self.data.ncon):
            contact = self.data.contact[i]
            if self._tool_geom not in (contact.geom1, contact.geom2):
                continue
            mujoco.mj_contactForce(self.model, self.data, i, local)
            frame = contact.frame.reshape(3, 3)
            force = frame.T @ local[:3]
            if contact.geom1 == self._tool_geom:
                force = -force  # MuJoCo's contact force acts on geom2
            total[:3] += force
            total[3:] += np.cross(contact.pos - flange_position, force)
        return total
