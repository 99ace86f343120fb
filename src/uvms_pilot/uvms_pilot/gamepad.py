"""A gamepad through Linux's input devices (python-evdev): found, opened, read in a thread.

``find_gamepad`` picks the first /dev/input/event* device that has sticks and a south face
button (the kernel's gamepad.rst); ``GamepadReader`` hands every event to the session
(``PilotSession.gamepad_event``) and, when the device goes away, zeroes its state and says so.
"""

from __future__ import annotations

import select
import threading
from collections.abc import Callable
from typing import Any

from uvms_pilot.errors import PilotError

#: Longest wait in one select() of the reader (s): how fast it sees a stop request.
READ_TURN_S = 0.1


def find_gamepad() -> str:
    """The path of the first input device that looks like a gamepad.

    Raises:
        PilotError: None is found (or none is readable: the input group, udev rules).
    """
    import evdev
    from evdev import ecodes

    for path in evdev.list_devices():
        try:
            device = evdev.InputDevice(path)
        except OSError:
            continue
        with device:
            capabilities = device.capabilities()
            if ecodes.EV_ABS in capabilities and ecodes.BTN_SOUTH in capabilities.get(
                    ecodes.EV_KEY, []):
                return str(path)
    msg = ('no gamepad among the readable /dev/input/event* devices (plugged in? your user '
           'in the input group?); give one with --gamepad /dev/input/eventN')
    raise PilotError(msg)


def open_gamepad(path: str) -> tuple[Any, dict[int, tuple[int, int]]]:
    """Open an input device; (the evdev InputDevice, its axis ranges code -> (min, max)).

    Raises:
        PilotError: The device cannot be opened (named, with the reason).
    """
    import evdev
    from evdev import ecodes

    try:
        device = evdev.InputDevice(path)
    except OSError as exc:
        msg = f'gamepad {path}: cannot open: {exc.strerror or exc}'
        raise PilotError(msg) from None
    ranges = {int(code): (int(info.min), int(info.max))
              for code, info in device.capabilities(absinfo=True).get(ecodes.EV_ABS, [])}
    return device, ranges


class GamepadReader:
    """Reads a device's events in a thread of its own and hands them on.

    Args:
        device: An open evdev InputDevice (or anything with ``fd``, ``read()`` and ``path``).
        on_event: Called with (type, code, value) of each event, in the reader's thread.
        on_lost: Called once if the device goes away (unplugged, out of range).
    """

    def __init__(self, device: Any, on_event: Callable[[int, int, int], None],
                 on_lost: Callable[[str], None]) -> None:
        self.device = device
        self._on_event = on_event
        self._on_lost = on_lost
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='gamepad', daemon=True)

    def start(self) -> None:
        """Start reading."""
        self._thread.start()

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                ready, _, _ = select.select([self.device.fd], [], [], READ_TURN_S)
                if not ready:
                    continue
                for event in self.device.read():
                    self._on_event(event.type, event.code, event.value)
        except (OSError, ValueError) as exc:  # ENODEV when unplugged; fd closed under us
            if not self._stop.is_set():
                self._on_lost(f'gamepad {self.device.path} lost: {exc}; its input is zero')

    def stop(self) -> None:
        """Stop reading and close the device."""
        self._stop.set()
        self._thread.join(timeout=1.0)
        self.device.close()
