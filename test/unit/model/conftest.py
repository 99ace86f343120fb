"""Fixtures of the uvms_model tests."""

from __future__ import annotations

import pytest
from model_oracles import PinocchioOracle, build_oracle
from reference_model import ReferenceRobot


@pytest.fixture(scope='module')
def oracle() -> PinocchioOracle:
    """Hand-built Pinocchio model of the paper's rigid bodies."""
    return build_oracle(ReferenceRobot())
