"""leadthrough: sensorless kinesthetic teaching (lead-through programming) of robot arms.

Example:
    >>> import leadthrough as lt
    >>> robot = lt.robots.yumi()
    >>> dyn = lt.Dynamics(robot)
    >>> dyn.gravity(robot.home()).shape
    (7,)
"""

from leadthrough import robots
from leadthrough.control_loop import LoopReport, control_loop
from leadthrough.description import (
    DHParameters,
    Joint,
    JointFriction,
    JointOrigin,
    LinkInertial,
    Placement,
    RobotDescription,
)
from leadthrough.dynamics import Dynamics
from leadthrough.errors import (
    InputShapeError,
    LeadthroughError,
    ParameterError,
    RobotDescriptionError,
)
from leadthrough.friction_identification import FitReport, identify_friction
from leadthrough.friction_model import FrictionModel
from leadthrough.lead_through import LeadThrough
from leadthrough.lead_through_parameters import LeadThroughParameters
from leadthrough.observer import MomentumObserver, ObserverParameters

__version__ = "0.1.0"

__all__ = [
    "DHParameters",
    "Dynamics",
    "FitReport",
    "FrictionModel",
    "InputShapeError",
    "Joint",
    "JointFriction",
    "JointOrigin",
    "LeadThrough",
    "LeadThroughParameters",
    "LeadthroughError",
    "LinkInertial",
    "LoopReport",
    "MomentumObserver",
    "ObserverParameters",
    "ParameterError",
    "Placement",
    "RobotDescription",
    "RobotDescriptionError",
    "__version__",
    "control_loop",
    "identify_friction",
    "robots",
]
