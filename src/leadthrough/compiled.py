"""Kernels compiled with numba on their first call, so that ``import leadthrough`` stays light.

A control period of a 7-joint arm is a few hundred operations on 7-element vectors, where
NumPy spends its time in call overhead (~0.3–1 µs per operation). The few per-joint loops
that run every period (the observer's filter step, the supervisor's checks) are written as
plain Python loops and compiled by numba: each call then costs ~0.2–0.5 µs. numba (and its
~0.5 s import) is only loaded when a kernel is first called; the machine code is cached on
disk (``cache=True``), so later processes load it instead of compiling.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

#: Every kernel defined, by name: ``signatures()`` reads what each has compiled.
_KERNELS: dict[str, Callable[..., Any]] = {}


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

            kernel = _compiled(numba, function)
            _bind(call, kernel)
        return kernel(*args)

    def compiled() -> tuple[str, ...]:
        return () if kernel is None else tuple(str(s) for s in kernel.signatures)  # type: ignore[attr-defined]

    call.py_func = function  # type: ignore[attr-defined]
    call.compiled_signatures = compiled  # type: ignore[attr-defined]
    call.__doc__, call.__name__ = function.__doc__, function.__name__
    _KERNELS[f"{function.__module__}.{function.__qualname__}"] = call
    return call


def _compiled(numba: Any, function: Callable[..., Any]) -> Callable[..., Any]:
    """``numba.njit(cache=True)(function)``, or without the disk cache where there is none.

    numba caches beside the module (``__pycache__``) or in the user's cache folder; an
    install that may write neither (read-only, no HOME) made every command fail
    ("cannot cache function"), ``--help`` included. It then compiles in each process.
    """
    try:
        return numba.njit(cache=True)(function)  # type: ignore[no-any-return]
    except RuntimeError:  # no cache locator: nowhere to write the cache
        return numba.njit(function)  # type: ignore[no-any-return]


def _bind(wrapper: Callable[..., Any], dispatcher: Callable[..., Any]) -> None:
    """Point the package's module-level names of ``wrapper`` at the compiled ``dispatcher``.

    Later calls from the package then go straight to numba, without the wrapper's Python
    frame (~0.2 µs, a dozen kernel calls per control period); a name held elsewhere (a
    test's import) still works through the wrapper.
    """
    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("leadthrough"):
            for name, value in list(vars(module).items()):
                if value is wrapper:
                    setattr(module, name, dispatcher)


def signatures() -> dict[str, tuple[str, ...]]:
    """The argument types each kernel has been compiled (or loaded from the cache) for.

    A kernel called with new argument types compiles again, there and then (a second or
    more): :meth:`~leadthrough.LeadThrough.warm_up` makes sure a control loop finds every
    kernel it will call already compiled.
    """
    return {name: call.compiled_signatures() for name, call in _KERNELS.items()}  # type: ignore[attr-defined]
