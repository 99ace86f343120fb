"""The pilot session figure: where the vehicle went, who owned the robot, the contact force.

``pilot_session.png`` of ``uvms plot``, for a recording in which the pilot drove (the
controller's ``/uvms/controller/mode`` was ``pilot`` at some point): the vehicle's position
and heading change from the start, the end effector's depth change and the contact force,
each panel shaded by the mode (pilot, task, hold) as the controller published it.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from uvms_recording.errors import RecordingError
from uvms_recording.mcap_reader import open_recording
from uvms_recording.typestore import uvms_typestore

from uvms_analysis.figure_style import FIGSIZE_TALL, _figure
from uvms_analysis.series import Run

MODE_TOPIC = '/uvms/controller/mode'
PILOT_SESSION_FIGURE = 'pilot_session.png'
#: Shading of each mode.
MODE_COLORS = {'pilot': 'tab:blue', 'task': 'tab:orange', 'hold': 'tab:gray'}


def mode_changes(path: Path, time_origin_ns: int) -> list[tuple[float, str]]:
    """(t in s from the run's origin, mode) at each change, from the recording's log times.

    The mode message has no header: its log time is the recorder's clock (the graph's).
    """
    try:
        recording = open_recording(path)
        typestore = uvms_typestore()
        changes = [((m.log_time_ns - time_origin_ns) * 1e-9,
                    str(typestore.deserialize_cdr(m.data, m.type_name).data))
                   for m in recording.messages([MODE_TOPIC])]
    except RecordingError:
        return []
    return sorted(changes)


def figure_pilot_session(run: Run) -> Figure | None:
    """Vehicle position and heading, end-effector depth and contact force, shaded by mode.

    None when the recording has no pilot mode or no odometry (not a pilot session).
    """
    if run.path is None or run.odometry is None or run.odometry.t.size == 0:
        return None
    modes = mode_changes(run.path, run.time_origin_ns)
    if not any(mode == 'pilot' for _, mode in modes):
        return None
    odom = run.odometry
    fig = _figure(FIGSIZE_TALL)
    ax_p, ax_h, ax_z, ax_f = fig.subplots(4, 1, sharex=True)
    end_s = float(odom.t[-1])
    for k, (start, mode) in enumerate(modes):
        stop = modes[k + 1][0] if k + 1 < len(modes) else end_s
        for ax in (ax_p, ax_h, ax_z, ax_f):
            ax.axvspan(start, stop, color=MODE_COLORS.get(mode, 'white'), alpha=0.15,
                       label=mode if ax is ax_p and mode not in
                       {m for _, m in modes[:k]} else None)
    moved = odom.position - odom.position[0]
    for k, axis in enumerate('xyz'):
        ax_p.plot(odom.t, moved[:, k], label=f'{axis} - {axis}$_0$')
    yaw_deg = np.degrees(np.unwrap(odom.rpy[:, 2]) - odom.rpy[0, 2])
    ax_h.plot(odom.t, yaw_deg, color='tab:purple',
              label=f'yaw ψ - ψ$_0$ ({math.degrees(odom.rpy[0, 2]):+.1f}° at start)')
    if run.ee_pose is not None and run.ee_pose.t.size:
        z_cm = (run.ee_pose.position[:, 2] - run.ee_pose.position[0, 2]) * 100.0
        ax_z.plot(run.ee_pose.t, z_cm, color='tab:green', label='end effector z - z$_0$ (down)')
    if run.contact is not None and run.contact.t.size:
        force = np.linalg.norm(run.contact.force, axis=1)
        ax_f.plot(run.contact.t, force, color='tab:red', label='|contact force| (ground truth)')
    ax_p.set_ylabel('vehicle, map_ned (m)')
    ax_h.set_ylabel('heading change (deg)')
    ax_z.set_ylabel('end effector (cm)')
    ax_f.set_ylabel('force (N)')
    ax_f.set_xlabel('time t (s)')
    ax_p.set_title(f'Pilot session: {run.name} (shading: the controller/mode owner)')
    for ax in (ax_p, ax_h, ax_z, ax_f):
        ax.grid(True, alpha=0.4)
        ax.legend(loc='best', fontsize='small')
    return fig
