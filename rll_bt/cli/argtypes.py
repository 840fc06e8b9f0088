"""Argument types the commands share: a bad value is argparse's usage error (exit 2) naming it."""
from __future__ import annotations

import argparse


def seconds(text: str) -> float:
    """A duration (or any quantity) >= 0."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
    if not v >= 0:
        raise argparse.ArgumentTypeError(f"seconds must be >= 0, not {text}")
    return v


def share(text: str) -> float:
    """A share in [0, 1): a loss rate, say."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0.0 <= v < 1.0:
        raise argparse.ArgumentTypeError(f"a share is in [0, 1), not {text}")
    return v


def count(text: str) -> int:
    """A whole number >= 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, not {text}")
    return v
