"""The command line's argument types: numbers with their bounds, said in one line when wrong
(argparse turns an ArgumentTypeError into the CLI's one-line error and exit 2)."""

from __future__ import annotations

import argparse


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number above 0, got {value}")
    return value


def non_negative_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number of 0 or more, got {value}")
    return value


def dimension(text: str) -> int:
    value = positive_int(text)
    if value > 16384:
        raise argparse.ArgumentTypeError(f"expected at most 16384 pixels, got {value}")
    return value
