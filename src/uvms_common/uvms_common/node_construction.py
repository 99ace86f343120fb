"""A node whose constructor fails leaves nothing behind: its ROS entities are destroyed at once.

A node constructor that refuses its parameters (``ControlParameterError`` and the like) raises
after rclpy's ``Node.__init__`` has created the node's publishers, services and timers. The
half-built node then lives on in a reference cycle until Python's garbage collector finds it,
at whatever moment and in whatever order it frees the entities (measured on Jazzy: a failed
``ControllerNode`` is still alive after the ``raise`` and goes at the next ``gc.collect()``).
rclpy's own ``destroy_node`` destroys the dependent entities first "to work around a possible
hang" (ros2/build_cop#248); the collector does not. In the CI of 2026-12-06 a test process
that had built several refused controllers hung for good with its main thread at 100 % CPU in
C code under an unrelated line: the collector's teardown of one of them, by every sign (no
Python frame moved; pytest-timeout's signal never ran).

:func:`destroyed_if_construction_fails` wraps a node class's ``__init__``: when it raises, the
node's entities are destroyed in rclpy's order, then the exception goes on. Only rclpy's base
``Node.destroy_node`` runs, not the class's own override (which may expect a device or a file
that the failed constructor never got); nothing may use the node after that, its own
``destroy_node`` included (its destroyed lifecycle state machine is then None). Within
:func:`kept_on_failure` nothing is destroyed: ``uvms_common.node_main`` builds a node
process's node in it, since that process ends at once after a failed build, without the
middleware's teardown (which has hung at stops), so no collector ever gets to the node.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from rclpy.node import Node

_kept_on_failure = False


def destroyed_if_construction_fails(
        init: Callable[..., None]) -> Callable[..., None]:
    """``init`` (a node class's ``__init__``), destroying the node's entities when it raises."""

    @functools.wraps(init)
    def construct(self: Node, *args: Any, **kwargs: Any) -> None:
        try:
            init(self, *args, **kwargs)
        except BaseException:
            destroy_half_built(self)
            raise

    return construct


@contextmanager
def kept_on_failure() -> Iterator[None]:
    """Within the block a constructor that raises leaves its entities to the process's end."""
    global _kept_on_failure
    earlier, _kept_on_failure = _kept_on_failure, True
    try:
        yield
    finally:
        _kept_on_failure = earlier


def destroy_half_built(node: Node) -> None:
    """Destroy what rclpy's ``Node.__init__`` created, if it got that far; never raises.

    Not within :func:`kept_on_failure`.

    ``Node.__init__`` creates its type description service last: without it the base
    constructor itself failed and rclpy has nothing of ours to free.
    """
    if _kept_on_failure or not hasattr(node, '_type_description_service'):
        return
    try:
        Node.destroy_node(node)
        # A lifecycle node's state machine holds the node's handle (and its transition
        # publisher); rclpy's LifecycleNode leaves it to the collector, so it goes here too.
        # Used after that, the destroyed machine crashes the process (a SIGSEGV, measured:
        # a node's own destroy_node reading its state): None makes it an AttributeError.
        state_machine = getattr(node, '_state_machine', None)
        if state_machine is not None:
            state_machine.destroy_when_not_in_use()
            node._state_machine = None  # type: ignore[attr-defined]
    except Exception:  # an entity already gone: the exception that matters is the caller's
        pass
