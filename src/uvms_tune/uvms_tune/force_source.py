"""Which force a run's figures are of: the simulator's ground truth or the controller's estimate.

``uvms report``'s metrics (``compute_metrics``, force source 'auto') take the force figures
from the simulator's ground-truth contact force when the recording holds it, else from the
controller's own estimate F_e, and say which in ``force_source``. The sweep's point runner
returns only the numeric metrics, so the tune reads the answer from the run's recording: the
figures are the ground truth's exactly when the recording holds a message on its topic.
"""

from __future__ import annotations

import io
from collections.abc import Mapping
from typing import Any

from uvms_analysis.series import TOPIC_CONTACT

from uvms_tune.objective import GROUND_TRUTH

#: ``force_source`` of figures from the controller's measured force F_e.
CONTROLLER_ESTIMATE = 'controller'


def recorded_force_source(mcap: bytes) -> str | None:
    """'contact' when the MCAP holds the ground-truth contact force, else 'controller'.

    None: the bytes are not a readable MCAP (nothing can be said).
    """
    from mcap.exceptions import McapError
    from mcap.reader import make_reader

    try:
        reader = make_reader(io.BytesIO(mcap))
        message = next(iter(reader.iter_messages(topics=[TOPIC_CONTACT])), None)
    except (McapError, ValueError, EOFError):
        return None
    return GROUND_TRUTH if message is not None else CONTROLLER_ESTIMATE


def with_force_source(outcome: Mapping[str, Any]) -> dict[str, Any]:
    """The outcome with ``metrics['force_source']`` set from its recording where not given.

    A runner that returns ``force_source`` keeps it; otherwise the recording decides, and an
    outcome without one leaves it unset (the objective then fails the run saying so).
    """
    result = dict(outcome)
    metrics = dict(result.get('metrics') or {})
    if metrics.get('force_source') is None and result.get('mcap'):
        source = recorded_force_source(result['mcap'])
        if source is not None:
            metrics['force_source'] = source
    result['metrics'] = metrics
    return result
