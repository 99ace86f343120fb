"""Parameters of the compat rclpy: declaration, descriptors, callbacks, overrides and files.

Each test states the behaviour of rclpy (Jazzy) or rcl_yaml_param_parser it mirrors.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import rclpy
from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    SetParametersResult,
)
from rclpy.context import Context
from rclpy.exceptions import (
    InvalidParameterTypeException,
    InvalidParameterValueException,
    ParameterAlreadyDeclaredException,
    ParameterNotDeclaredException,
    ParameterUninitializedException,
)
from rclpy.impl.implementation_singleton import RCLError
from rclpy.node import Node
from rclpy.parameter import Parameter


def make_node(args: list[str], name: str = 'controller', namespace: str = '/uvms',
              **kwargs: object) -> Node:
    """A node whose context was initialized with ``args``."""
    context = Context()
    rclpy.init(args=args, context=context)
    return Node(name, namespace=namespace, context=context, **kwargs)  # type: ignore[arg-type]


def write(tmp_path: Path, name: str, text: str) -> str:
    """Write a parameter file and return its path."""
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def unit_range(step: float = 0.0) -> ParameterDescriptor:
    """A descriptor allowing doubles in [0, 1]."""
    return ParameterDescriptor(
        floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1.0, step=step)]
    )


# -- declaration, get and set ------------------------------------------------------------------


def test_declared_parameter_has_its_default(node: Node) -> None:
    """As in rclpy, declare_parameter returns the parameter with the default as its value."""
    declared = node.declare_parameter('gain', 2.5)
    assert declared.value == 2.5
    assert node.get_parameter('gain').type_ == Parameter.Type.DOUBLE
    assert node.has_parameter('gain')


def test_declaring_twice_raises(node: Node) -> None:
    """As in rclpy, declaring a declared parameter raises ParameterAlreadyDeclaredException."""
    node.declare_parameter('gain', 1.0)
    with pytest.raises(ParameterAlreadyDeclaredException, match='gain'):
        node.declare_parameter('gain', 2.0)


def test_undeclared_parameter_access_raises(node: Node) -> None:
    """As in rclpy, get and set of an undeclared parameter raise ParameterNotDeclaredException."""
    with pytest.raises(ParameterNotDeclaredException, match='missing'):
        node.get_parameter('missing')
    with pytest.raises(ParameterNotDeclaredException, match='missing'):
        node.set_parameters([Parameter('missing', value=1)])


def test_undeclared_parameters_allowed_when_requested(context: Context) -> None:
    """As in rclpy, allow_undeclared_parameters lets set_parameters create parameters."""
    free = Node('free', context=context, allow_undeclared_parameters=True)
    assert free.get_parameter('x').type_ == Parameter.Type.NOT_SET
    assert free.set_parameters([Parameter('x', value=3)])[0].successful
    assert free.get_parameter('x').value == 3
    free.destroy_node()


def test_parameter_declared_with_type_only_is_uninitialized(node: Node) -> None:
    """As in rclpy, declaring with a Parameter.Type gives a typed parameter without a value."""
    node.declare_parameter('mass_kg', Parameter.Type.DOUBLE)
    with pytest.raises(ParameterUninitializedException, match='mass_kg'):
        node.get_parameter('mass_kg')
    assert node.get_parameter_or('mass_kg', Parameter('mass_kg', value=1.0)).value == 1.0
    assert not node.set_parameters([Parameter('mass_kg', value='heavy')])[0].successful
    assert node.set_parameters([Parameter('mass_kg', value=530.0)])[0].successful
    assert node.get_parameter('mass_kg').value == 530.0


def test_set_parameter_of_wrong_type_is_rejected(node: Node) -> None:
    """As in rclpy, setting a double parameter to a string fails with 'Wrong parameter type'."""
    node.declare_parameter('gain', 1.0)
    result = node.set_parameters([Parameter('gain', value='fast')])[0]
    assert not result.successful
    assert "Wrong parameter type, expected 'Type.DOUBLE' got 'Type.STRING'" in result.reason
    assert node.get_parameter('gain').value == 1.0


def test_integer_is_rejected_for_double_parameter(node: Node) -> None:
    """As in rclpy, an int is not a double: set(gain=1) on a double parameter fails."""
    node.declare_parameter('gain', 1.0)
    result = node.set_parameters([Parameter('gain', value=2)])[0]
    assert not result.successful
    assert 'Type.INTEGER' in result.reason


def test_value_outside_floating_point_range_is_rejected(node: Node) -> None:
    """As in rclpy, a value outside [from_value, to_value] fails naming min, max and value."""
    node.declare_parameter('weight', 0.5, unit_range())
    result = node.set_parameters([Parameter('weight', value=1.5)])[0]
    assert not result.successful
    assert 'weight out of range' in result.reason
    assert 'Min: 0.0, Max: 1.0, value: 1.5' in result.reason
    assert node.set_parameters([Parameter('weight', value=1.0)])[0].successful


def test_floating_point_range_step_is_honoured(node: Node) -> None:
    """As in rclpy, with a step only from_value + k*step (within 1e-6 relative) is accepted."""
    node.declare_parameter('weight', 0.5, unit_range(step=0.25))
    assert node.set_parameters([Parameter('weight', value=0.75)])[0].successful
    result = node.set_parameters([Parameter('weight', value=0.3)])[0]
    assert not result.successful
    assert 'step' in result.reason


def test_integer_range_and_step_are_enforced(node: Node) -> None:
    """As in rclpy, integer_range bounds and step apply to integer parameters."""
    descriptor = ParameterDescriptor(
        integer_range=[IntegerRange(from_value=6, to_value=12, step=2)]
    )
    node.declare_parameter('thrusters', 8, descriptor)
    assert node.set_parameters([Parameter('thrusters', value=10)])[0].successful
    assert not node.set_parameters([Parameter('thrusters', value=9)])[0].successful
    result = node.set_parameters([Parameter('thrusters', value=14)])[0]
    assert not result.successful
    assert 'Min: 6, Max: 12, value: 14' in result.reason


def test_read_only_parameter_cannot_be_set(node: Node) -> None:
    """As in rclpy, a read_only descriptor makes set_parameters fail."""
    node.declare_parameter('robot', 'uvms', ParameterDescriptor(read_only=True))
    result = node.set_parameters([Parameter('robot', value='other')])[0]
    assert not result.successful
    assert 'read-only' in result.reason
    assert node.get_parameter('robot').value == 'uvms'


def test_dynamic_typing_allows_type_change(node: Node) -> None:
    """As in rclpy, dynamic_typing=True lets a parameter change its type."""
    node.declare_parameter('anything', 1, ParameterDescriptor(dynamic_typing=True))
    assert node.set_parameters([Parameter('anything', value='text')])[0].successful
    assert node.get_parameter('anything').value == 'text'


def test_on_set_callback_can_reject_with_reason(node: Node) -> None:
    """As in rclpy, an on-set callback returning successful=False refuses the change."""
    node.declare_parameter('gain', 1.0)

    def refuse_negative(params: list[Parameter]) -> SetParametersResult:
        for param in params:
            if param.name == 'gain' and param.value < 0.0:
                return SetParametersResult(successful=False, reason='gain must be >= 0')
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(refuse_negative)
    result = node.set_parameters([Parameter('gain', value=-1.0)])[0]
    assert not result.successful
    assert result.reason == 'gain must be >= 0'
    node.remove_on_set_parameters_callback(refuse_negative)
    assert node.set_parameters([Parameter('gain', value=-1.0)])[0].successful


def test_set_parameters_atomically_sets_all_or_none(node: Node) -> None:
    """As in rclpy, set_parameters_atomically changes nothing if one parameter is rejected."""
    node.declare_parameter('a', 1.0)
    node.declare_parameter('b', 2.0)
    result = node.set_parameters_atomically(
        [Parameter('a', value=10.0), Parameter('b', value='bad')]
    )
    assert not result.successful
    assert node.get_parameter('a').value == 1.0


def test_declare_parameters_prefixes_the_namespace(node: Node) -> None:
    """As in rclpy, declare_parameters('ns', [(name, value)]) declares 'ns.name'."""
    node.declare_parameters('impedance', [('stiffness', 1000.0), ('damping', 50.0)])
    assert node.get_parameter('impedance.stiffness').value == 1000.0
    by_prefix = node.get_parameters_by_prefix('impedance')
    assert sorted(by_prefix) == ['damping', 'stiffness']


def test_describe_parameter_reports_declared_type(node: Node) -> None:
    """As in rclpy, describe_parameter gives the descriptor with name and type filled in."""
    node.declare_parameter('weight', 0.5, unit_range())
    descriptor = node.describe_parameter('weight')
    assert descriptor.name == 'weight'
    assert descriptor.type == Parameter.Type.DOUBLE.value
    assert descriptor.floating_point_range[0].to_value == 1.0


def test_post_set_callback_sees_accepted_parameters(node: Node) -> None:
    """As in rclpy, post-set callbacks are called with the parameters that were set."""
    node.declare_parameter('gain', 1.0)
    seen: list[float] = []
    node.add_post_set_parameters_callback(lambda params: seen.extend(p.value for p in params))
    node.set_parameters([Parameter('gain', value=3.0)])
    assert seen == [3.0]


# -- overrides from the command line and parameter files ------------------------------------


def test_command_line_override_replaces_default_at_declaration() -> None:
    """As in rclpy, --ros-args -p name:=value sets the initial value of a declared parameter."""
    node = make_node(['prog', '--ros-args', '-p', 'gain:=3.5'])
    assert node.declare_parameter('gain', 1.0).value == 3.5
    node.context.try_shutdown()


@pytest.mark.parametrize(
    ('text', 'expected', 'type_'),
    [
        ('1', 1, Parameter.Type.INTEGER),
        ('1.0', 1.0, Parameter.Type.DOUBLE),
        ('1e3', 1000.0, Parameter.Type.DOUBLE),
        ('0x10', 16, Parameter.Type.INTEGER),
        ('true', True, Parameter.Type.BOOL),
        ('y', True, Parameter.Type.BOOL),
        ('Off', False, Parameter.Type.BOOL),
        ('hello', 'hello', Parameter.Type.STRING),
        ("'1'", '1', Parameter.Type.STRING),
        ('[1.0, 2.5]', [1.0, 2.5], Parameter.Type.DOUBLE_ARRAY),
        ('[a, b]', ['a', 'b'], Parameter.Type.STRING_ARRAY),
    ],
)
def test_command_line_values_are_typed_as_rcl_does(
    text: str, expected: object, type_: Parameter.Type
) -> None:
    """As rcl_yaml_param_parser types a -p value: bools, strtoll ints, strtod doubles, strings."""
    node = make_node(
        ['--ros-args', '-p', f'value:={text}'],
        automatically_declare_parameters_from_overrides=True,
    )
    parameter = node.get_parameter('value')
    node.context.try_shutdown()
    assert parameter.type_ == type_
    assert parameter.value == expected


def test_integer_override_for_double_parameter_fails_naming_parameter_and_source() -> None:
    """As in rclpy, an int override of a double raises InvalidParameterTypeException."""
    node = make_node(['--ros-args', '-p', 'gain:=1'])
    with pytest.raises(InvalidParameterTypeException) as info:
        node.declare_parameter('gain', 1.0)
    node.context.try_shutdown()
    message = str(info.value)
    assert "'gain'" in message and "'1'" in message
    assert "of type 'INTEGER', expecting type 'DOUBLE'" in message
    assert "-p 'gain:=1'" in message


def test_out_of_range_override_fails_naming_value_range_and_file(tmp_path: Path) -> None:
    """As in rclpy, an out-of-range override raises InvalidParameterValueException at declare."""
    path = write(tmp_path, 'gains.yaml', '/**:\n  ros__parameters:\n    weight: 1.5\n')
    node = make_node(['--ros-args', '--params-file', path])
    with pytest.raises(InvalidParameterValueException) as info:
        node.declare_parameter('weight', 0.5, unit_range())
    node.context.try_shutdown()
    message = str(info.value)
    assert 'weight' in message and '1.5' in message
    assert 'Min: 0.0, Max: 1.0' in message
    assert f"'{path}' line 3" in message


def test_params_file_applies_to_node_key_and_wildcards(tmp_path: Path) -> None:
    """As in rclpy, file keys /ns/node, /**, and /**/node select the nodes they apply to."""
    path = write(tmp_path, 'params.yaml', (
        '/**:\n'
        '  ros__parameters:\n'
        '    shared: 1\n'
        '/uvms/controller:\n'
        '  ros__parameters:\n'
        '    own: 2\n'
        '/**/controller:\n'
        '  ros__parameters:\n'
        '    any_ns: 3\n'
        '/other:\n'
        '  ros__parameters:\n'
        '    not_mine: 4\n'
    ))
    node = make_node(
        ['--ros-args', '--params-file', path], automatically_declare_parameters_from_overrides=True
    )
    names = {name: node.get_parameter(name).value for name in ('shared', 'own', 'any_ns')}
    has_other = node.has_parameter('not_mine')
    node.context.try_shutdown()
    assert names == {'shared': 1, 'own': 2, 'any_ns': 3}
    assert not has_other


def test_params_file_nested_namespaces_and_node_levels(tmp_path: Path) -> None:
    """As in rcl: nested keys above ros__parameters form the node name, below they dot names."""
    path = write(tmp_path, 'params.yaml', (
        'uvms:\n'
        '  controller:\n'
        '    ros__parameters:\n'
        '      impedance:\n'
        '        stiffness: 1000.0\n'
        '        damping:\n'
        '          linear: 50.0\n'
    ))
    node = make_node(['--ros-args', '--params-file', path])
    stiffness = node.declare_parameter('impedance.stiffness', 0.0).value
    linear = node.declare_parameter('impedance.damping.linear', 0.0).value
    node.context.try_shutdown()
    assert (stiffness, linear) == (1000.0, 50.0)


def test_params_file_arrays_get_ros2_array_types(tmp_path: Path) -> None:
    """As in rcl: homogeneous sequences become bool[], int64[], double[] and string[]."""
    path = write(tmp_path, 'params.yaml', (
        '/**:\n'
        '  ros__parameters:\n'
        '    flags: [true, false]\n'
        '    counts: [1, 2, 3]\n'
        '    gains: [0.5, 1.5]\n'
        '    joints:\n'
        '      - joint_1\n'
        '      - joint_2\n'
    ))
    node = make_node(
        ['--ros-args', '--params-file', path], automatically_declare_parameters_from_overrides=True
    )
    types = {n: node.get_parameter(n).type_ for n in ('flags', 'counts', 'gains', 'joints')}
    values = {n: list(node.get_parameter(n).value) for n in ('flags', 'counts', 'gains', 'joints')}
    node.context.try_shutdown()
    assert types == {
        'flags': Parameter.Type.BOOL_ARRAY,
        'counts': Parameter.Type.INTEGER_ARRAY,
        'gains': Parameter.Type.DOUBLE_ARRAY,
        'joints': Parameter.Type.STRING_ARRAY,
    }
    assert values['gains'] == [0.5, 1.5]
    assert values['joints'] == ['joint_1', 'joint_2']


def test_later_sources_override_earlier_ones(tmp_path: Path) -> None:
    """As rcl merges overrides in command-line order: later files and -p rules win."""
    first = write(
        tmp_path, 'first.yaml', '/**:\n  ros__parameters:\n    a: 1\n    b: 1\n    c: 1\n'
    )
    second = write(tmp_path, 'second.yaml', '/**:\n  ros__parameters:\n    b: 2\n    c: 2\n')
    node = make_node([
        '--ros-args', '--params-file', first, '--params-file', second, '-p', 'c:=3',
    ])
    values = [node.declare_parameter(name, 0).value for name in ('a', 'b', 'c')]
    node.context.try_shutdown()
    assert values == [1, 2, 3]


def test_node_cli_args_and_parameter_overrides_win_over_global_arguments() -> None:
    """As in rclpy: node cli_args apply after the context's; parameter_overrides win over all."""
    node = make_node(
        ['--ros-args', '-p', 'a:=1', '-p', 'b:=1'],
        cli_args=['--ros-args', '-p', 'a:=2', '-p', 'b:=2'],
        parameter_overrides=[Parameter('b', value=3)],
    )
    values = [node.declare_parameter('a', 0).value, node.declare_parameter('b', 0).value]
    node.context.try_shutdown()
    assert values == [2, 3]


