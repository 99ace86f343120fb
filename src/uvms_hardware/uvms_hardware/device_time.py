"""A device's clock in ours: the offset (and rate) from (device time, arrival time) pairs. Pure.

A device that stamps its data with its own clock (the DVL's ``time_of_transmission``, the
Net F/T's record counter at its RDT rate) tells us *when* it measured, but on its clock. Every
arrival on ours is that time plus the clock offset plus a delay that is never negative:
``arrival - device = offset + delay``. So the *lower envelope* of ``arrival - device`` over a
sliding window is the offset plus the smallest delay (the minimum-delay filter of NTP's clock
filter and of PTP servos), and late arrivals (a busy host, a queued socket) lie above it and
do not move it::

    clock = DeviceClockEstimator(window_s=10.0, bucket_s=0.5, reset_s=0.1)
    clock.add(device_s, arrival_s)          # each arrival (both in s)
    stamp_s = clock.to_local(device_s)      # when the device measured, on our clock
    clock.offset_s, clock.skew, clock.spread_s, clock.jitter_s, clock.resets

The window keeps the earliest arrival of each ``bucket_s`` of device time (its minimum-delay
pair). The envelope is the line under those of the finished buckets that lies highest at their
mean (flat until `MIN_SKEW_BUCKETS` are finished): the edge of their lower convex hull above
the mean device time, which is the linear-programming estimate of offset and skew of Moon,
Skelly and Towsley ("Estimation and removal of clock skew from network delay measurements",
INFOCOM 1999). Its slope is the rate difference of the two clocks (skew,
within ``max_skew``: ATI quotes RDT rates within +-0.5 %), so a window of many seconds does
not lag a drifting clock. A pair more than ``reset_s`` below the envelope (the device's clock
jumped forward: an NTP step, a restarted counter) or `LATE_BUCKETS` whole buckets in a row
more than ``reset_s`` above it (jumped back; fewer are a starved host) restarts the estimate
from that pair.

Reported: ``spread_s`` (how far the buckets' minima lie above the envelope: the uncertainty of
the offset itself) and ``jitter_s`` (the standard deviation of recent arrivals' delay above the
envelope: the error an arrival-time stamp would carry).

Two clocks that do not run at one rate (a device on wall time against a node on a simulator's
``/clock`` at another factor, or standing still) cannot be mapped. A longer history of the
earliest arrival per ``window_s / 5`` (kept across the restarts late arrivals or clock jumps
cause, cleared when the device announces a new count or its time runs back) gives the rate
of one clock against the other by its lower envelope, which late arrivals do not move: beyond
``max_skew`` ``rates_agree`` is False, and a bridge stamps at arrival (and says so) rather
than with a wrong device time.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from itertools import pairwise

__all__ = ['DeviceClockEstimator', 'Point', 'lower_envelope']

#: Recent arrivals whose delay above the envelope makes ``jitter_s``.
JITTER_SAMPLES = 200
#: Finished buckets the skew needs; with fewer the envelope is flat.
MIN_SKEW_BUCKETS = 4
#: Finished buckets in a row this far above the envelope: the device's clock was set back.
LATE_BUCKETS = 3
#: The rate history: blocks per window, and how many windows it keeps.
BLOCKS_PER_WINDOW = 5
HISTORY_WINDOWS = 2
#: Finished blocks the rate check needs; with fewer the rates are taken to agree.
MIN_RATE_BLOCKS = 4


@dataclass(frozen=True)
class Point:
    """One bucket's earliest arrival: device time x (s), y = arrival - device (s)."""

    x: float
    y: float


def _cross(o: Point, a: Point, b: Point) -> float:
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)


