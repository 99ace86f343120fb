"""Exception types of uvms_hardware."""

from __future__ import annotations


class HardwareError(Exception):
    """Base class of every error raised by uvms_hardware."""


class ProtocolError(HardwareError, ValueError):
    """Bytes that do not decode as the protocol defines them (bad frame, CRC, length)."""


class DeviceCheckError(HardwareError):
    """A check of the device failed at configure: the message names what is wrong.

    A bridge refuses to activate on it (configure returns FAILURE with this message logged).
    """


class AddressError(HardwareError, ValueError):
    """A connection string or address parameter that cannot be parsed."""
