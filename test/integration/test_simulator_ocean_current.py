"""The simulator node's ocean current: start-up and run-time parameters, /uvms/ocean/current."""

# The harness fixture is test_simulator_node's, imported: its name is every test's argument.
# ruff: noqa: F811

from __future__ import annotations

import time
from typing import Any

from geometry_msgs.msg import TwistStamped
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient
from test_simulator_node import Harness, collect, harness, stamp_ns  # noqa: F401


def _linear(msg: TwistStamped) -> tuple[float, float, float]:
    return (msg.twist.linear.x, msg.twist.linear.y, msg.twist.linear.z)


def _set(harness: Harness, **values: float) -> Any:
    """set_parameters on /uvms/simulator through its service, as ros2 param set does."""
    client = AsyncParameterClient(harness.responder.node, '/uvms/simulator')
    harness.spin_until(lambda: client.services_are_ready())
    future = client.set_parameters([Parameter(f'ocean.current.{name}', value=value)
                                    for name, value in values.items()])
    harness.spin_until(future.done)
    return future.result().results


def test_scenario_current_is_published_with_the_ground_truth(harness: Harness) -> None:
    """ocean.current.* at start-up: ocean/current carries v_c in map_ned with every contact."""
    current = collect(harness, TwistStamped, 'ocean/current')
    sim = harness.start(duration_s=0.01, ocean__current__mean_speed_m_s=0.2,
                        ocean__current__direction_rad=0.0)
    harness.spin_until(lambda: sim.finished and len(current) >= 6)
    assert [stamp_ns(m) for m in current] == [2_000_000 * k for k in range(6)]
    assert all(m.header.frame_id == 'map_ned' and _linear(m) == (0.2, 0.0, 0.0)
               for m in current)


def test_still_water_publishes_no_current(harness: Harness) -> None:
    """Default (current off): no ocean/current message, so recordings stay as they were."""
    current = collect(harness, TwistStamped, 'ocean/current')
    sim = harness.start(duration_s=0.01)
    harness.spin_until(lambda: sim.finished)
    harness.spin_for(0.1)
    assert current == []


def test_set_parameters_at_run_time_changes_the_published_current(harness: Harness) -> None:
    """Real time: set mean_speed_m_s on /uvms/simulator; the next ocean/current shows it.

    Every message stamped after the set was accepted carries the new speed; the wall time
    from the set's reply to the first such message is printed (acceptance: under a second).
    """
    current = collect(harness, TwistStamped, 'ocean/current')
    harness.responder.answer = lambda _: False
    sim = harness.start(mode='realtime', startup__hold=False, ocean__current__mean_speed_m_s=0.1)
    harness.spin_until(lambda: len(current) > 0)
    assert _linear(current[-1]) == (0.1, 0.0, 0.0)
    results = _set(harness, mean_speed_m_s=0.35, direction_rad=1.5707963267948966)
    accepted_ns, replied = sim.sim_time_ns, time.monotonic()
    assert all(r.successful for r in results)
    harness.spin_until(lambda: any(stamp_ns(m) > accepted_ns for m in current))
    latency_s = time.monotonic() - replied
    later = [m for m in current if stamp_ns(m) > accepted_ns]
    assert all(abs(_linear(m)[1] - 0.35) < 1e-12 and abs(_linear(m)[0]) < 1e-12 for m in later)
    print(f'new current published {latency_s * 1e3:.1f} ms (wall) after the set was accepted')


def test_out_of_range_current_is_refused_and_the_current_kept(harness: Harness) -> None:
    """A negative speed, or a mean above max_speed_m_s (2 m/s), is refused with a reason."""
    current = collect(harness, TwistStamped, 'ocean/current')
    harness.responder.answer = lambda _: False
    sim = harness.start(mode='realtime', startup__hold=False, ocean__current__mean_speed_m_s=0.1)
    harness.spin_until(lambda: len(current) > 0)
    for speed in (-0.2, 2.5):
        (result,) = _set(harness, mean_speed_m_s=speed)
        assert not result.successful, speed
        assert 'range' in result.reason or 'max_speed_m_s' in result.reason, result.reason
    accepted_ns = sim.sim_time_ns
    harness.spin_until(lambda: any(stamp_ns(m) > accepted_ns for m in current))
    assert _linear(current[-1]) == (0.1, 0.0, 0.0)
    assert sim.get_parameter('ocean.current.mean_speed_m_s').value == 0.1
