"""Devices served in the simulator's process: what the simulator hands them, what it takes.

A `PlantSide` given to ``SimulatorNode`` (``uvms_twins.simulator_with_twins``: the protocol
twins) stands for the devices in the simulator's own process: it is handed each published
state and navigation reading by call instead of the device-side topics (joint_states, wrench,
imu, dvl, depth, position_fix), and gives the actuator command instead of
``command/actuators``.
"""

from __future__ import annotations

from typing import Any, Protocol

from uvms_model.nav_sensors import Reading

from uvms_sim.navigation_topics import NavigationTopics
from uvms_sim.plant import Observation


class PlantSide(Protocol):
    """The devices, served in the simulator's process: its measurements in, its command out."""

    def observe(self, seen: Observation) -> None:
        """Each published state, joint states and wrench as the devices deliver them."""

    def reading(self, reading: Reading) -> None:
        """Each navigation reading when it is due (after its latency), valid or not."""

    def command(self, t_ns: int) -> tuple[Any, Any] | None:
        """Thrusts (N) and joint torques (N m, the model's order) from ``t_ns`` on; None: none."""


class PlantSideNavigation(NavigationTopics):
    """The navigation sensors' readings handed to a `PlantSide`, not published."""

    def __init__(self, plant_side: PlantSide, *args: Any) -> None:
        super().__init__(*args)
        self._plant_side = plant_side

    def _send(self, reading: Reading) -> None:
        self._plant_side.reading(reading)
