"""The digital twin: a MuJoCo plant of the arm, its interface, friction and operator."""

import os

# MuJoCo picks its OpenGL backend when it is first imported: offscreen EGL unless the
# user chose otherwise (a screen is never assumed).
os.environ.setdefault("MUJOCO_GL", "egl")
