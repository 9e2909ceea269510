"""Cycle jumping: the worn depth after many cycles, the joint updated as it wears, with as
few runs of the mechanism as the accuracy asks. The depth grows by dh/dN = r(h), r the
wear of one cycle on the joint worn by h (a mechanism run and Archard's law). A jump of dN
cycles is a step of the trapezoidal rule with its Euler predictor,

    h~ = h + dN r(h),   h' = h + dN (r(h) + r(h~)) / 2,

whose difference dN |r(h~) - r(h)| / 2 estimates the jump's error: a jump is kept when that
is within the tolerance at every angle, and the next one is grown or shrunk by
0.9 sqrt(tolerance / error) (between 1/4 and 2), as an adaptive second-order integrator does;
the rate at h~ stands for the rate at h' (they differ by the error). Two runs a jump."""

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Jumps:
    """The jumps taken: per kept jump the cycles reached, its size, its error estimate (m),
    and what `record` said of the joint there; the jumps refused."""

    cycles: list = field(default_factory=list)
    sizes: list = field(default_factory=list)
    errors: list = field(default_factory=list)
    records: list = field(default_factory=list)
    refused: int = 0
    runs: int = 0


def jump(rate, h0: np.ndarray, cycles: float, tolerance: float, first: float,
         record=lambda h, r: None, smallest: float = 1.0) -> tuple[np.ndarray, Jumps]:
    """The depth after `cycles` (h0 at 0), and the Jumps. rate(h) -> (the depth one cycle
    wears at h, anything `record` keeps of that run); the first jump `first` cycles; a jump
    is never below `smallest` cycles (the last ones kept at their error)."""
    out = Jumps()
    h, done, size = np.asarray(h0, float), 0.0, min(first, cycles)
    r0, info = rate(h)
    out.runs += 1
    out.cycles.append(0.0), out.sizes.append(0.0), out.errors.append(0.0), out.records.append(record(h, info))
    while done < cycles * (1 - 1e-12):
        size = min(size, cycles - done)
        predicted = h + size * r0
        r1, info = rate(predicted)
        out.runs += 1
        error = float(np.max(np.abs(r1 - r0))) * size / 2
        factor = 2.0 if error == 0 else min(2.0, max(0.25, 0.9 * math.sqrt(tolerance / error)))
        if error > tolerance and size > smallest:
            out.refused += 1
            size = max(size * factor, smallest)
            continue
        h = h + size * (r0 + r1) / 2
        done += size
        r0 = r1
        out.cycles.append(done), out.sizes.append(size), out.errors.append(error)
        out.records.append(record(h, info))
        size *= factor
    return h, out
