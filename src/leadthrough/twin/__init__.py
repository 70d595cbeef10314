"""The digital twin: a MuJoCo plant of the arm, its interface, friction and operator.

Importing it changes nothing in the process: the OpenGL backend of MuJoCo is chosen where
rendering starts (:func:`leadthrough.twin.render.prefer_offscreen_gl`).
"""
