"""The device-clock estimator: minimum-delay offset and skew, robust to late arrivals and jumps."""

from __future__ import annotations

import math
import random

import pytest
from uvms_hardware.device_time import DeviceClockEstimator, Point, lower_envelope

OFFSET_S = 1234.5678
MIN_DELAY_S = 0.0004


def feed(clock: DeviceClockEstimator, rng: random.Random, start_s: float, seconds: float,
         rate_hz: float, skew: float = 0.0, late_s: float = 0.0, late_every: int = 0,
         offset_s: float = OFFSET_S) -> list[tuple[float, float]]:
    """Pairs of a device at ``rate_hz`` (device s, true local s), fed with random delays."""
    truth = []
    for i in range(int(seconds * rate_hz)):
        device_s = start_s + i / rate_hz
        local_s = offset_s + device_s * (1.0 + skew)
        delay_s = MIN_DELAY_S + rng.expovariate(1.0 / 0.002)
        if late_every and i % late_every == 0:
            delay_s += late_s
        clock.add(device_s, local_s + delay_s)
        truth.append((device_s, local_s))
    return truth


def worst_error_s(clock: DeviceClockEstimator, truth: list[tuple[float, float]]) -> float:
    """Largest |to_local(device) - true local time| over the pairs (s)."""
    return max(abs((clock.to_local(d) or math.nan) - t) for d, t in truth)


def test_nothing_is_known_before_the_first_pair() -> None:
    """No pair: no local time, no offset."""
    clock = DeviceClockEstimator()
    assert clock.to_local(1.0) is None and math.isnan(clock.offset_s) and not clock.ready


def test_a_constant_offset_is_found_within_the_smallest_delay() -> None:
    """Delays of 0.4 ms + exponential(2 ms): stamps within 0.5 ms of the truth."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.25)
    rng = random.Random(1)
    feed(clock, rng, 0.0, 5.0, 100.0)
    truth = feed(clock, rng, 5.0, 1.0, 100.0)
    assert worst_error_s(clock, truth) < 0.0005
    assert clock.offset_s == pytest.approx(OFFSET_S, abs=0.0005)


def test_late_arrivals_do_not_move_the_estimate() -> None:
    """One arrival in three 30 ms late (a busy host): the estimate stays on the early ones."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.25)
    rng = random.Random(2)
    truth = feed(clock, rng, 0.0, 6.0, 200.0, late_s=0.030, late_every=3)[-200:]
    assert worst_error_s(clock, truth) < 0.0005
    assert clock.jitter_s > 0.005  # the late ones are in the reported jitter


def test_a_clock_half_a_percent_fast_is_followed() -> None:
    """ATI's rate tolerance (+-0.5 %): the skew is estimated and stamps stay within 0.5 ms."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.25)
    rng = random.Random(3)
    feed(clock, rng, 0.0, 5.0, 500.0, skew=0.005)
    truth = feed(clock, rng, 5.0, 2.0, 500.0, skew=0.005)
    assert worst_error_s(clock, truth) < 0.0005
    assert clock.skew == pytest.approx(0.005, abs=0.0002)


def test_without_skew_a_long_window_would_lag_a_drifting_clock() -> None:
    """Oracle: the flat minimum over the window (no slope) errs by about skew x window / 2."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.25, max_skew=0.0)
    rng = random.Random(3)
    feed(clock, rng, 0.0, 5.0, 500.0, skew=0.005)
    truth = feed(clock, rng, 5.0, 1.0, 500.0, skew=0.005)
    assert worst_error_s(clock, truth) > 0.005