def test_node_specific_command_line_rule_applies_to_that_node_only() -> None:
    """As in rcl: -p node_name:param:=value applies only to the node of that name."""
    context = Context()
    rclpy.init(args=['--ros-args', '-p', 'controller:gain:=5.0'], context=context)
    controller = Node('controller', context=context)
    other = Node('allocator', context=context)
    values = [controller.declare_parameter('gain', 1.0).value,
              other.declare_parameter('gain', 1.0).value]
    context.try_shutdown()
    assert values == [5.0, 1.0]


def test_ignore_override_keeps_the_default() -> None:
    """As in rclpy, declare_parameter(..., ignore_override=True) ignores overrides."""
    node = make_node(['--ros-args', '-p', 'gain:=9.0'])
    value = node.declare_parameter('gain', 1.0, ignore_override=True).value
    node.context.try_shutdown()
    assert value == 1.0


def test_yaml_syntax_error_names_file_and_line(tmp_path: Path) -> None:
    """As rcl refuses a malformed file at init: the error names the file and the line."""
    path = write(tmp_path, 'broken.yaml', '/**:\n  ros__parameters:\n    a: [1, 2\n    b: 3\n')
    context = Context()
    with pytest.raises(RCLError, match=r"broken\.yaml'.*line \d+, column \d+: YAML syntax"):
        rclpy.init(args=['--ros-args', '--params-file', path], context=context)


