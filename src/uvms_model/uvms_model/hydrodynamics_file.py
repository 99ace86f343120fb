"""The hydrodynamics file of a robot (``hydrodynamics.yaml``): per link, checked.

A mapping from link name to that link's parameters: the hull (the root link) by one of the
kinds of ``HULL_ADDED_MASS``, each arm link by one of ``LINK_ADDED_MASS``; every key of the
kind required, unknown keys refused (docs/robots.md, "Adding a robot").
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from uvms_model.errors import DescriptionError

HULL_ADDED_MASS = ('prolate_spheroid', 'coefficients', 'none')
LINK_ADDED_MASS = ('slender_cylinder', 'none')


@dataclass(frozen=True)
class HullHydrodynamics:
    """Hydrodynamic parameters of the vehicle hull (link ``base_link_frd``).

    ``prolate_spheroid`` (and ``none``): added mass from the collision ellipsoid, drag from the
    C_D readings, buoyancy from ``buoyancy_ratio``. ``coefficients``: the published
    coefficients of Fossen's model as magnitudes (docs/robots.md): M_A = diag(added_mass_kg),
    D = diag(linear_damping) + diag(quadratic_damping) |nu|, buoyancy from
    ``displaced_volume_m3`` or ``buoyancy_ratio`` (the other None).
    """

    added_mass: str = 'prolate_spheroid'
    buoyancy_ratio: float | None = 1.0
    center_of_buoyancy_m: tuple[float, float, float] = (0.028, 0.0, 0.0)
    linear_drag_translation_n_s_m: float = 0.0
    linear_drag_rotation_n_m_s: float = 0.81
    drag_coefficient_translation: float = 1.05
    drag_coefficient_rotation: float = 1.0
    added_mass_kg: tuple[float, ...] | None = None
    linear_damping: tuple[float, ...] | None = None
    quadratic_damping: tuple[float, ...] | None = None
    displaced_volume_m3: float | None = None


@dataclass(frozen=True)
class LinkHydrodynamics:
    """Hydrodynamic parameters of one arm link (a slender cylinder)."""

    added_mass: str = 'slender_cylinder'
    cross_flow_drag_coefficient: float = 1.1


#: Keys of each entry of the hydrodynamics file: (type, valid range or choices).
_HULL_KEYS: dict[str, tuple[str, Any]] = {
    'added_mass': ('choice', HULL_ADDED_MASS),
    'buoyancy_ratio': ('float', (0.0, 10.0)),
    'center_of_buoyancy_m': ('vector3', (-100.0, 100.0)),
    'linear_drag_translation_n_s_m': ('float', (0.0, 1e7)),
    'linear_drag_rotation_n_m_s': ('float', (0.0, 1e7)),
    'drag_coefficient_translation': ('float', (0.0, 100.0)),
    'drag_coefficient_rotation': ('float', (0.0, 100.0)),
}
_HULL_COEFFICIENT_KEYS: dict[str, tuple[str, Any]] = {
    'added_mass': ('choice', HULL_ADDED_MASS),
    'added_mass_kg': ('vector6', (0.0, 1e7)),
    'linear_damping': ('vector6', (0.0, 1e7)),
    'quadratic_damping': ('vector6', (0.0, 1e7)),
    'center_of_buoyancy_m': ('vector3', (-100.0, 100.0)),
    'buoyancy_ratio': ('float', (0.0, 10.0)),
    'displaced_volume_m3': ('float', (0.0, 1e4)),
}
#: Keys of which a coefficient hull takes exactly one.
_HULL_BUOYANCY_KEYS = ('buoyancy_ratio', 'displaced_volume_m3')
_LINK_KEYS: dict[str, tuple[str, Any]] = {
    'added_mass': ('choice', LINK_ADDED_MASS),
    'cross_flow_drag_coefficient': ('float', (0.0, 100.0)),
}


def _entry(
    path: Path, link: str, raw: object, keys: Mapping[str, tuple[str, Any]]
) -> dict[str, Any]:
    """Validate one link's entry of the hydrodynamics file against its keys."""
    if not isinstance(raw, Mapping):
        raise DescriptionError(f'{path}: {link}: expected a mapping of parameters')
    unknown = sorted(set(raw) - set(keys))
    if unknown:
        raise DescriptionError(f'{path}: {link}: unknown keys {unknown}; known: {sorted(keys)}')
    missing = sorted(set(keys) - set(raw))
    if missing:
        raise DescriptionError(f'{path}: {link}: missing keys {missing}')
    values: dict[str, Any] = {}
    for key, (kind, valid) in keys.items():
        value = raw[key]
        where = f'{path}: {link}.{key} = {value!r}'
        if kind == 'choice':
            if value not in valid:
                raise DescriptionError(f'{where} must be one of {list(valid)}')
            values[key] = value
            continue
        size = {'vector3': 3, 'vector6': 6}.get(kind, 1)
        items = value if size > 1 else [value]
        if (
            not isinstance(items, list)
            or len(items) != size
            or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in items)
        ):
            expected = f'{size} numbers' if size > 1 else 'a number'
            raise DescriptionError(f'{where} must be {expected}')
        lo, hi = valid
        if not all(math.isfinite(v) and lo <= v <= hi for v in items):
            raise DescriptionError(f'{where} is out of range [{lo}, {hi}]')
        floats = tuple(float(v) for v in items)
        values[key] = floats if size > 1 else floats[0]
    return values