def lower_envelope(points: list[Point], max_slope: float) -> tuple[float, float, float]:
    """(x_ref, y at x_ref, slope) of the line under every point, highest at their mean x.

    Points sorted by x. The slope is that of the lower convex hull's edge above the mean x (flat
    with one point), clamped to +-``max_slope``; the line is then the highest of that slope
    under every point.

    >>> [round(v, 9) for v in lower_envelope(
    ...     [Point(0.0, 1.0), Point(1.0, 0.2), Point(2.0, 0.4), Point(3.0, 1.0)], 1.0)]
    [1.5, 0.3, 0.2]
    """
    if not points:
        raise ValueError('lower_envelope of no points')
    mean_x = sum(p.x for p in points) / len(points)
    hull: list[Point] = []
    for p in points:  # Andrew's monotone chain, lower half
        while len(hull) >= 2 and _cross(hull[-2], hull[-1], p) <= 0.0:
            hull.pop()
        hull.append(p)
    slope = 0.0
    for a, b in pairwise(hull):
        if a.x <= mean_x <= b.x and b.x > a.x:
            slope = (b.y - a.y) / (b.x - a.x)
            break
    slope = max(-max_slope, min(max_slope, slope))
    return mean_x, min(p.y - slope * (p.x - mean_x) for p in points), slope


