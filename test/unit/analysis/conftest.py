"""Fixtures: synthetic recordings with known signals (see analysis_recordings)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
from analysis_recordings import Signals, contact_signals, free_motion_signals, write_signals


@pytest.fixture(scope='session')
def contact_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The known contact run, recorded with scenario name 'case1_synthetic'."""
    path = tmp_path_factory.mktemp('recordings') / 'contact.mcap'
    return write_signals(path, contact_signals(), scenario='case1_synthetic')


@pytest.fixture(scope='session')
def moving_wall_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The known contact run with a wall that starts moving at 0.05 m/s after contact."""
    path = tmp_path_factory.mktemp('recordings') / 'moving_wall.mcap'
    return write_signals(path, contact_signals(moving_wall=True), scenario='case3_synthetic')


@pytest.fixture(scope='session')
def free_motion_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The free-motion run, without scenario metadata and without thruster state."""
    path = tmp_path_factory.mktemp('recordings') / 'free_motion_run.mcap'
    return write_signals(path, free_motion_signals(), thrusters=False)


@pytest.fixture
def recording_factory(tmp_path: Path) -> Callable[..., Path]:
    """Write a run from signals into tmp_path: ``factory(name, signals, **kwargs)``."""

    def factory(name: str, signals: Signals, **kwargs: Any) -> Path:
        return write_signals(tmp_path / f'{name}.mcap', signals, **kwargs)

    return factory
