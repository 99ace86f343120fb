"""The DVL twin sends what a Water Linked DVL sends: its own clock's times in µs."""

from __future__ import annotations

import json

from uvms_twins.dvl_twin import DvlTwin


def test_a_report_carries_the_plants_time_of_validity_and_the_send_time() -> None:
    """time_of_validity is the plant's time of the reading, time_of_transmission the clock's."""
    twin = DvlTwin(clock=lambda: 1000.25)
    try:
        twin.report((0.5, 0.0, 0.0), time_of_validity_s=1000.125)
        assert list(twin.sent_log) == [(1000.125, 1000.25, 0.5)]
        obj = json.loads(twin.velocity_line(1000.125, 1000.25))
        assert (obj['time_of_validity'], obj['time_of_transmission']) == (1000125000,
                                                                          1000250000)
    finally:
        twin.stop()


def test_without_a_plant_time_the_report_is_valid_when_it_is_sent() -> None:
    """The idle stream: both times are the twin's clock now."""
    twin = DvlTwin(clock=lambda: 7.0)
    try:
        twin.report((0.0, 0.0, 0.0))
        assert list(twin.sent_log) == [(7.0, 7.0, 0.0)]
    finally:
        twin.stop()