@pytest.mark.parametrize('jump_s', [1.0, -1.0])
def test_a_device_clock_that_jumps_is_followed_after_a_restart(jump_s: float) -> None:
    """An NTP step on the device (forward or back): the estimate restarts and is right again."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.25, reset_s=0.1)
    rng = random.Random(4)
    feed(clock, rng, 0.0, 5.0, 50.0)
    # From device time 5 s on the device reads jump_s more for the same local time.
    feed(clock, rng, 5.0 + jump_s, 1.0, 50.0, offset_s=OFFSET_S - jump_s)
    truth = feed(clock, rng, 6.0 + jump_s, 1.0, 50.0, offset_s=OFFSET_S - jump_s)
    assert clock.resets >= 1
    assert worst_error_s(clock, truth) < 0.001


def test_after_a_forward_jump_the_rates_agree_again_once_it_left_the_history() -> None:
    """A 1 s step looks like another rate for two windows (arrival stamps: safe), then not."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.25, reset_s=0.1)
    rng = random.Random(9)
    feed(clock, rng, 0.0, 6.0, 50.0)
    feed(clock, rng, 7.0, 2.0, 50.0, offset_s=OFFSET_S - 1.0)
    assert not clock.rates_agree
    feed(clock, rng, 9.0, 11.0, 50.0, offset_s=OFFSET_S - 1.0)
    assert clock.rates_agree


def test_the_spread_and_jitter_are_reported() -> None:
    """report() names offset, skew, spread, jitter, restarts and pairs, all finite."""
    clock = DeviceClockEstimator(window_s=2.0, bucket_s=0.1)
    feed(clock, random.Random(5), 0.0, 3.0, 100.0)
    report = clock.report()
    assert set(report) == {'clock_offset_s', 'clock_skew_ppm', 'clock_offset_spread_s',
                           'arrival_jitter_s', 'clock_resets', 'clock_pairs',
                           'clock_rates_agree'}
    assert 0.0 <= float(report['clock_offset_spread_s']) < 0.002  # type: ignore[arg-type]
    assert float(report['arrival_jitter_s']) == pytest.approx(0.002, rel=0.4)  # type: ignore[arg-type]


def test_non_finite_pairs_are_ignored() -> None:
    """NaN or inf in a pair never reaches the estimate."""
    clock = DeviceClockEstimator()
    clock.add(math.nan, 1.0)
    clock.add(1.0, math.inf)
    assert not clock.ready and clock.pairs == 0


@pytest.mark.parametrize('kwargs', [{'bucket_s': 0.0}, {'window_s': 0.1, 'bucket_s': 0.5},
                                    {'reset_s': 0.0}, {'max_skew': 1.5}])
def test_impossible_settings_are_refused(kwargs: dict[str, float]) -> None:
    """A bucket wider than the window, no reset threshold, a skew of 150 %: refused."""
    with pytest.raises(ValueError, match='device clock'):
        DeviceClockEstimator(**kwargs)


def test_the_envelope_lies_under_every_point() -> None:
    """The fitted line never passes above a point, and touches at least one."""
    rng = random.Random(6)
    points = [Point(i * 0.1, 0.3 + 0.01 * i + rng.random() * 0.05) for i in range(40)]
    x_ref, y_ref, slope = lower_envelope(points, 1.0)
    gaps = [p.y - (y_ref + slope * (p.x - x_ref)) for p in points]
    assert min(gaps) == pytest.approx(0.0, abs=1e-12) and all(g >= -1e-12 for g in gaps)
    assert slope == pytest.approx(0.1, abs=0.03)  # y rises 0.01 per 0.1 of x


@pytest.mark.parametrize('skew', [-0.5, -1.0, 0.02])
def test_clocks_at_different_rates_are_said_to_disagree(skew: float) -> None:
    """A simulator's clock at half speed or standing still, a rate 2 % off: rates_agree False."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.25, reset_s=0.1)
    feed(clock, random.Random(7), 0.0, 6.0, 50.0, skew=skew)
    assert not clock.rates_agree


def test_a_starved_host_is_not_a_clock_that_disagrees() -> None:
    """Every arrival for 0.6 s at a time 0.3 s late, twice: the rates agree, stamps stay right."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.1, reset_s=0.1)
    rng = random.Random(10)
    feed(clock, rng, 0.0, 5.0, 200.0)
    for start_s in (5.0, 7.0):
        feed(clock, rng, start_s, 0.6, 200.0, late_s=0.3, late_every=1)
        feed(clock, rng, start_s + 0.6, 1.4, 200.0)
    truth = feed(clock, rng, 9.0, 1.0, 200.0)
    assert clock.rates_agree and worst_error_s(clock, truth) < 0.0005


