"""Checks of settings objects' fields, shared by every *Params dataclass's __post_init__.

Each check takes the settings object and field names, and raises InvalidInputError naming
``Class.field``, what it must be and what it got. A check never converts a value: a field holds what
the caller passed or the object is refused. A number check refuses bools and strings, which compare
and multiply without complaint ("0.01" > 0 raises deep inside, True counts as 1), and NaN, which
passes every "not x > 0" test written the other way round and then spreads through the arithmetic.
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import numpy as np

from psorr.errors import InvalidInputError


def _shown(value) -> str:
    return f"{value!r:.60} ({type(value).__name__})"


def _is_real(value) -> bool:
    """A finite real number: python or numpy, int or float, not a bool."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, Real):
        return False
    return isinstance(value, Integral) or math.isfinite(value)  # a huge int overflows isfinite's float


def _real(params, name: str, requirement: str, holds, optional: bool = False) -> None:
    value = getattr(params, name)
    if optional and value is None:
        return
    where = f"{type(params).__name__}.{name}"
    if not _is_real(value):
        raise InvalidInputError(f"{where} must {requirement}, a finite number, got {_shown(value)}")
    if not holds(value):
        raise InvalidInputError(f"{where} must {requirement}, got {value!r}")


def positive(params, *names: str, unit: str = "", optional: bool = False) -> None:
    """Finite numbers > 0 (or None, if ``optional``); ``unit`` (" metres") goes into the message."""
    for name in names:
        _real(params, name, f"be > 0{unit}" + (" or None" if optional else ""), lambda v: v > 0, optional)


def non_negative(params, *names: str, unit: str = "", note: str = "") -> None:
    """Finite numbers >= 0; ``note`` (" (0 turns it off)") goes into the message."""
    for name in names:
        _real(params, name, f"be >= 0{unit}{note}", lambda v: v >= 0)


def within(params, *names: str, low: float = 0, high: float = 1, closed: bool = True,
           optional: bool = False) -> None:
    """Finite numbers in [low, high], or in (low, high) unless ``closed``; or None, if ``optional``."""
    interval = f"[{low}, {high}]" if closed else f"({low}, {high})"
    inside = (lambda v: low <= v <= high) if closed else (lambda v: low < v < high)
    for name in names:
        _real(params, name, f"lie in {interval}" + (" or be None" if optional else ""), inside, optional)


def whole(params, *names: str, minimum: int = 1, note: str = "") -> None:
    """Python or numpy ints >= ``minimum``. A float is refused even when integral: 2.5 would be cut to 2
    somewhere downstream, or fail as a slice step or an array size there."""
    for name in names:
        value = getattr(params, name)
        where = f"{type(params).__name__}.{name}"
        if isinstance(value, bool | np.bool_) or not isinstance(value, Integral):
            raise InvalidInputError(f"{where} must be >= {minimum}{note} and a whole number (an int), "
                                    f"got {_shown(value)}")
        if value < minimum:
            raise InvalidInputError(f"{where} must be >= {minimum}{note}, got {value!r}")


def flag(params, *names: str) -> None:
    """True or False; anything else (the string "no" is truthy) is refused."""
    for name in names:
        value = getattr(params, name)
        if not isinstance(value, bool | np.bool_):
            raise InvalidInputError(f"{type(params).__name__}.{name} must be True or False, got {_shown(value)}")


def real_pair(params, name: str, requirement: str = "") -> tuple:
    """A tuple or list of two finite numbers, returned for the caller's own check of their order;
    ``requirement`` (" with 0 < min < max") goes into the message."""
    value = getattr(params, name)
    if not isinstance(value, tuple | list) or len(value) != 2 or not all(_is_real(v) for v in value):
        raise InvalidInputError(f"{type(params).__name__}.{name} must be a pair (min, max) of finite numbers"
                                f"{requirement}, got {_shown(value)}")
    return tuple(value)


def instance(params, name: str, cls: type) -> None:
    """A nested settings object of class ``cls``: a dict or a string in its place would fail on first use."""
    require_instance(getattr(params, name), cls, f"{type(params).__name__}.{name}",
                     f"build one with {cls.__name__}(...)")


def require_instance(value, cls: type, what: str, fix: str) -> None:
    """``value`` is a ``cls``, or the error names ``what`` was passed and ``fix``."""
    if not isinstance(value, cls):
        raise InvalidInputError(f"{what} must be a {cls.__name__} ({fix}), got {_shown(value)}")
