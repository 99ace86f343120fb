"""Run batches of point requests on Ray for a caller that is not a sweep (``uvms tune``).

A ``PointBatches`` holds one Ray (started locally on 127.0.0.1 or joined, as ``uvms sweep``
does: ``engine.start_local_ray``, ``engine.join_ray``) and its stop flag for the caller's
lifetime, and runs each batch of requests (``execute_point``'s, built by ``point_request``)
as point tasks with ROS domains of their own, returning the outcomes in request order.
Every other package reaches Ray through here: only uvms_sweep imports ``ray``.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

from uvms_common.node_main import StopEvent

from uvms_sweep.engine import (
    CANCEL_GRACE_S,
    DOMAIN_IDS,
    _import_ray,
    join_ray,
    start_local_ray,
)
from uvms_sweep.point import INTERRUPTED
from uvms_sweep.stop_flag import point_task, ray_error_line, start_stop_flag

#: Wall-clock period at which a batch checks for Ctrl-C while its points run (s).
_WAIT_S = 0.5


def point_request(
    point_id: str, scenario_path: Path, duration_s: float, seed: int,
    overrides: Mapping[str, Mapping[str, Any]], *, record: bool = False,
) -> dict[str, Any]:
    """The request of one point (``execute_point``): a scenario file with overrides.

    Args:
        point_id: Name of the point in logs and outcomes.
        scenario_path: The base scenario file.
        duration_s: Simulated duration (s).
        seed: Sensor noise seed.
        overrides: Node name to dotted parameter name to value, over the scenario's.
        record: Return the run's MCAP bytes with the outcome.
    """
    return {'point_id': point_id, 'scenario_path': str(Path(scenario_path).resolve()),
            'duration_s': float(duration_s), 'seed': int(seed),
            'overrides': {node: dict(values) for node, values in overrides.items()},
            'record': record}


class PointBatches:
    """A Ray for batches of points: local by default, a cluster with ``address``.

    Use it as a context manager; a Ray this process is already connected to is used and
    left running (tests), one started or joined here is shut down on exit.

    Args:
        address: Ray cluster address; None: a local Ray on 127.0.0.1.
        workers: Points at once; None: the machine's CPUs (local) or the cluster's.
        stop: The caller's Ctrl-C event: a running batch stops its points and raises
            KeyboardInterrupt.
    """

    def __init__(self, address: str | None = None, workers: int | None = None,
                 stop: StopEvent | None = None) -> None:
        """Remember the settings; Ray starts on ``__enter__``."""
        self._address = address
        self._workers = workers
        self._stop = stop
        self._ray: Any = None
        self._owned = False
        self._flag: Any = None
        self._task: Any = None
        self.capacity = 1

    def __enter__(self) -> PointBatches:
        """Start or join Ray (raises ``SweepEngineError``) and the stop flag."""
        self._owned = 'ray' not in sys.modules or not _import_ray().is_initialized()
        if self._owned:
            self._ray = (join_ray(self._address) if self._address
                         else start_local_ray(self._workers or os.cpu_count() or 1))
        else:
            self._ray = _import_ray()
        cpus = max(int(self._ray.cluster_resources().get('CPU', 1)), 1)
        self.capacity = min(self._workers or cpus, len(DOMAIN_IDS))
        self._task = self._ray.remote(num_cpus=1, max_retries=0)(point_task)
        self._flag = start_stop_flag(self._ray, self._stop)
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        """Stop the flag and shut a Ray started here down."""
        if self._flag is not None:
            self._ray.kill(self._flag)
        if self._owned:
            self._ray.shutdown()

    def run(self, requests: Sequence[Mapping[str, Any]], timeout_s: float) -> list[dict[str, Any]]:
        """Run every request (at most ``capacity`` at once); their outcomes in request order.

        A point that Ray itself failed (worker died) is a failed outcome with Ray's reason.

        Raises:
            KeyboardInterrupt: The stop event was set; the running points were stopped.
        """
        ray = self._ray
        outcomes: list[dict[str, Any] | None] = [None] * len(requests)
        pending = list(range(len(requests)))
        free = list(DOMAIN_IDS[:self.capacity])
        in_flight: dict[Any, tuple[int, int]] = {}
        try:
            while pending or in_flight:
                self._check_stop()
                while pending and free:
                    index, domain = pending.pop(0), free.pop(0)
                    ref = self._task.remote(dict(requests[index]), domain, timeout_s, self._flag)
                    in_flight[ref] = (index, domain)
                ready, _ = ray.wait(list(in_flight), num_returns=1, timeout=_WAIT_S)
                self._check_stop()
                for ref in ready:
                    index, domain = in_flight.pop(ref)
                    free.append(domain)
                    outcomes[index] = self._outcome(ref, requests[index])
        except KeyboardInterrupt:
            self._stop_in_flight(list(in_flight))
            raise
        return [outcome for outcome in outcomes if outcome is not None]

    def _check_stop(self) -> None:
        if self._stop is not None and self._stop.is_set():
            raise KeyboardInterrupt

    def _outcome(self, ref: Any, request: Mapping[str, Any]) -> dict[str, Any]:
        try:
            return dict(self._ray.get(ref))
        except self._ray.exceptions.RayError as exc:
            return {'point_id': request['point_id'], 'status': 'failed',
                    'reason': f'Ray: {ray_error_line(exc)}', 'metrics': {}}

    def _stop_in_flight(self, refs: list[Any]) -> None:
        """Raise the flag, give the points the grace time, then cancel what is left."""
        if self._flag is not None:
            self._flag.set.remote()
        deadline = time.monotonic() + CANCEL_GRACE_S
        while refs and time.monotonic() < deadline:
            _, refs = self._ray.wait(refs, num_returns=len(refs), timeout=0.2)
        for ref in refs:
            self._ray.cancel(ref, force=True)


__all__ = ['INTERRUPTED', 'PointBatches', 'point_request']
