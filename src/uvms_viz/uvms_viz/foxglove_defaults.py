"""Where the Foxglove live view listens unless told otherwise: this machine only."""

#: Address the live view binds by default (loopback: nothing beyond this machine connects).
FOXGLOVE_HOST = '127.0.0.1'

#: Foxglove's customary WebSocket port.
FOXGLOVE_PORT = 8765