def test_missing_params_file_names_the_file(tmp_path: Path) -> None:
    """As rcl fails init for an unreadable --params-file, naming it."""
    missing = str(tmp_path / 'nowhere.yaml')
    with pytest.raises(RCLError, match=r"nowhere\.yaml' does not exist"):
        rclpy.init(args=['--ros-args', '--params-file', missing], context=Context())


def test_mixed_type_sequence_is_an_error_naming_the_line(tmp_path: Path) -> None:
    """As rcl: 'Sequence should be of same type' (e.g. [1, 2.5]) fails, naming the line."""
    path = write(tmp_path, 'mixed.yaml', '/**:\n  ros__parameters:\n    gains: [1, 2.5]\n')
    with pytest.raises(RCLError, match=r"mixed\.yaml' line 3: sequence 'gains' mixes types"):
        rclpy.init(args=['--ros-args', '--params-file', path], context=Context())


def test_parameter_without_value_is_an_error(tmp_path: Path) -> None:
    """As rcl: 'No value at line N' for a key without a value."""
    path = write(tmp_path, 'empty.yaml', '/**:\n  ros__parameters:\n    gain:\n')
    with pytest.raises(RCLError, match=r"line 3: no value for parameter 'gain'"):
        rclpy.init(args=['--ros-args', '--params-file', path], context=Context())
