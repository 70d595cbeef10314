"""Errors of the digital twin only (the simulated operator, the twin's friction physics)."""

from __future__ import annotations

from leadthrough.errors import ParameterError


class OperatorError(ParameterError):
    """A parameter of the simulated operator (path, hand, torque profile) is invalid."""


class FrictionParameterError(ParameterError):
    """A friction parameter is invalid (twin friction physics or its defaults)."""
