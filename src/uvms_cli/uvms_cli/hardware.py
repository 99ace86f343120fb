"""``uvms hardware check twin|FILE`` and ``uvms hardware restore ardusub``.

``check``: each device of a hardware file found and described; changes nothing on any device
(``uvms_hardware.hardware_check`` says what it sends). First the bridges running on the graph
(their ``/diagnostics``, ``hardware_check_graph``), then device by device: a line as each
starts with the longest it may take, what it found, and its problems and time. Exit status 0
when every device answered and nothing stops its bridge from activating (nor shows a running
bridge stopped), 1 when something does (each problem on a line of its own), 2 for a bad
command line or file.

``reset-trip``: the controller reset (deactivate, activate: its hold taken where the arm is),
then 0.5 s later the alpha5_bridge's overspeed trip cleared (its ``~/reset_trip`` service:
refused while a joint still moves over the trip speed), so that the first command the bridge
takes again is the controller's holding torque. Exit status 0 when cleared (or nothing was
tripped), 1 when refused or a node did not answer.

``restore ardusub``: what an ardusub_bridge that did not end cleanly (a kill, a crash) left
changed on the vehicle put back, as the bridge's own stop does (``uvms_hardware.
ardusub_restore``): neutral, disarm, overrides released, then the thruster outputs'
functions from the journal (else the firmware defaults) set and read back; the journal is
removed once all were. Exit status 0 when done or nothing was left, 1 when something could
not be restored, 2 for a bad command line or file.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Sequence
from dataclasses import replace

from uvms_bringup.hardware_plan import (
    HardwareFileError,
    HardwarePlan,
    hardware_file_path,
    load_hardware_plan,
)
from uvms_bringup.launch_helpers import config_dir
from uvms_hardware.ardusub_restore import restore_ardusub
from uvms_hardware.errors import HardwareError
from uvms_hardware.hardware_check import BridgeStatus, CheckBounds, check_hardware

EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE = 0, 1, 2
#: After the controller's reset, before the trip is cleared: it steps and holds first (s).
CONTROLLER_SETTLE_S = 0.5
#: The ardusub_bridge's default ``mavlink_url``.
DEFAULT_MAVLINK_URL = 'udpout:127.0.0.1:14550'


def launch_plan(name_or_path: str, twins_apart: bool) -> HardwarePlan:
    """``uvms launch --hardware twin|FILE [--twins-apart]``: the file read and checked.

    The stand's settings (``twins:`` as a mapping) are checked by the twins' own names and
    types (``uvms_twins.twin_stand.checked_settings``): a misspelt one would otherwise reach
    the twins as a ROS parameter they do not declare, and be ignored.

    Raises:
        ValueError: The file, or a setting of the stand, is wrong (named).
    """
    plan = load_hardware_plan(hardware_file_path(name_or_path, config_dir()))
    plan = replace(plan, twins_in_simulator=not twins_apart)
    if plan.twin_settings:
        from uvms_twins.twin_stand import checked_settings

        plan = replace(plan, twin_settings=checked_settings(plan.twin_settings, str(plan.path)))
    return plan


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``check FILE`` or ``restore ardusub``; run it; the exit status."""
    parser = argparse.ArgumentParser(
        prog='uvms hardware', description='Find the devices a hardware file names and say what '
        'they are and what would stop their bridges; change nothing.')
    sub = parser.add_subparsers(dest='action', required=True)
    check = sub.add_parser('check', help='connect to each device, print what it is')
    check.add_argument('hardware', metavar='twin|FILE',
                       help='config/hardware/NAME.yaml by name, or a path')
    check.add_argument('--robot', default='bluerov2_alpha5',
                       help='robot folder whose hardware.yaml describes the devices '
                            '(default: bluerov2_alpha5)')
    check.add_argument('--wait', type=float, default=CheckBounds.wait_s, metavar='S',
                       help="seconds for each device's first answer (default "
                            f"{CheckBounds.wait_s:g}; not the file's start-up waits)")
    check.add_argument('--graph-wait', type=float, default=3.0, metavar='S',
                       help='seconds to listen on /diagnostics for running bridges (default 3; '
                            '0: do not look at the graph)')
    reset = sub.add_parser('reset-trip', help="clear the alpha5_bridge's overspeed trip once "
                           'the arm is still (docs/hardware.md, "Recovering the arm")')
    reset.add_argument('--namespace', default='/uvms', metavar='NS',
                       help="the graph's namespace (default /uvms)")
    reset.add_argument('--timeout', type=float, default=10.0, metavar='S',
                       help='seconds to wait for the service and its answer (default 10)')
    reset.add_argument('--no-controller-reset', action='store_true',
                       help='clear the trip only (by default the controller is reset first, '
                            f'{CONTROLLER_SETTLE_S:g} s before: its hold where the arm is)')
    restore = sub.add_parser('restore', help='put back what a bridge that did not end cleanly '
                             'left changed on its device')
    restore.add_argument('device', choices=['ardusub'])
    where = restore.add_mutually_exclusive_group()
    where.add_argument('--url', help='MAVLink URL of the vehicle, as the bridge uses it '
                       f'(default: {DEFAULT_MAVLINK_URL})')
    where.add_argument('--hardware', metavar='twin|FILE',
                       help="take the URL and GCS id from this hardware file's ardusub_bridge")
    restore.add_argument('--robot', default='bluerov2_alpha5',
                         help='robot folder whose hardware.yaml names the thruster outputs')
    restore.add_argument('--journal-dir', default='',
                         help='folder of the journal (default: UVMS_JOURNAL_DIR, else '
                              '$XDG_STATE_HOME/uvms/journal, else ~/.local/state/uvms/journal)')
    restore.add_argument('--gcs-system-id', type=int, default=None,
                         help='our MAVLink system id (default: from the hardware file, else 255)')
    restore.add_argument('--heartbeat-timeout', type=float, default=10.0,
                         help='seconds to wait for the vehicle (default 10)')
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    if args.action == 'restore':
        return _restore(args)
    if args.action == 'reset-trip':
        return _reset_trip(args.namespace, args.timeout, not args.no_controller_reset)
    try:
        plan = load_hardware_plan(hardware_file_path(args.hardware, config_dir()))
    except HardwareFileError as exc:
        print(f'uvms hardware: error: {exc}', file=sys.stderr)
        return EXIT_USAGE
    try:
        bounds = CheckBounds(wait_s=args.wait)
    except ValueError as exc:
        print(f'uvms hardware: error: --wait: {exc}', file=sys.stderr)
        return EXIT_USAGE
    start_s = time.monotonic()
    if plan.twins:
        print('uvms hardware: this file says twins: true; the twins run only inside '
              '`uvms launch --hardware`: checking whatever answers at its addresses (a '
              "running twin launch's)", flush=True)
    graph = _running_bridges(list(plan.bridges), args.graph_wait)
    problems = check_hardware(args.robot, plan.bridges, lambda line: print(line, flush=True),
                              bounds, graph)
    print(f'uvms hardware: {time.monotonic() - start_s:.1f} s: {problems} problem(s); '
          'nothing was changed on any device')
    return EXIT_OK if problems == 0 else EXIT_PROBLEMS


