"""Bounds on the inputs that scale the work of teaching and replaying on the twin.

Kept apart from :mod:`leadthrough.experiments.teach` so that the command line checks its
arguments without importing MuJoCo (which must be imported only after the OpenGL
backend is chosen, :func:`leadthrough.twin.render.prefer_offscreen_gl`).
"""

#: Longest simulated session or replay [s] (results take about 0.3 MB per simulated second).
MAX_SECONDS = 600.0
#: Bounds of a replay's time scale, replay duration over taught duration [–].
TIME_SCALE_RANGE = (0.05, 20.0)
