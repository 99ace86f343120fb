"""``uvms hardware check twin|FILE``: each device of a hardware file found and described.

Changes nothing on any device (``uvms_hardware.hardware_check`` says what it sends). Exit
status 0 when every device answered and nothing stops its bridge from activating, 1 when
something does (each problem on a line of its own), 2 for a bad command line or file.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from uvms_bringup.hardware_plan import HardwareFileError, hardware_file_path, load_hardware_plan
from uvms_bringup.launch_helpers import config_dir
from uvms_hardware.hardware_check import check_hardware

EXIT_OK, EXIT_PROBLEMS, EXIT_USAGE = 0, 1, 2


def main(argv: Sequence[str] | None = None) -> int:
    """Parse ``check FILE [--robot NAME]``, check each device, print what was found."""
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
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    try:
        plan = load_hardware_plan(hardware_file_path(args.hardware, config_dir()))
    except HardwareFileError as exc:
        print(f'uvms hardware: error: {exc}', file=sys.stderr)
        return EXIT_USAGE
    if plan.twins:
        print('uvms hardware: this file says twins: true; the twins run only inside '
              '`uvms launch --hardware`: checking whatever answers at its addresses')
    problems = check_hardware(args.robot, plan.bridges, lambda line: print(line, flush=True))
    print(f'uvms hardware: {problems} problem(s); nothing was changed on any device')
    return EXIT_OK if problems == 0 else EXIT_PROBLEMS


if __name__ == '__main__':
    sys.exit(main())
