"""A graph whose simulated time stands still ends with an error instead of spinning forever."""

from pathlib import Path

import pytest
from uvms_run.graph import GraphError, build_graph, run_graph
from uvms_scenarios.scenario import load_scenario

from uvms_run import graph as graph_module

SCENARIOS = Path(__file__).resolve().parents[2] / 'config' / 'scenarios'


def test_a_simulator_whose_timers_never_fire_stops_the_run_naming_the_stall(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """No timer of the simulator runs: the run stops after the stall limit with the reason."""
    monkeypatch.setattr(graph_module, 'stall_limit_s', lambda startup_s, lockstep_s: 1.0)
    scenario = load_scenario(SCENARIOS / 'free_motion.yaml').with_changes(duration_s=0.2)
    graph = build_graph(scenario, 'lockstep')
    sim = graph.simulator
    for timer in list(sim.timers):  # the kick never comes: nothing is ever published
        sim.destroy_timer(timer)
    with pytest.raises(GraphError, match=r't = 0\.000 s .* the graph is stalled'):
        run_graph(graph)
