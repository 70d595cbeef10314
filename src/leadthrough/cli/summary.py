"""Human-readable model summary of a robot description (``leadthrough info``)."""

from __future__ import annotations

import numpy as np

from leadthrough.model.description import RobotDescription
from leadthrough.model.dynamics import Dynamics


def model_summary(robot: RobotDescription, q: np.ndarray | None = None) -> str:
    """A text table of joints, limits, masses, gravity torques and the conditioning of M.

    Args:
        robot: The arm.
        q: Joint readings to evaluate gravity and M at [rad] (default: the home pose).
    """
    dynamics = Dynamics(robot)
    q = robot.home() if q is None else np.asarray(q, dtype=float)
    gravity = dynamics.gravity(q)
    mass_matrix = dynamics.mass(q)
    flange = dynamics.pose(q)[:3, 3]
    kinematics = "standard DH" if robot.uses_dh else "URDF joint origins"
    width = max(len(name) for name in robot.joint_names) + 2
    lines = [
        f"{robot.name}: {robot.n_joints} revolute joints ({kinematics}), "
        f"moving mass {robot.total_mass:.3f} kg",
        "",
        f"{'joint':<{width}}{'range [deg]':>18}{'speed [deg/s]':>15}{'torque [Nm]':>13}"
        f"{'gear':>8}{'G²Jm [kg m²]':>14}{'link [kg]':>11}{'G(q) [Nm]':>11}",
    ]
    for i, joint in enumerate(robot.joints):
        low, high = np.rad2deg(joint.position_limits)
        lines.append(
            f"{joint.name:<{width}}{f'{low:.1f} … {high:.1f}':>18}"
            f"{np.rad2deg(joint.velocity_limit):>15.0f}{joint.torque_limit:>13.1f}"
            f"{joint.gear_ratio:>8.0f}{joint.reflected_rotor_inertia:>14.2e}"
            f"{joint.link.mass:>11.3f}{gravity[i]:>11.3f}"
        )
    eigenvalues = np.linalg.eigvalsh(mass_matrix)
    lines += [
        "",
        f"at q = {np.array2string(np.rad2deg(q), precision=1, separator=', ')} deg:",
        f"  flange position in world  {np.array2string(flange, precision=4)} m",
        f"  |G(q)|                    {np.linalg.norm(gravity):.3f} Nm",
        f"  M(q) eigenvalues          {eigenvalues.min():.3e} … {eigenvalues.max():.3e} kg m²"
        f" (condition {eigenvalues.max() / eigenvalues.min():.1f})",
    ]
    return "\n".join(lines)