def test_clocks_at_one_rate_agree() -> None:
    """0.5 % apart (ATI's tolerance, within max_skew 1 %): they agree."""
    clock = DeviceClockEstimator(window_s=5.0, bucket_s=0.25)
    feed(clock, random.Random(8), 0.0, 6.0, 50.0, skew=0.005)
    assert clock.rates_agree


def test_rates_agree_asked_at_every_sample_answers_as_asked_once() -> None:
    """Read at every arrival (as the bridges do) it says what a fresh look at the history says.

    Two estimators take the same pairs, across a rate change and a forward jump; one is asked
    at every pair, the other only now and then: their answers match each time.
    """
    every = DeviceClockEstimator(window_s=5.0, bucket_s=0.25, reset_s=0.1)
    seldom = DeviceClockEstimator(window_s=5.0, bucket_s=0.25, reset_s=0.1)
    rng = random.Random(11)
    answers = []
    pairs = ([(i / 50.0, OFFSET_S + i / 50.0) for i in range(300)]  # one rate
             + [(6.0 + i / 50.0, OFFSET_S + 6.0 + 0.5 * i / 50.0) for i in range(400)]  # half
             + [(15.0 + i / 50.0, OFFSET_S + 3.0 + i / 50.0) for i in range(700)])  # jumped
    for k, (device_s, local_s) in enumerate(pairs):
        arrival_s = local_s + MIN_DELAY_S + rng.expovariate(1.0 / 0.002)
        every.add(device_s, arrival_s)
        seldom.add(device_s, arrival_s)
        asked = every.rates_agree
        if k % 37 == 0:
            answers.append((asked, seldom.rates_agree))
    assert all(a == b for a, b in answers)
    assert {a for a, _ in answers} == {True, False}  # both answers were given


class RefitAtEveryUse(DeviceClockEstimator):
    """The estimator with its envelope fitted anew at every use: no fit kept between pairs."""

    def _fitted(self) -> tuple[float, float, float] | None:
        self._dirty = True
        return super()._fitted()


def test_the_kept_fit_stamps_as_a_fit_made_anew_at_every_pair() -> None:
    """The fit is kept while only the filling bucket's minimum changes: no stamp differs.

    Both take the same pairs (late ones, a skew of 0.3 %, a forward jump); stamps, skew and
    offset are compared bit for bit after every pair.
    """
    kept = DeviceClockEstimator(window_s=5.0, bucket_s=0.1, reset_s=0.1)
    anew = RefitAtEveryUse(window_s=5.0, bucket_s=0.1, reset_s=0.1)
    rng = random.Random(5)
    pairs = ([(i / 500.0, OFFSET_S + i / 500.0 * 1.003) for i in range(4000)]
             + [(8.0 + i / 500.0, OFFSET_S + 9.0 + i / 500.0) for i in range(2000)])
    for k, (device_s, local_s) in enumerate(pairs):
        late_s = 0.05 if k % 97 == 0 else 0.0
        arrival_s = local_s + MIN_DELAY_S + rng.expovariate(1.0 / 0.002) + late_s
        kept.add(device_s, arrival_s)
        anew.add(device_s, arrival_s)
        assert kept.to_local(device_s) == anew.to_local(device_s)
        assert (kept.skew, kept.offset_s, kept.resets) == (anew.skew, anew.offset_s, anew.resets)
    assert kept.resets == 1  # the jump was seen
