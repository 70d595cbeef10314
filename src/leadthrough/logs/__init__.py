"""Robot logs: one type for a run of joint samples.

:class:`JointLog` is plain data (used by identification and estimation). The readers of
the formats robots write, :func:`leadthrough.runtime.readers.read_log`, sit at the top of
the core: they also read the project's own recordings (``runtime``) and excitation logs.
:mod:`leadthrough.logs.rows` drops the corrupted rows of a text log for all of them.
"""

from leadthrough.logs.log import JointLog

__all__ = ["JointLog"]