class DeviceClockEstimator:
    """Minimum-delay estimate of a device clock's offset and skew against ours."""

    def __init__(self, window_s: float = 10.0, bucket_s: float = 0.5, reset_s: float = 0.1,
                 max_skew: float = 0.01) -> None:
        if not (0.0 < bucket_s < window_s and reset_s > 0.0 and 0.0 <= max_skew < 1.0):
            raise ValueError(f'device clock: need 0 < bucket_s ({bucket_s}) < window_s '
                             f'({window_s}), reset_s ({reset_s}) > 0, 0 <= max_skew '
                             f'({max_skew}) < 1')
        self.window_s = window_s
        self.bucket_s = bucket_s
        self.reset_s = reset_s
        self.max_skew = max_skew
        #: Times the estimate restarted (a device clock that jumped).
        self.resets = 0
        #: Pairs taken.
        self.pairs = 0
        self._buckets: deque[tuple[int, Point]] = deque()
        self._line: tuple[float, float, float] | None = None
        self._excess: deque[float] = deque(maxlen=JITTER_SAMPLES)
        self._late_buckets = 0
        self._block_s = window_s / BLOCKS_PER_WINDOW
        self._history: deque[tuple[int, Point]] = deque(
            maxlen=BLOCKS_PER_WINDOW * HISTORY_WINDOWS + 1)
        self._dirty = False
        #: ``rates_agree`` of the finished blocks, None once they changed (a block appended
        #: or the history cleared); asked for every sample, it changes once a block.
        self._rates_agree: bool | None = None

    def add(self, device_s: float, arrival_s: float) -> None:
        """One arrival: the device's time of it and ours (s); non-finite pairs are ignored."""
        if not (math.isfinite(device_s) and math.isfinite(arrival_s)):
            return
        self.pairs += 1
        point = Point(device_s, arrival_s - device_s)
        self._remember(point)
        line = self._fitted()
        if line is not None:
            excess = point.y - self._y(line, device_s)
            if excess < -self.reset_s:
                self.restart()
            else:
                self._excess.append(max(0.0, excess))
        index = math.floor(device_s / self.bucket_s)
        if self._buckets and index < self._buckets[-1][0]:
            if device_s > self._buckets[-1][1].x - self.reset_s:
                return  # a late, reordered pair: its minimum cannot matter
            self.restart()  # device time ran back: the clock was set back
        if self._buckets and self._buckets[-1][0] == index:
            if point.y < self._buckets[-1][1].y:
                self._buckets[-1] = (index, point)
                # The filling bucket is in the fit only while it is the only one (_fitted):
                # a new minimum in it changes nothing else (the hull was rebuilt at each such
                # minimum: about 340 times a second in the robot process at the twin stand).
                self._dirty = self._dirty or len(self._buckets) == 1
        else:
            self._close_bucket()
            self._buckets.append((index, point))
            self._dirty = True
        while self._buckets and self._buckets[0][1].x < device_s - self.window_s:
            self._buckets.popleft()
            self._dirty = True

    def to_local(self, device_s: float) -> float | None:
        """A device time (s) on our clock: device + envelope there; None before any pair."""
        line = self._fitted()
        return None if line is None else device_s + self._y(line, device_s)

    @property
    def ready(self) -> bool:
        """True once a pair has been taken since the last restart."""
        return bool(self._buckets)

    @property
    def offset_s(self) -> float:
        """Our clock minus the device's at the newest pair, smallest delay included (s)."""
        line = self._fitted()
        if line is None or not self._buckets:
            return math.nan
        return self._y(line, self._buckets[-1][1].x)

    @property
    def rates_agree(self) -> bool:
        """False when the history shows the clocks running more than ``max_skew`` apart."""
        if self._rates_agree is None:
            finished = [p for _, p in self._history][:-1]
            self._rates_agree = (len(finished) < MIN_RATE_BLOCKS
                                 or abs(lower_envelope(finished, math.inf)[2]) < self.max_skew)
        return self._rates_agree

    @property
    def span_s(self) -> float:
        """Device time the pairs in the window cover (s): how much the skew rests on."""
        return self._buckets[-1][1].x - self._buckets[0][1].x if self._buckets else 0.0

    @property
    def skew(self) -> float:
        """Rate of our clock against the device's, minus 1 (dimensionless; 1e-6 = 1 ppm)."""
        line = self._fitted()
        return math.nan if line is None else line[2]

    @property
    def spread_s(self) -> float:
        """Largest height of a bucket's minimum above the envelope (s): the offset's spread."""
        line = self._fitted()
        if line is None:
            return math.nan
        return max(p.y - self._y(line, p.x) for _, p in self._buckets)

    @property
    def jitter_s(self) -> float:
        """Standard deviation of recent arrivals' delay above the envelope (s)."""
        if len(self._excess) < 2:
            return math.nan
        mean = sum(self._excess) / len(self._excess)
        return math.sqrt(sum((e - mean) ** 2 for e in self._excess) / (len(self._excess) - 1))

    def report(self) -> dict[str, object]:
        """The estimate for /diagnostics (s, ppm, counts)."""
        return {'clock_offset_s': self.offset_s, 'clock_skew_ppm': self.skew * 1e6,
                'clock_offset_spread_s': self.spread_s, 'arrival_jitter_s': self.jitter_s,
                'clock_resets': self.resets, 'clock_pairs': self.pairs,
                'clock_rates_agree': self.rates_agree}

    @staticmethod
    def _y(line: tuple[float, float, float], x: float) -> float:
        x_ref, y_ref, slope = line
        return y_ref + slope * (x - x_ref)

    def _fitted(self) -> tuple[float, float, float] | None:
        if self._dirty:
            self._dirty = False
            # The newest bucket is still filling: one late arrival alone in it would tilt the
            # envelope, so it counts only while no bucket is finished.
            points = [p for _, p in self._buckets]
            points = points[:-1] if len(points) > 1 else points
            max_slope = self.max_skew if len(points) >= MIN_SKEW_BUCKETS else 0.0
            self._line = lower_envelope(points, max_slope) if points else None
        return self._line

    def _remember(self, point: Point) -> None:
        """The earliest arrival of each block into the rate history (device time forward)."""
        index = math.floor(point.x / self._block_s)
        if self._history and index < self._history[-1][0]:
            self._history.clear()  # device time ran back: a history across it means nothing
            self._rates_agree = None
        if self._history and self._history[-1][0] == index:
            if point.y < self._history[-1][1].y:
                self._history[-1] = (index, point)  # the newest block: not in rates_agree
        else:
            self._history.append((index, point))
            self._rates_agree = None

    def _close_bucket(self) -> None:
        """`LATE_BUCKETS` finished buckets in a row wholly above the envelope: set back."""
        line = self._fitted()
        if line is None or len(self._buckets) < 2:
            return
        last = self._buckets[-1][1]
        if last.y - self._y(line, last.x) <= self.reset_s:
            self._late_buckets = 0
            return
        self._late_buckets += 1  # a starved host makes a few; a clock set back, all from now
        if self._late_buckets >= LATE_BUCKETS:
            self.restart(keep=last)

    def restart(self, keep: Point | None = None, jumped: bool = True) -> None:
        """Forget every pair, keeping ``keep`` if given.

        ``jumped``: the device's clock jumped against ours (the rate history is kept); False
        for a reset the device announced (a new stream numbered from the start: the history
        is cleared too).
        """
        self.resets += 1
        self._late_buckets = 0
        if not jumped:
            self._history.clear()
            self._rates_agree = None
        self._buckets.clear()
        self._excess.clear()
        if keep is not None:
            self._buckets.append((math.floor(keep.x / self.bucket_s), keep))
        self._line = None
        self._dirty = True
