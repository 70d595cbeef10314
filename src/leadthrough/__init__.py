"""leadthrough: sensorless kinesthetic teaching (lead-through programming) of robot arms.

Example:
    >>> import leadthrough as lt
    >>> robot = lt.robots.yumi()
    >>> dyn = lt.Dynamics(robot)
    >>> dyn.gravity(robot.home()).shape
    (7,)
"""

from leadthrough.control.lead_through import LeadThrough
from leadthrough.control.parameters import LeadThroughParameters
from leadthrough.errors import (
    InputShapeError,
    InputValueError,
    LeadthroughError,
    ParameterError,
    RobotDescriptionError,
)
from leadthrough.estimation.contacts import ContactEvent, ContactParameters
from leadthrough.estimation.log_observer import detect_contacts
from leadthrough.estimation.observer import MomentumObserver, ObserverParameters
from leadthrough.estimation.payload import PayloadEstimate, PayloadParameters, estimate_payload
from leadthrough.estimation.wrench import ToolWrench
from leadthrough.friction.identification import FitReport, identify_friction
from leadthrough.friction.model import FrictionModel
from leadthrough.identification.dynamics import DynamicsReport, DynamicsSettings, identify_dynamics
from leadthrough.logs import JointLog
from leadthrough.logs.sample import JointState
from leadthrough.model import robots
from leadthrough.model.description import (
    DHParameters,
    Joint,
    JointFriction,
    JointOrigin,
    LinkInertial,
    Placement,
    RobotDescription,
)
from leadthrough.model.dynamics import Dynamics
from leadthrough.runtime.loop import LoopReport, control_loop
from leadthrough.runtime.readers import read_log

__version__ = "0.1.0"

__all__ = [
    "ContactEvent",
    "ContactParameters",
    "DHParameters",
    "Dynamics",
    "DynamicsReport",
    "DynamicsSettings",
    "FitReport",
    "FrictionModel",
    "InputShapeError",
    "InputValueError",
    "Joint",
    "JointFriction",
    "JointLog",
    "JointOrigin",
    "JointState",
    "LeadThrough",
    "LeadThroughParameters",
    "LeadthroughError",
    "LinkInertial",
    "LoopReport",
    "MomentumObserver",
    "ObserverParameters",
    "ParameterError",
    "PayloadEstimate",
    "PayloadParameters",
    "Placement",
    "RobotDescription",
    "RobotDescriptionError",
    "ToolWrench",
    "__version__",
    "control_loop",
    "detect_contacts",
    "estimate_payload",
    "identify_dynamics",
    "identify_friction",
    "read_log",
    "robots",
]