def _running_bridges(names: list[str], listen_s: float) -> dict[str, BridgeStatus]:
    """The bridges of ``names`` on the graph, said on a line (none when ``listen_s`` is 0)."""
    if listen_s <= 0.0:
        return {}
    print(f'graph: listening on /diagnostics for running bridges (at most {listen_s:g} s)',
          flush=True)
    from uvms_hardware.hardware_check_graph import running_bridges

    start_s = time.monotonic()
    graph = running_bridges(names, listen_s)
    took = f'{time.monotonic() - start_s:.1f} s with starting ROS'
    print('graph: ' + (', '.join(f'{s.name} {s.state}' for s in graph.values()) + f' ({took})'
                       if graph else f'no bridge running ({took})'), flush=True)
    return graph



def _reset_trip(namespace: str, timeout_s: float, controller: bool) -> int:
    """``reset-trip``: the controller reset, then the bridge's ``~/reset_trip``; printed.

    Back to back in one process: reset separately, a command line at a time beside the
    SCHED_FIFO graph (4-70 s apart on a loaded machine), the controller's hold breached its
    tracking limit while the bridge still refused its arm torques, and the arm tripped again.
    """
    import rclpy
    from rclpy.node import Node
    from std_srvs.srv import Trigger
    from uvms_common.ros_environment import ros_environment_defaults

    from uvms_cli.lifecycle import LifecycleCallError, LifecycleClient
    from uvms_cli.service_call import call_service

    ros_environment_defaults()
    base = namespace.rstrip('/')
    target = f'{base}/alpha5_bridge/reset_trip'
    rclpy.init(args=[])
    node = Node('uvms_hardware_reset_trip')
    try:
        client = node.create_client(Trigger, target)
        if not client.wait_for_service(timeout_sec=timeout_s):
            raise LifecycleCallError(f'{target} did not appear within {timeout_s:g} s (is an '
                                     'alpha5_bridge active?)')
        if controller:
            lifecycle = LifecycleClient(node, f'{base}/controller', timeout_s)
            states = [lifecycle.state()]
            steps = ('deactivate', 'activate') if states[0] == 'active' else ('activate',)
            states += [lifecycle.transition(step) for step in steps]
            print(f'{base}/controller: {" -> ".join(states)} (its hold taken where the arm is)',
                  flush=True)
            end_s = time.monotonic() + CONTROLLER_SETTLE_S
            while time.monotonic() < end_s:  # the controller steps and holds first
                rclpy.spin_once(node, timeout_sec=0.05)
        answer = call_service(node, client, Trigger.Request(), timeout_s, LifecycleCallError,
                              ' (is an alpha5_bridge active?)')
    except LifecycleCallError as exc:
        print(f'uvms hardware: error: {exc}', file=sys.stderr)
        return EXIT_PROBLEMS
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    print(f'{target}: {answer.message}')
    return EXIT_OK if answer.success else EXIT_PROBLEMS


def _restore(args: argparse.Namespace) -> int:
    """``restore ardusub``: the vehicle found, its leftovers put back."""
    url, gcs_id = args.url or DEFAULT_MAVLINK_URL, 255
    if args.hardware:
        try:
            plan = load_hardware_plan(hardware_file_path(args.hardware, config_dir()))
        except HardwareFileError as exc:
            print(f'uvms hardware: error: {exc}', file=sys.stderr)
            return EXIT_USAGE
        values = plan.bridges.get('ardusub_bridge', {})
        url = str(values.get('mavlink_url', url))
        gcs_id = int(values.get('gcs_system_id', gcs_id))
    if args.gcs_system_id is not None:
        gcs_id = args.gcs_system_id
    try:
        problems = restore_ardusub(args.robot, url, lambda line: print(line, flush=True),
                                   gcs_id, args.journal_dir, args.heartbeat_timeout)
    except (HardwareError, ValueError, OSError) as exc:
        print(f'ardusub: PROBLEM: {exc}', flush=True)
        problems = 1
    print(f'uvms hardware restore: {problems} problem(s)')
    return EXIT_OK if problems == 0 else EXIT_PROBLEMS


if __name__ == '__main__':
    sys.exit(main())
