"""Robot logs: one type for a run of joint samples, and readers for the formats robots write.

:class:`JointLog` is plain data (used by identification and estimation). The readers
sit at the top of the core: they also read the project's own recordings (``runtime``).
"""

from leadthrough.logs.log import JointLog
from leadthrough.logs.readers import LogError, LogWarning, detect_format, read_log

__all__ = ["JointLog", "LogError", "LogWarning", "detect_format", "read_log"]
