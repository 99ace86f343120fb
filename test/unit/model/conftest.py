"""Fixtures of the uvms_model tests."""

from __future__ import annotations

import pytest
from model_oracles import PinocchioOracle, build_oracle

from uvms_model import UvmsParameters


@pytest.fixture(scope='module')
def oracle() -> PinocchioOracle:
    """Pinocchio oracle for the default parameters."""
    return build_oracle(UvmsParameters())
