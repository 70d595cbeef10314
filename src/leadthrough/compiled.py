"""Kernels compiled with numba on their first call, so that ``import leadthrough`` stays light.

A control period of a 7-joint arm is a few hundred operations on 7-element vectors, where
NumPy spends its time in call overhead (~0.3–1 µs per operation). The few per-joint loops
that run every period (the observer's filter step, the supervisor's checks) are written as
plain Python loops and compiled by numba: each call then costs ~0.2–0.5 µs. numba (and its
~0.5 s import) is only loaded when a kernel is first called; the machine code is cached on
disk (``cache=True``), so later processes load it instead of compiling.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any


def kernel(function: Callable[..., Any]) -> Callable[..., Any]:
    """``function`` compiled by ``numba.njit(cache=True)`` when it is first called.

    The plain Python function stays available as ``.py_func`` (the same arithmetic,
    interpreted: what the tests compare the compiled kernel with).
    """
    kernel: Callable[..., Any] | None = None

    def call(*args: Any) -> Any:
        nonlocal kernel
        if kernel is None:
            import numba  # at the first call: numba takes ~0.5 s to import

            kernel = numba.njit(cache=True)(function)
        return kernel(*args)

    call.py_func = function  # type: ignore[attr-defined]
    call.__doc__, call.__name__ = function.__doc__, function.__name__
    return call
