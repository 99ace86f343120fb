"""The pure cores import no ROS: nodes are the only place messages meet numpy."""

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / 'src'

#: Modules that must stay free of ROS: the model, the controller and allocator cores, the
#: simulator's plant, the whole analysis package, the MCAP writer and reader, the marker
#: geometry, and the navigation filter and its health.
PURE_MODULES = sorted(
    [
        *(SRC / 'uvms_model' / 'uvms_model').rglob('*.py'),
        *(SRC / 'uvms_control' / 'uvms_control' / 'core').rglob('*.py'),
        *(
            SRC / 'uvms_thrusters' / 'uvms_thrusters' / f'{name}.py'
            for name in ('allocation', 'errors', 'fault_detection', 'fault_parameters',
                         'parameter_specs', 'parameters', 'thruster_dynamics',
                         'thruster_faults', 'thruster_kernels')
        ),
        SRC / 'uvms_common' / 'uvms_common' / 'parameter_spec.py',
        *(
            path
            for path in (SRC / 'uvms_sim' / 'uvms_sim').rglob('*.py')
            if not path.name.endswith('_node.py')
            and path.name not in ('conversions.py', 'navigation_topics.py', 'startup_watch.py',
                                  'startup_hold.py')
        ),
        *(SRC / 'uvms_analysis' / 'uvms_analysis').rglob('*.py'),
        *(
            SRC / 'uvms_recording' / 'uvms_recording' / name
            for name in ('errors.py', 'mcap_writer.py', 'mcap_reader.py')
        ),
        SRC / 'uvms_viz' / 'uvms_viz' / 'marker_geometry.py',
        *(SRC / 'uvms_navigation' / 'uvms_navigation' / name
          for name in ('eskf.py', 'health.py')),
    ]
)

FORBIDDEN_ROOTS = {'rclpy', 'launch', 'launch_ros', 'ament_index_python'}


def imported_roots(path: Path) -> set[str]:
    """Top-level package names that a module imports."""
    roots = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            roots.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split('.')[0])
    return roots


def test_pure_core_modules_exist() -> None:
    """The model and controller cores are where the layout says they are."""
    names = {path.relative_to(SRC).parts[0] for path in PURE_MODULES if path.exists()}
    assert {'uvms_model', 'uvms_control', 'uvms_thrusters', 'uvms_sim', 'uvms_analysis',
            'uvms_recording'} <= names


@pytest.mark.parametrize('path', PURE_MODULES, ids=lambda p: str(p.relative_to(SRC)))
def test_pure_core_imports_no_ros(path: Path) -> None:
    """A pure core imports neither rclpy nor any message package."""
    if not path.exists():
        pytest.fail(f'{path.relative_to(SRC)} is listed as a pure core but does not exist')
    roots = imported_roots(path)
    ros = {root for root in roots if root in FORBIDDEN_ROOTS or root.endswith('_msgs')}
    assert not ros, f'{path.relative_to(SRC)} imports ROS packages: {sorted(ros)}'
