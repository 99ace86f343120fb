"""Argparse types of the ``uvms`` command's options: each refuses a bad value naming it."""

from __future__ import annotations

import argparse
import math


def positive_seconds(text: str) -> float:
    """Argparse type: a finite number of seconds > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number of seconds, got {text!r}') from None
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f'expected a number of seconds > 0, got {text!r}')
    return value


def seconds_or_zero(text: str) -> float:
    """Argparse type: a finite number of seconds >= 0 (0: no limit)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a number of seconds, got {text!r}') from None
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(
            f'expected a number of seconds >= 0 (0: run until Ctrl-C), got {text!r}')
    return value


def seed(text: str) -> int:
    """Argparse type: an integer seed in [0, 2^31 - 1]."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected an integer, got {text!r}') from None
    if not 0 <= value <= 2**31 - 1:
        raise argparse.ArgumentTypeError(f'expected an integer in [0, 2147483647], got {value}')
    return value


def port(text: str) -> int:
    """Argparse type: a TCP port in [0, 65535] (0: any free port)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'expected a TCP port number, got {text!r}') from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f'expected a TCP port in [0, 65535], got {value}')
    return value
