"""RateGate: the first stamp of each window passes, so a lower-rate topic keeps its rate."""

import pytest
from uvms_common.rate_gate import RateGate

STEP_NS = 2_000_000  # a 500 Hz loop


def test_50hz_gate_on_a_500hz_loop_passes_every_tenth_stamp() -> None:
    """Stamps 0, 20, 40 ms pass; the nine between each are held back."""
    gate = RateGate(50.0)
    passed = [k * STEP_NS for k in range(25) if gate.due(k * STEP_NS)]
    assert passed == [0, 20_000_000, 40_000_000]


def test_gate_at_the_loop_rate_passes_every_stamp() -> None:
    """At 500 Hz (or above) every 2 ms stamp goes out."""
    for rate in (500.0, 1000.0):
        gate = RateGate(rate)
        assert all(gate.due(k * STEP_NS) for k in range(50))


def test_rate_zero_passes_every_message() -> None:
    """0 Hz: every stamp, however close, and a repeated one (a timer on a paused clock)."""
    gate = RateGate(0.0)
    stamps = [0, 1_900_000, 2_100_000, 5_950_000, 6_050_000, 6_050_000]
    assert all(gate.due(t) for t in stamps)


def test_jittery_stamps_keep_the_rate_without_drift() -> None:
    """Real-time stamps 2 ms +- 0.3 ms apart: one message per 10 ms window, 100 in 1 s."""
    gate = RateGate(100.0)
    jitter = [300_000, -300_000, 100_000, 0]
    stamps = [k * STEP_NS + jitter[k % 4] for k in range(500)]
    assert sum(gate.due(t) for t in stamps) == 100


def test_a_repeated_stamp_is_not_passed_twice() -> None:
    """At a rate, the same stamp again (a re-published state) does not go out twice."""
    gate = RateGate(500.0)
    assert gate.due(STEP_NS)
    assert not gate.due(STEP_NS)


@pytest.mark.parametrize('rate', [-5.0, float('nan')])
def test_a_negative_rate_is_refused(rate: float) -> None:
    """Negative or NaN Hz: ValueError naming the rate."""
    with pytest.raises(ValueError, match='rate must be 0'):
        RateGate(rate)
