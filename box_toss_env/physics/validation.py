"""Checks that turn bad input into an error naming the parameter and its allowed range."""

import math

import numpy as np


def check_finite(name: str, value) -> float:
    """Return ``value`` as a float, or raise ValueError if it is not a finite real number."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite real number, got {value!r}") from None
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite real number, got {number}")
    return number


def check_range(name: str, value, low=-math.inf, high=math.inf, *, low_open=False, high_open=False) -> float:
    """Return ``value`` as a float if it lies in the interval, else raise a ValueError that
    names the parameter and the interval, e.g. ``restitution must be in [0, 1], got 1.5``."""
    number = check_finite(name, value)
    below = number <= low if low_open else number < low
    above = number >= high if high_open else number > high
    if below or above:
        left = "(" if low_open else "["
        right = ")" if high_open else "]"
        raise ValueError(f"{name} must be in {left}{_fmt(low)}, {_fmt(high)}{right}, got {number}")
    return number


def check_vector(name: str, value, size: int) -> tuple[float, ...]:
    """Return ``value`` as a tuple of ``size`` finite floats, else raise ValueError."""
    array = np.asarray(value, dtype=object)
    if array.shape != (size,):
        raise ValueError(f"{name} must be a sequence of {size} finite numbers, got {value!r}")
    return tuple(check_finite(f"{name}[{k}]", component) for k, component in enumerate(array))


def _fmt(bound: float) -> str:
    if math.isinf(bound):
        return "inf" if bound > 0 else "-inf"
    return f"{bound:g}"
