"""Information about the publishers and subscriptions of a topic (rclpy.topic_endpoint_info)."""

from __future__ import annotations

from enum import IntEnum
from typing import Any

from rclpy.qos import QoSProfile


class TopicEndpointTypeEnum(IntEnum):
    """Kind of endpoint."""

    INVALID = 0
    PUBLISHER = 1
    SUBSCRIPTION = 2


class TopicEndpointInfo:
    """A publisher or subscription of a topic: its node, type, kind and QoS."""

    def __init__(
        self,
        node_name: str = '',
        node_namespace: str = '',
        topic_type: str = '',
        topic_type_hash: Any = None,
        endpoint_type: TopicEndpointTypeEnum = TopicEndpointTypeEnum.INVALID,
        endpoint_gid: list[int] | None = None,
        qos_profile: QoSProfile | None = None,
    ) -> None:
        self.node_name = node_name
        self.node_namespace = node_namespace
        self.topic_type = topic_type
        self.topic_type_hash = topic_type_hash
        self.endpoint_type = endpoint_type
        self.endpoint_gid = list(endpoint_gid or [])
        self.qos_profile = qos_profile

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, TopicEndpointInfo):
            return False
        return vars(self) == vars(other)

    __hash__ = None  # type: ignore[assignment]

    def __str__(self) -> str:
        return '\n'.join([
            f'Node name: {self.node_name}',
            f'Node namespace: {self.node_namespace}',
            f'Topic type: {self.topic_type}',
            f'Endpoint type: {self.endpoint_type.name}',
            f'GID: {".".join(format(x, "02x") for x in self.endpoint_gid)}',
            'QoS profile:',
            f'  {self.qos_profile}',
        ])
