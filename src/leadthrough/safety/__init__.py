"""Safety: limits, checks on every sample, braking and the supervisor state machine."""

from leadthrough.safety.limits import SafetyLimits, SafetyParameters
from leadthrough.safety.supervisor import SafetyEvent, SafetySupervisor, SupervisorState

__all__ = [
    "SafetyEvent",
    "SafetyLimits",
    "SafetyParameters",
    "SafetySupervisor",
    "SupervisorState",
]
