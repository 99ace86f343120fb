"""``uvms pilot``: drive the vehicle and the arm from the terminal (and a gamepad).

Joins the graph of the ROS domain in the environment (namespace /uvms), publishes the pilot
topics (``pilot/vehicle_twist``, ``pilot/ee_twist``, ``pilot/jaw``) at ``--rate`` while a key
is held or a stick is off center, one zero when input stops (the controller's deadman then
holds the pose), and shows depth, heading, velocity, force, the controller's mode and the
last /diagnostics line. ``h`` asks the controller to hold, ``t`` starts ``--task FILE``, ``c``
cancels it. ``--gamepad`` adds a Linux input device read through ``--mapping`` (and
sensor_msgs/Joy on /joy); ``--no-tui`` runs the gamepad alone (one line per event of note).
docs/piloting.md.

Exit status: 0 done; 2 bad usage, a bad mapping file or no gamepad; 130 interrupted.
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

EXIT_OK = 0
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130
#: Wall time to look for a /clock publisher at start (s): with one, stamps are sim time.
CLOCK_DISCOVERY_S = 1.5
#: Wall time to wait for the controller's answer naming its robot (s).
ROBOT_QUERY_S = 2.0
EE_FRAMES = {'body': 'base_link_frd', 'map': 'map_ned'}
#: The robot of run and launch when none is named (uvms_description.DEFAULT_ROBOT).
DEFAULT_ROBOT = 'paper_uvms'


def _positive(text: str) -> float:
    value = float(text)
    if not value > 0.0:
        raise argparse.ArgumentTypeError(f'expected a number > 0, got {text}')
    return value


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``pilot`` to ``uvms``'s subparsers."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        'pilot', help='drive the vehicle and the arm from the terminal or a gamepad',
        description='Drive the vehicle and the arm of a running graph from the terminal '
                    '(and a gamepad) on the pilot topics; hold, start and cancel a task; the '
                    'live state on screen. docs/piloting.md')
    parser.add_argument('--robot', metavar='NAME|PATH',
                        help="whose pilot limits the gears scale (the robot folder's "
                             "controller.yaml pilot.*); default: the running controller's "
                             f'robot_name, else {DEFAULT_ROBOT}')
    parser.add_argument('--task', type=Path, metavar='FILE.yaml',
                        help='task or mission file that the t key (or start button) sends')
    parser.add_argument('--ee-frame', choices=sorted(EE_FRAMES), default='body',
                        help='frame of the arm keys: the vehicle body (base_link_frd, '
                             'default) or the map (map_ned)')
    parser.add_argument('--gamepad', nargs='?', const='auto', metavar='DEVICE',
                        help='read a gamepad too: /dev/input/eventN, or the first one found')
    parser.add_argument('--mapping', type=Path, metavar='FILE.yaml',
                        help='gamepad mapping file (default: config/pilot/xbox.yaml)')
    parser.add_argument('--no-tui', action='store_true',
                        help='no terminal UI: the gamepad alone, notes on stdout')
    parser.add_argument('--rate', type=_positive, default=20.0, metavar='HZ',
                        help='publish rate while input moves the robot (default 20 Hz)')
    parser.add_argument('--namespace', default='/uvms', metavar='NS',
                        help="the graph's namespace (default /uvms)")
    parser.add_argument('--use-sim-time', choices=('auto', 'true', 'false'), default='auto',
                        help='stamp with /clock time (auto: when /clock has a publisher)')
    parser.add_argument('--first-hold', type=_positive, default=None, metavar='S',
                        help='a key counts as held this long after its first press '
                             '(default 0.45 s: bridges the keyboard auto-repeat delay)')
    parser.add_argument('--repeat-hold', type=_positive, default=None, metavar='S',
                        help='and this long after each auto-repeat (default 0.25 s)')
    return parser


def _error(message: str) -> None:
    print(f'uvms pilot: error: {message}', file=sys.stderr)


def default_mapping() -> Path:
    """The shipped gamepad mapping (config/pilot/xbox.yaml)."""
    from uvms_bringup.launch_helpers import config_dir

    return config_dir() / 'pilot' / 'xbox.yaml'


def run(args: argparse.Namespace) -> int:
    """Run ``uvms pilot`` on parsed arguments; the exit status."""
    from uvms_pilot.errors import PilotError
    from uvms_pilot.gamepad_state import GamepadState
    from uvms_pilot.keys import FIRST_HOLD_S, REPEAT_HOLD_S, KeyboardDemand

    if args.no_tui and args.gamepad is None:
        _error('--no-tui needs --gamepad (the keys need the terminal UI)')
        return EXIT_USAGE
    if args.task is not None and not args.task.is_file():
        _error(f'--task: no file {args.task}')
        return EXIT_USAGE
    gamepad = device = None
    if args.gamepad is not None:
        from uvms_pilot.gamepad import find_gamepad, open_gamepad
        from uvms_pilot.gamepad_mapping import load_mapping

        try:
            mapping = load_mapping(args.mapping or default_mapping())
            path = find_gamepad() if args.gamepad == 'auto' else args.gamepad
            device, ranges = open_gamepad(path)
            gamepad = GamepadState(mapping, ranges)
        except (PilotError, ValueError) as exc:
            if device is not None:
                device.close()
            _error(str(exc))
            return EXIT_USAGE
    keys = None if args.no_tui else KeyboardDemand(args.first_hold or FIRST_HOLD_S,
                                                   args.repeat_hold or REPEAT_HOLD_S)
    return _run_in_graph(args, keys, gamepad, device)


def _run_in_graph(args: argparse.Namespace, keys: Any, gamepad: Any, device: Any) -> int:
    """Join the graph, run the session until the pilot leaves, leave the robot still."""
    import rclpy
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from rclpy.signals import SignalHandlerOptions
    from uvms_common.node_main import make_executor
    from uvms_common.ros_environment import ros_environment_defaults

    from uvms_pilot.command import Demand, command
    from uvms_pilot.gamepad import GamepadReader
    from uvms_pilot.limits import pilot_limits
    from uvms_pilot.link import PilotLink
    from uvms_pilot.session import PilotSession

    ros_environment_defaults()
    rclpy.init(args=[], signal_handler_options=SignalHandlerOptions.NO)
    node = Node(f'uvms_pilot_{os.getpid()}', namespace=args.namespace)
    executor = make_executor('single')
    executor.add_node(node)
    link = PilotLink(node, EE_FRAMES[args.ee_frame], joy=gamepad is not None,
                     task_file=args.task)
    # Before the executor spins in its thread: rclpy entities destroyed while another thread
    # waits on them break that thread's executor (the robot query's client).
    if args.use_sim_time == 'true' or (args.use_sim_time == 'auto' and _clock_published(node)):
        node.set_parameters([Parameter('use_sim_time', value=True)])
    robot = args.robot or _robot_of_graph(node, executor) or DEFAULT_ROBOT
    try:
        limits = pilot_limits(robot)
    except ValueError as exc:
        _error(f'robot {robot}: {exc}')
        link.destroy()
        node.destroy_node()
        rclpy.try_shutdown()
        return EXIT_USAGE
    stop = threading.Event()
    spinner = threading.Thread(target=_spin, args=(executor, stop), name='ros', daemon=True)
    spinner.start()
    session = PilotSession(link, limits, keys, gamepad)
    reader = None
    if device is not None:
        reader = GamepadReader(device, session.gamepad_event,
                               lambda why: (session.gamepad_lost(), link.note(why)))
        reader.start()
    title = (f'uvms pilot ({node.get_namespace()}, {robot}, arm in '
             f'{EE_FRAMES[args.ee_frame]})')
    try:
        if keys is not None:
            from uvms_pilot.tui import run_tui

            run_tui(session, lambda: link.live, args.rate, title)
        else:
            _run_headless(session, link, args.rate, title)
        return EXIT_OK
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    finally:
        # The parts still moving get their zero; the controller's deadman does the rest.
        session.keys = None
        session.gamepad = None
        link.publish(session.parts_to_stop(), command(Demand(), limits, 1.0))
        if reader is not None:
            reader.stop()
        stop.set()
        spinner.join(timeout=2.0)
        executor.shutdown(timeout_sec=1.0)
        link.destroy()
        node.destroy_node()
        rclpy.try_shutdown()


def _clock_published(node: Any) -> bool:
    """Whether /clock gets a publisher within CLOCK_DISCOVERY_S (the graph runs on sim time)."""
    deadline = time.monotonic() + CLOCK_DISCOVERY_S
    while time.monotonic() < deadline:
        if node.count_publishers('/clock') > 0:
            return True
        time.sleep(0.05)
    return False


def _spin(executor: Any, stop: threading.Event) -> None:
    """Spin in short turns until ``stop`` (executor.spin would race the shutdown)."""
    while not stop.is_set():
        executor.spin_once(timeout_sec=0.1)


def _robot_of_graph(node: Any, executor: Any) -> str | None:
    """The running controller's robot_name parameter, or None (no controller answered)."""
    from rcl_interfaces.srv import GetParameters

    client = node.create_client(GetParameters, 'controller/get_parameters')
    try:
        if not client.wait_for_service(timeout_sec=ROBOT_QUERY_S):
            return None
        future = client.call_async(GetParameters.Request(names=['robot_name']))
        executor.spin_until_future_complete(future, timeout_sec=ROBOT_QUERY_S)
        response = future.result() if future.done() else None
        if response is None or not response.values or not response.values[0].string_value:
            return None
        return str(response.values[0].string_value)
    finally:
        node.destroy_client(client)


def _run_headless(session: Any, link: Any, rate_hz: float, title: str) -> None:
    """The gamepad alone: tick at rate_hz, print each new note and the mode on stdout."""
    print(f'{title}: gamepad only, Ctrl-C to leave', flush=True)
    shown: tuple[Any, ...] = ()
    period_s = 1.0 / rate_hz
    while True:
        session.tick(time.monotonic())
        live = link.live
        now = (live.mode, live.note, live.task)
        if now != shown:
            shown = now
            print(f'mode {live.mode or "-"} | {live.task or "-"} | {live.note or ""}',
                  flush=True)
        time.sleep(period_s)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m uvms_pilot.cli``: the subcommand alone, as ``uvms pilot`` runs it."""
    parser = argparse.ArgumentParser(prog='uvms')
    add_parser(parser.add_subparsers(dest='command'))
    try:
        args = parser.parse_args(['pilot', *(sys.argv[1:] if argv is None else argv)])
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    return run(args)


if __name__ == '__main__':
    sys.exit(main())
