"""Checks that turn bad input into an error naming the parameter: a ``TypeError`` for a value of the
wrong type (a string, a bool or a complex number where a number belongs), a ``ValueError`` naming
the allowed range for a value of the right type outside it. The ranges are in ``ranges``."""

import math

import numpy as np


def is_real(value) -> bool:
    """True for Python and numpy ints and floats (also 0-d arrays of them); False for bools,
    strings, complex numbers and everything else."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        return value.dtype.kind in "iuf"
    if isinstance(value, (bool, np.bool_)):
        return False
    return isinstance(value, (int, float, np.integer, np.floating))


def check_real(name: str, value) -> float:
    """Return ``value`` as a float, or raise TypeError if it is not a real number."""
    if not is_real(value):
        raise TypeError(f"{name} must be a real number (int or float), got {type(value).__name__} {value!r}")
    return float(value)


def check_finite(name: str, value) -> float:
    """Return ``value`` as a float; TypeError if it is not a real number, ValueError if not finite."""
    number = check_real(name, value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite real number, got {number}")
    return number


def check_range(
    name: str, value, low=-math.inf, high=math.inf, *, low_open=False, high_open=False, unit: str = ""
) -> float:
    """Return ``value`` as a float if it lies in the interval, else raise a ValueError that
    names the parameter and the interval, e.g. ``restitution must be in [0, 1], got 1.5``."""
    number = check_finite(name, value)
    below = number <= low if low_open else number < low
    above = number >= high if high_open else number > high
    if below or above:
        raise ValueError(f"{name} must be in {interval(low, high, low_open, high_open, unit)}, got {number}")
    return number


def check_vector(name: str, value, size: int) -> tuple[float, ...]:
    """Return ``value`` as a tuple of ``size`` finite floats; TypeError for a string or a
    component that is not a real number, ValueError for a wrong length or a non-finite value."""
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{name} must be a sequence of {size} real numbers, got {type(value).__name__} {value!r}")
    array = np.asarray(value, dtype=object)
    if array.shape != (size,):
        raise ValueError(f"{name} must be a sequence of {size} finite numbers, got {value!r}")
    return tuple(check_finite(f"{name}[{k}]", component) for k, component in enumerate(array))


def check_bool(name: str, value) -> bool:
    """``value`` as a bool; TypeError unless it is True or False (Python or numpy)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False, got {type(value).__name__} {value!r}")
    return bool(value)


def check_choice(name: str, value, choices: tuple[str, ...]) -> str:
    """``value`` if it is one of the strings ``choices``; TypeError if it is not a string,
    ValueError if it is another one."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, one of {choices}, got {type(value).__name__} {value!r}")
    if value not in choices:
        raise ValueError(f"{name} must be one of {choices}, got {value!r}")
    return value


def check_integer(name: str, value, low: int, high: int | None = None) -> int:
    """``value`` as an int in [low, high] (no upper limit for None); TypeError unless it is a
    Python or numpy integer (not a bool), ValueError outside the range."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__} {value!r}")
    if value < low or (high is not None and value > high):
        bounds = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise ValueError(f"{name} must be an integer {bounds}, got {value!r}")
    return int(value)


def interval(low: float, high: float, low_open=False, high_open=False, unit: str = "") -> str:
    """``[1e-6, 1e6] kg``: an interval as the error messages and docs/ranges.md write it."""
    left = "(" if low_open or low == -math.inf else "["
    right = ")" if high_open or high == math.inf else "]"
    text = f"{left}{fmt(low)}, {fmt(high)}{right}"
    return f"{text} {unit}" if unit else text


def fmt(bound: float) -> str:
    """A bound as written in messages: ``inf``, ``0.1``, ``1e-6``, ``1e12``."""
    if math.isinf(bound):
        return "inf" if bound > 0 else "-inf"
    return f"{bound:g}".replace("e+0", "e").replace("e-0", "e-").replace("e+", "e")
