"""The bridges' base: no transition, refused or raising, leaves a device changed or held."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
import rclpy
from rclpy.context import Context
from rclpy.lifecycle import TransitionCallbackReturn
from rclpy.parameter import Parameter
from uvms_common.diagnostics import OK, Report
from uvms_common.lifecycle import state_label
from uvms_hardware.bridge_node import BridgeNode
from uvms_hardware.errors import DeviceCheckError, HardwareError

SUCCESS = TransitionCallbackReturn.SUCCESS
FAILURE = TransitionCallbackReturn.FAILURE
ERROR = TransitionCallbackReturn.ERROR


class FakeDevice:
    """What a device would hold: whether a link is open and which values were changed."""

    def __init__(self) -> None:
        self.links_open = 0
        self.changed: dict[str, float] = {}
        self.puts_back = 0


class FakeBridge(BridgeNode):
    """A bridge whose hooks change a fake device and raise where a test asks."""

    error_type = HardwareError

    def __init__(self, device: FakeDevice, context: Context, **faults: Any) -> None:
        super().__init__('fake_bridge', context=context, parameter_overrides=[
            Parameter('robot_name', value='bluerov2_alpha5'),
            Parameter('autostart', value=False)])
        self.device = device
        self.faults = faults
        self.start()

    def configure_device(self) -> None:
        """Open the link; raise where the test asks."""
        self.device.links_open += 1
        if 'configure' in self.faults:
            raise self.faults['configure']

    def activate_device(self) -> None:
        """Change one value, raise where the test asks, then change another."""
        self.device.changed['SERVO1_FUNCTION'] = 33.0  # the original, journaled first
        if 'activate' in self.faults:
            raise self.faults['activate']
        self.device.changed['SERVO2_FUNCTION'] = 34.0

    def put_device_back(self) -> list[str]:
        """Every changed value back."""
        self.device.puts_back += 1
        self.device.changed.clear()
        return []

    def release_device(self) -> None:
        """Close the link."""
        self.device.links_open -= 1

    def device_report(self) -> Report:
        """Always fine."""
        return Report(OK, 'fine', {})


@pytest.fixture
def context() -> Iterator[Context]:
    """An rclpy context of the test's own."""
    ctx = Context()
    rclpy.init(args=[], context=ctx)
    yield ctx
    rclpy.try_shutdown(context=ctx)


def test_refused_configure_names_why_and_releases_the_link(context: Context) -> None:
    """A device check that fails: FAILURE, the reason kept, no link left open."""
    device = FakeDevice()
    node = FakeBridge(device, context, configure=DeviceCheckError('joint_2: silent'))
    try:
        assert node.trigger_configure() == FAILURE
        assert node.refusal == 'joint_2: silent'
        assert device.links_open == 0
        assert state_label(node) == 'unconfigured'
    finally:
        node.destroy_node()


def test_configure_that_raises_ends_unconfigured_with_the_link_released(
        context: Context) -> None:
    """A bug in configure: ERROR, on_error, unconfigured again, nothing held."""
    device = FakeDevice()
    node = FakeBridge(device, context, configure=KeyError('t200'))
    try:
        assert node.trigger_configure() == ERROR
        assert state_label(node) == 'unconfigured'
        assert device.links_open == 0
        assert 'KeyError' in node.refusal
    finally:
        node.destroy_node()


@pytest.mark.parametrize('fault', [DeviceCheckError('arm: refused'), RuntimeError('bug')])
def test_activate_failing_half_way_puts_back_what_it_changed(context: Context,
                                                             fault: Exception) -> None:
    """Whatever activate changed before it failed or raised is put back before it answers."""
    device = FakeDevice()
    node = FakeBridge(device, context, activate=fault)
    try:
        assert node.trigger_configure() == SUCCESS
        assert node.trigger_activate() != SUCCESS
        assert device.changed == {}
        assert device.puts_back == 1
        assert not node.device_active
    finally:
        node.destroy_node()
    assert device.links_open == 0


def test_deactivate_and_shutdown_put_back_once_and_release(context: Context) -> None:
    """Put back on deactivate; a shutdown after it does not put back twice; link closed."""
    device = FakeDevice()
    node = FakeBridge(device, context)
    assert node.trigger_configure() == SUCCESS
    assert node.trigger_activate() == SUCCESS
    assert device.changed
    assert node.trigger_deactivate() == SUCCESS
    assert device.changed == {} and device.puts_back == 1
    node.destroy_node()
    assert device.puts_back == 1
    assert device.links_open == 0


def test_destroying_an_active_bridge_puts_the_device_back(context: Context) -> None:
    """The process's end (destroy_node after SIGINT/SIGTERM) leaves the device as found."""
    device = FakeDevice()
    node = FakeBridge(device, context)
    assert node.trigger_configure() == SUCCESS
    assert node.trigger_activate() == SUCCESS
    node.destroy_node()
    assert device.changed == {}
    assert device.links_open == 0


def test_autostart_refusal_raises_the_bridge_error_naming_it(context: Context) -> None:
    """Autostart true and a failing check: the constructor raises with the refusal."""

    class Starting(FakeBridge):
        def __init__(self, device: FakeDevice, context: Context) -> None:
            BridgeNode.__init__(self, 'fake_bridge', context=context, parameter_overrides=[
                Parameter('robot_name', value='bluerov2_alpha5')])
            self.device, self.faults = device, {'configure': DeviceCheckError('no vehicle')}
            self.start()

    device = FakeDevice()
    with pytest.raises(HardwareError, match='no vehicle'):
        Starting(device, context)
    assert device.links_open == 0