def _hull_entry(path: Path, root: str, raw: object) -> HullHydrodynamics:
    """The hull's entry: the keys of its ``added_mass`` kind, each checked."""
    if not (isinstance(raw, Mapping) and raw.get('added_mass') == 'coefficients'):
        return HullHydrodynamics(**_entry(path, root, raw, _HULL_KEYS))
    given = [key for key in _HULL_BUOYANCY_KEYS if key in raw]
    if len(given) != 1:
        raise DescriptionError(
            f'{path}: {root}: added_mass: coefficients takes exactly one of '
            f'{list(_HULL_BUOYANCY_KEYS)}, got {given}'
        )
    keys = {k: v for k, v in _HULL_COEFFICIENT_KEYS.items()
            if k not in _HULL_BUOYANCY_KEYS or k in given}
    values = _entry(path, root, raw, keys)
    values.setdefault('buoyancy_ratio', None)
    return HullHydrodynamics(**values)


def read_hydrodynamics(
    path: Path, root: str, arm_links: tuple[str, ...]
) -> tuple[HullHydrodynamics, tuple[LinkHydrodynamics, ...]]:
    """The hull's and each arm link's parameters from the file at ``path``.

    Raises:
        DescriptionError: An unreadable or malformed file, a link that is not the hull or
            an arm link, a missing entry or key, an unknown key, a value out of range.
    """
    try:
        text = path.read_text(encoding='utf-8')
    except OSError as exc:
        msg = f'{path}: cannot read the hydrodynamic parameters: {exc.strerror or exc}'
        raise DescriptionError(msg) from exc
    try:
        tree = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise DescriptionError(f'{path}: malformed YAML: {exc}'.replace('\n', ' ')) from exc
    if not isinstance(tree, Mapping):
        raise DescriptionError(f'{path}: expected a mapping from link names to parameters')
    known = (root, *arm_links)
    unknown = sorted(set(tree) - set(known))
    if unknown:
        raise DescriptionError(
            f'{path}: links {unknown} are not the hull or arm links of the URDF {list(known)}'
        )
    for link in known:
        if link not in tree:
            raise DescriptionError(f'{path}: link {link} has no entry')
    hull = _hull_entry(path, root, tree[root])
    links = tuple(
        LinkHydrodynamics(**_entry(path, link, tree[link], _LINK_KEYS)) for link in arm_links
    )
    return hull, links
