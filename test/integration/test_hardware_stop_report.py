"""Ctrl-C on a hardware launch says what each bridge put back, and the last line sums it up.

Issue 52 item 4: Ctrl-C on ``uvms launch ... --hardware twin`` printed only ``interrupted;
every node stopped``: no line said the thrusters went neutral, the vehicle disarmed, the arm
back to its mode. Each bridge now says it on the console (``put back: ...``) and hands it to
the launcher (``uvms_hardware.stop_report``), whose closing line names every bridge's.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from uvms_hardware.stop_report import stop_summary

#: The console line of each bridge at its stop (the ArduSub twin runs the watchdog script:
#: script mode, no parameter changed).
BRIDGE_LINES = {
    'ardusub_bridge': 'put back: thrusters neutral (1500 us), disarmed, RC overrides released; '
                      'no parameter had been changed (script mode)',
    # The jaws too: bluerov2_alpha5's hardware.yaml names them (the bridge drives them).
    'alpha5_bridge': 'put back: every joint VELOCITY 0, then its mode from before (joint_1 '
                     'Standby, joint_2 Standby, joint_3 Standby, joint_4 Standby, jaw Standby), '
                     'each read back',
    'netft_bridge': 'put back: RDT stream stopped',
    'dvl_bridge': 'put back: nothing to put back: the DVL was only listened to',
}


def test_a_bridge_without_a_report_is_named() -> None:
    """A bridge that never got to its put-back (a kill) is said, not left out."""
    line = stop_summary({'ardusub_bridge': {'done': 'thrusters neutral', 'problems': ['x']}},
                        ['ardusub_bridge', 'alpha5_bridge'])
    assert line == ('put back: ardusub_bridge: thrusters neutral (1 PROBLEM: see its log); '
                    'alpha5_bridge: no put-back reported (never active, or killed: uvms '
                    'hardware check)')


def test_ctrl_c_on_a_twin_launch_says_what_each_bridge_put_back(tmp_path: Path) -> None:
    """SIGINT once the bridges drive: four put-back lines, and the closing line names them."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p),
               PYTHONUNBUFFERED='1')
    log = tmp_path / 'launch.log'
    with log.open('w') as out:
        launch = subprocess.Popen(
            [sys.executable, '-m', 'uvms_cli.cli', 'launch', 'idle_wall', '--robot',
             'bluerov2_alpha5', '--hardware', 'twin', '--real-time-factor', '0.5', '--duration',
             '0'], env=env, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 180.0
        while 'actuator commands to the plant' not in log.read_text():
            assert launch.poll() is None and time.monotonic() < deadline, log.read_text()[-3000:]
            time.sleep(0.2)
        time.sleep(2.0)
        launch.send_signal(signal.SIGINT)
        launch.wait(timeout=120.0)
    finally:
        if launch.poll() is None:
            launch.kill()
    text = log.read_text()
    assert launch.returncode == 130, text[-3000:]
    lines = text.splitlines()
    for bridge, said in BRIDGE_LINES.items():
        # Each bridge's own logger, in the robot process (the default) or a process of its own.
        assert any(f'[uvms.{bridge}]: ' in line and said in line for line in lines), \
            '\n'.join([bridge, *(line for line in lines if bridge in line)])
    last = lines[-1]
    assert last.startswith('uvms launch: interrupted; every node stopped; put back: '
                           'ardusub_bridge: thrusters neutral (1500 us), disarmed'), last
    for bridge in BRIDGE_LINES:
        assert f'{bridge}: ' in last, last
    assert 'no put-back reported' not in last and 'PROBLEM' not in last, last
