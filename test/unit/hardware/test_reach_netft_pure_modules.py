"""The Alpha 5 and Net F/T codecs, cores and twins import no ROS: only the bridge nodes do."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[3] / 'src'
#: Modules by their path under src/: the hardware package's cores and the twins' package.
PURE = [*(f'uvms_hardware/uvms_hardware/{name}' for name in (
    'reach_protocol.py', 'rdt_protocol.py', 'hardware_config.py', 'alpha5_core.py',
    'netft_core.py', 'transport.py')), 'uvms_twins/uvms_twins/alpha5_twin.py',
    'uvms_twins/uvms_twins/netft_twin.py']
FORBIDDEN = {'rclpy', 'launch', 'launch_ros', 'ament_index_python'}


@pytest.mark.parametrize('name', PURE)
def test_module_imports_no_ros(name: str) -> None:
    """No rclpy and no message package in a codec, core, transport or twin."""
    roots = set()
    for node in ast.walk(ast.parse((SRC / name).read_text(encoding='utf-8'))):
        if isinstance(node, ast.Import):
            roots.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split('.')[0])
    assert not {r for r in roots if r in FORBIDDEN or r.endswith(('_msgs', '_srvs'))}
