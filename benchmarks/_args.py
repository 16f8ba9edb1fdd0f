"""Argument types the benchmarks share (argparse turns their ValueError into its one-line error, exit 2)."""
from __future__ import annotations


def positive_int(text: str) -> int:
    """An integer of at least 1 (a count of turns or repeats: with none there is no time to report)."""
    n = int(text)
    if n < 1:
        raise ValueError(text)
    return n


positive_int.__name__ = "positive integer"  # argparse names the type in its message
