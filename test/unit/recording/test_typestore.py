"""Tests of uvms_recording.typestore: Jazzy + uvms_msgs types, schemas and type hashes."""

from __future__ import annotations

from pathlib import Path

import pytest
from rosbags.typesys import get_types_from_msg
from uvms_recording.typestore import (
    InterfaceError,
    message_definition,
    normalize_type_name,
    type_hash,
    uvms_msgs_directory,
    uvms_typestore,
)

REPO = Path(__file__).resolve().parents[3]
UVMS_MSG_FILES = sorted((REPO / 'src' / 'uvms_msgs' / 'msg').glob('*.msg'))


def test_uvms_msgs_come_from_the_ament_index_of_the_built_interfaces() -> None:
    """The .msg files the rosidl build installed (share/uvms_msgs/msg) are the ones used."""
    from ament_index_python.packages import get_package_share_directory

    directory = uvms_msgs_directory()
    assert directory == Path(get_package_share_directory('uvms_msgs')) / 'msg'
    assert sorted(p.name for p in directory.glob('*.msg')) == [p.name for p in UVMS_MSG_FILES]


def test_uvms_msgs_are_found_in_the_source_tree_without_an_ament_index(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Without an ament index (nothing built or sourced) the files of src/uvms_msgs/msg serve."""
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(REPO / 'no-such-prefix'))
    assert uvms_msgs_directory() == REPO / 'src' / 'uvms_msgs' / 'msg'


@pytest.mark.parametrize('path', UVMS_MSG_FILES, ids=lambda p: p.stem)
def test_every_uvms_msg_file_is_registered(path: Path) -> None:
    """Each src/uvms_msgs/msg/*.msg is a type 'uvms_msgs/msg/<stem>' of the typestore."""
    assert f'uvms_msgs/msg/{path.stem}' in uvms_typestore().fielddefs


@pytest.mark.parametrize(
    ('type_name', 'published_hash'),
    [
        # Values that ROS 2 Jazzy's rosidl generates (type_description_interfaces, REP-2011).
        ('std_msgs/msg/Header',
         'RIHS01_f49fb3ae2cf070f793645ff749683ac6b06203e41c891e17701b1cb597ce6a01'),
        ('geometry_msgs/msg/Vector3',
         'RIHS01_cc12fe83e4c02719f1ce8070bfd14aecd40f75a96696a67a2a1f37f7dbb0765d'),
        ('builtin_interfaces/msg/Time',
         'RIHS01_b106235e25a4c5ed35098aa0a61a3ee9c9b18d197f398b0e4206cea9acf9c197'),
    ],
)
def test_type_hash_equals_the_hash_jazzy_publishes(type_name: str, published_hash: str) -> None:
    """type_hash gives the RIHS01 string a Jazzy install reports for the same type."""
    assert type_hash(type_name) == published_hash


def test_message_definition_delimits_dependencies_as_rosbag2() -> None:
    """Dependencies follow 80 '=' and 'MSG: pkg/Type' lines, never 'MSG: pkg/msg/Type'."""
    text = message_definition('uvms_msgs/msg/ControllerState')
    assert '=' * 80 + '\nMSG: std_msgs/Header\n' in text
    assert '=' * 80 + '\nMSG: geometry_msgs/Vector3\n' in text
    assert 'MSG: std_msgs/msg/Header' not in text


@pytest.mark.parametrize('path', UVMS_MSG_FILES, ids=lambda p: p.stem)
def test_message_definition_parses_back_to_the_registered_fields(path: Path) -> None:
    """The rosbags .msg parser, given the concatenated text, yields the fields of the type."""
    type_name = f'uvms_msgs/msg/{path.stem}'
    parsed = get_types_from_msg(message_definition(type_name), type_name)
    assert parsed[type_name] == uvms_typestore().fielddefs[type_name]


def test_message_definition_keeps_constants() -> None:
    """The ControllerState phase constants appear in its schema text."""
    text = message_definition('uvms_msgs/msg/ControllerState')
    assert 'uint8 PHASE_CONSTRAINED=2' in text


def test_short_type_name_is_normalized() -> None:
    """'pkg/Type' and 'pkg/msg/Type' name the same type."""
    assert normalize_type_name('sensor_msgs/JointState') == 'sensor_msgs/msg/JointState'
    assert type_hash('sensor_msgs/JointState') == type_hash('sensor_msgs/msg/JointState')


def test_unknown_type_is_reported_by_name() -> None:
    """An unknown type raises InterfaceError naming it."""
    with pytest.raises(InterfaceError, match='no_such_msgs/msg/Thing'):
        message_definition('no_such_msgs/msg/Thing')


def test_malformed_type_name_is_rejected() -> None:
    """A name that is not 'pkg/msg/Type' raises InterfaceError naming it."""
    with pytest.raises(InterfaceError, match='JointState!'):
        type_hash('JointState!')
