"""Cancel latencies that a virtual machine's host does not inflate. No bpy: the pytest files
import it as well as the Blender scripts.

A cancel test times how long work goes on after Esc, Ctrl-C or progress.cancel(). On a virtual
machine the host can run other guests on this machine's CPUs for seconds at a time (steal
time). Those seconds pass on the wall clock while nothing of this machine runs, and they are no
part of the latency under test. One such stall made a 0.5 s bound fail on CI, where the same
cancel takes 10-50 ms.

A LatencyClock started at the event measures the wall time since, less the steal of all CPUs
over the same span: /proc/stat's first line, eighth value, in clock ticks. That is 0 on bare
metal, and where /proc/stat is missing. Taking away every CPU's steal is generous when one CPU
was stolen while the thread measured ran on another; the bounds themselves stay as tight as
before, and every report shows the wall time and the steal beside the latency.
"""

import os
import time
from typing import NamedTuple

_TICKS_PER_SECOND = os.sysconf("SC_CLK_TCK")
_STEAL_FIELD = 8  # "cpu user nice system idle iowait irq softirq steal ..."


def stolen_seconds():
    """Seconds the host has run other work on this machine's CPUs since boot (all CPUs)."""
    try:
        with open("/proc/stat") as stat:
            fields = stat.readline().split()
    except OSError:
        return 0.0
    if len(fields) <= _STEAL_FIELD or fields[0] != "cpu":
        return 0.0
    return int(fields[_STEAL_FIELD]) / _TICKS_PER_SECOND


class Latency(NamedTuple):
    wall: float    # seconds on the wall clock
    stolen: float  # seconds of them the host took from this machine's CPUs

    @property
    def seconds(self):
        return max(0.0, self.wall - self.stolen)

    def __str__(self):
        return f"{self.seconds:.3f} s ({self.wall:.3f} s on the wall clock, {self.stolen:.3f} s " \
               "of it stolen by the host)"


class LatencyClock:
    """Started when made (or by start()); read() is the Latency since then."""

    def __init__(self):
        self.start()

    def start(self):
        self._wall, self._stolen = time.perf_counter(), stolen_seconds()
        return self

    def read(self):
        return Latency(time.perf_counter() - self._wall, stolen_seconds() - self._stolen)
