"""A seeded family of plants: the twin as an arm the project has never seen.

Controllers are judged on many plants, never on one (the house rule "generalise, don't
tune"). :func:`sample_plant` draws one plant from a seed, with either friction physics
(``"lugre"``: the twin's LuGre torque; ``"dry"``: MuJoCo's own ``frictionloss``
constraint, :mod:`~leadthrough.twin.dry_friction`):

- link masses (and inertias) ±5 %, centres of mass ±5 mm per axis;
- friction levels (Coulomb, viscous) ±20 % per joint, stiction ratio 1.1–1.5, Stribeck
  velocity 0.005–0.03 rad/s; for the dry physics ±15 % position dependence with a
  random phase per joint;
- one or two control periods of delay, measured-torque noise 0.002–0.01 Nm and
  motor ripple 1–3 %;
- the interface errors of real arms: a motor torque constant off by up to ±10 % per joint
  (applied = gain · command, measured = applied / gain), a torque offset up to ±0.05 Nm,
  and a joint velocity from the differenced quantised encoder, low-passed at 15–40 Hz.

The controller keeps the nominal description and friction: nothing here is visible to it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from leadthrough.errors import ParameterError
from leadthrough.model.description import RobotDescription
from leadthrough.twin.dry_friction import DryFrictionParameters
from leadthrough.twin.errors import FrictionParameterError
from leadthrough.twin.friction import TwinFrictionParameters, smallest_effective_inertia
from leadthrough.twin.model_error import ModelError, perturbed_robot
from leadthrough.twin.sensors import SensorModel
from leadthrough.twin.simulator import TwinConfig
from leadthrough.validation import FloatArray

FRICTION_PHYSICS = ("lugre", "dry")


@dataclass(frozen=True)
class PlantRanges:
    """Ranges the plants are drawn from (uniformly), each ``(low, high)``.

    Attributes:
        mass_error: Relative link mass error bound [–].
        com_error: Centre-of-mass shift bound per axis [m].
        friction_scale: Per-joint factor on Coulomb and viscous friction [–].
        static_ratio: Stiction over Coulomb [–].
        stribeck_velocity: Stribeck velocity [rad/s].
        delay_periods: Control periods of delay (integers, both ends included).
        torque_noise_std: Measured-torque noise [Nm].
        torque_ripple: Relative motor torque ripple [–].
        torque_gain: True over nominal motor torque constant [–].
        torque_offset: Measured-torque offset [Nm].
        velocity_cutoff: Corner of the velocity low-pass [Hz].
        position_amplitude: Relative position dependence of the dry friction [–].
        enabling_device: Whether the arms have a hand-guiding enabling device, held while
            the operator holds the arm (``TwinConfig.enabling_device``; not drawn).
        torque_sensor: Whether the drives report the torque they apply
            (``SensorModel.torque_sensor``; not drawn).
        start_spread: How far from the home pose each joint may start [rad]: uniform
            within ±spread, kept :data:`START_MARGIN` inside the joint's limits (further
            from home where home itself is nearer a limit); 0 starts every plant at home.
            Drawn from a stream of its own, so the plant is otherwise the same; the stream
            counts the physics, so dry #n and lugre #n start at different poses.
        encoder_counts: Counts per motor revolution of every joint's encoder
            (``SensorModel.encoder_counts``; not drawn): fewer is a coarser angle, and a
            noisier velocity differenced from it.
    """

    mass_error: float = 0.05
    com_error: float = 0.005
    friction_scale: tuple[float, float] = (0.8, 1.2)
    static_ratio: tuple[float, float] = (1.1, 1.5)
    stribeck_velocity: tuple[float, float] = (0.005, 0.03)
    delay_periods: tuple[int, int] = (1, 2)
    torque_noise_std: tuple[float, float] = (0.002, 0.01)
    torque_ripple: tuple[float, float] = (0.01, 0.03)
    torque_gain: tuple[float, float] = (0.9, 1.1)
    torque_offset: tuple[float, float] = (-0.05, 0.05)
    velocity_cutoff: tuple[float, float] = (15.0, 40.0)
    position_amplitude: float = 0.15
    enabling_device: bool = False
    torque_sensor: bool = True
    start_spread: float = 0.0
    encoder_counts: int = SensorModel.encoder_counts

    def __post_init__(self) -> None:
        for name, (allowed, text) in _RANGE_RULES.items():
            value = getattr(self, name)
            ends = value if isinstance(value, tuple) else (value,)
            if not all(np.isfinite(x) and allowed(x) for x in ends) or ends[0] > ends[-1]:
                order = ", LOW ≤ HIGH" if isinstance(value, tuple) else ""
                raise ParameterError(name, f"must be {text}{order}, got {value}")


#: What both ends of each range of :class:`PlantRanges` must satisfy (and low ≤ high).
_RANGE_RULES: dict[str, tuple[Callable[[float], bool], str]] = {
    "mass_error": (lambda x: 0.0 <= x < 1.0, "in [0, 1)"),
    "com_error": (lambda x: x >= 0.0, "≥ 0"),
    "friction_scale": (lambda x: x > 0.0, "> 0"),
    "static_ratio": (lambda x: x >= 1.0, "≥ 1"),
    "stribeck_velocity": (lambda x: x > 0.0, "> 0"),
    "delay_periods": (lambda x: x >= 0 and float(x).is_integer(), "whole periods ≥ 0"),
    "torque_noise_std": (lambda x: x >= 0.0, "≥ 0"),
    "torque_ripple": (lambda x: x >= 0.0, "≥ 0"),
    "torque_gain": (lambda x: x > 0.0, "> 0"),
    "torque_offset": (lambda x: True, "finite"),
    "velocity_cutoff": (lambda x: x > 0.0, "> 0"),
    "position_amplitude": (lambda x: 0.0 <= x < 1.0, "in [0, 1)"),
    "start_spread": (lambda x: x >= 0.0, "≥ 0"),
    "encoder_counts": (lambda x: x >= 1 and float(x).is_integer(), "a whole number ≥ 1"),
}

#: How far inside its limits a joint starts, at least [rad]: two of the lead-through
#: controller's limit zones, outside the band where its compensation fades.
START_MARGIN = 0.4


#: A family wider than the one the defaults were developed on: friction levels 0.7–1.3 of
#: the nominal and ±25 % along the travel (``guiding_quality.py --plants
#: friction_scale=0.7,1.3 position_amplitude=0.25``, in ``make bench``;
#: docs/guiding_results.md, *Beyond the family*).
WIDER_RANGES = PlantRanges(friction_scale=(0.7, 1.3), position_amplitude=0.25)


@dataclass(frozen=True, eq=False)
class Plant:
    """One sampled plant.

    Attributes:
        name: ``"<physics> #<seed>"``.
        seed: The seed it was drawn from.
        friction_physics: ``"lugre"`` or ``"dry"``.
        config: The twin configuration (use with the *nominal* description).
        start: Where the arm starts [rad] (None: the home pose; ``DigitalTwin(..., q0=)``).
    """

    name: str
    seed: int
    friction_physics: str
    config: TwinConfig
    start: FloatArray | None = None


def sample_plant(
    robot: RobotDescription,
    seed: int,
    friction: str = "dry",
    ranges: PlantRanges | None = None,
) -> Plant:
    """Draw one plant of ``robot`` from ``seed``; the same seed gives the same plant.

    Args:
        robot: The nominal description (what the controller uses).
        seed: Seed of every draw (the twin's own noise included).
        friction: ``"lugre"`` or ``"dry"``.
        ranges: Ranges to draw from (default :class:`PlantRanges`).

    Raises:
        FrictionParameterError: ``friction`` is not one of :data:`FRICTION_PHYSICS`.
    """
    if friction not in FRICTION_PHYSICS:
        raise FrictionParameterError("friction", f"must be 'lugre' or 'dry', got {friction!r}")
    r = ranges or PlantRanges()
    rng = np.random.default_rng([seed, FRICTION_PHYSICS.index(friction)])
    n = robot.n_joints
    model_error = ModelError(mass_error=r.mass_error, com_error=r.com_error)
    true_robot = perturbed_robot(robot, model_error, np.random.default_rng(seed))  # as the twin
    scale = rng.uniform(*r.friction_scale, n)
    ratio = rng.uniform(*r.static_ratio, n)
    stribeck = rng.uniform(*r.stribeck_velocity)
    if friction == "dry":
        params: TwinFrictionParameters | DryFrictionParameters = DryFrictionParameters.from_robot(
            true_robot,
            static_ratio=ratio,
            stribeck_velocity=stribeck,
            scale=scale,
            position_amplitude=r.position_amplitude,
            position_phase=rng.uniform(0.0, 2.0 * np.pi, n),
        )
    else:
        params = _lugre(true_robot, scale, ratio, stribeck)
    sensors = SensorModel(
        torque_noise_std=float(rng.uniform(*r.torque_noise_std)),
        torque_ripple=float(rng.uniform(*r.torque_ripple)),
        torque_gain=tuple(float(x) for x in rng.uniform(*r.torque_gain, n)),
        torque_offset=tuple(float(x) for x in rng.uniform(*r.torque_offset, n)),
        velocity_cutoff=float(rng.uniform(*r.velocity_cutoff)),
        torque_sensor=r.torque_sensor,
        encoder_counts=r.encoder_counts,
    )
    low, high = r.delay_periods
    config = TwinConfig(
        delay_periods=int(rng.integers(low, high + 1)),
        sensors=sensors,
        model_error=model_error,
        friction=params,
        friction_physics=friction,
        seed=seed,
        enabling_device=r.enabling_device,
    )
    start = _start_pose(robot, r.start_spread, [seed, FRICTION_PHYSICS.index(friction), 2])
    return Plant(f"{friction} #{seed}", seed, friction, config, start)


def _start_pose(robot: RobotDescription, spread: float, seed: list[int]) -> FloatArray | None:
    """The home pose moved up to ``spread`` [rad] per joint, inside the limits.

    :data:`START_MARGIN` inside each; None for no spread.
    """
    if spread == 0.0:
        return None
    offset = np.random.default_rng(seed).uniform(-spread, spread, robot.n_joints)
    low, high = robot.q_min + START_MARGIN, robot.q_max - START_MARGIN
    return np.clip(robot.home() + offset, np.minimum(low, high), np.maximum(low, high))


def _lugre(
    robot: RobotDescription, scale: np.ndarray, ratio: np.ndarray, stribeck: float
) -> TwinFrictionParameters:
    """LuGre parameters of ``robot`` with per-joint level scales and stiction ratios."""
    base = TwinFrictionParameters.from_robot(
        robot, stribeck_velocity=stribeck, inertia=smallest_effective_inertia(robot)
    )
    coulomb = base.coulomb * scale
    return dataclasses.replace(
        base, coulomb=coulomb, static=coulomb * ratio, viscous=base.viscous * scale
    )
