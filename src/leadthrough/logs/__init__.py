"""Robot logs: one type for a run of joint samples, and readers for the formats robots write."""

from leadthrough.logs.log import JointLog

__all__ = ["JointLog"]
