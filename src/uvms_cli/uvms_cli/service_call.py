"""One synchronous ROS 2 service call with a bound, as ``uvms lifecycle`` and ``uvms param`` make.

There is no ros2cli wheel; these commands call a node's services themselves::

    answer = call_service(node, client, request, 5.0, ParamCallError, 'is the graph running?')
"""

from __future__ import annotations

from typing import Any


def call_service(node: Any, client: Any, request: Any, timeout_s: float,
                 error_type: type[Exception], hint: str) -> Any:
    """The answer of ``client`` to ``request``, spinning ``node``; each wait ``timeout_s``.

    Raises:
        error_type: the service did not appear (the message ends with ``hint``) or gave no
            answer within the timeout; both name the service.
    """
    import rclpy

    if not client.wait_for_service(timeout_sec=timeout_s):
        msg = f'{client.srv_name} did not appear within {timeout_s:g} s{hint}'
        raise error_type(msg)
    future = client.call_async(request)
    rclpy.spin_until_future_complete(node, future, timeout_sec=timeout_s)
    if not future.done() or future.result() is None:
        msg = f'{client.srv_name} gave no answer within {timeout_s:g} s'
        raise error_type(msg)
    return future.result()
