"""Build our ROS 2 interface packages into a PyPI-wheel venv with Jazzy's rosidl generators.

Usage: ``<venv>/bin/python tools/build_interfaces.py [--force]``

The Jazzy wheels carry ament_cmake and the rosidl generators but no ``colcon`` workspace:
each package here (``src/uvms_msgs``, and ``interfaces/tf2_msgs`` since tf2_msgs has no
wheel) is configured with cmake against the venv as its prefix, built, and installed into
the venv, where rclpy finds the generated Python and C type support like any other wheel's.

A package is rebuilt only when one of its files changed since its last build (a SHA-256 of
the package's files is kept in ``<venv>/share/<pkg>/uvms_build.sha256``).

Two facts of the wheels this works around (measured, see shared/REAL_ROS.md):
- their exported CMake targets name the include directories of the interpreter that built
  them (``/opt/python/cp3XX-cp3XX/...``); they are rewritten to this interpreter's once;
- type-support discovery goes through the ament index: ``AMENT_PREFIX_PATH`` must hold
  the venv while cmake runs.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
#: Interface packages in build order (uvms_msgs depends on nothing of ours).
PACKAGES = (REPO / 'interfaces' / 'tf2_msgs', REPO / 'src' / 'uvms_msgs')
_WHEEL_PYTHON = re.compile(r'/opt/python/cp3\d+-cp3\d+/')
_STAMP = 'uvms_build.sha256'


class BuildError(RuntimeError):
    """An interface package failed to configure, build or install."""


def package_digest(package: Path) -> str:
    """SHA-256 over the relative paths and contents of a package's source files."""
    digest = hashlib.sha256()
    for path in sorted(p for p in package.rglob('*') if p.is_file()):
        digest.update(str(path.relative_to(package)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def fix_wheel_include_paths(prefix: Path) -> int:
    """Point the wheels' exported include directories at this interpreter; return files fixed."""
    import numpy  # the venv's numpy: the generated C extensions compile against it

    python_include = sysconfig.get_paths()['include']
    numpy_include = numpy.get_include()
    fixed = 0
    for path in (prefix / 'share').glob('*/cmake/*Export.cmake'):
        text = path.read_text()
        if '/opt/python/' not in text:
            continue
        text = re.sub(r'/opt/python/cp3\d+-cp3\d+/include/python3\.\d+', python_include, text)
        text = re.sub(r'/opt/python/cp3\d+-cp3\d+/lib/python3\.\d+/site-packages/numpy/'
                      r'_core/include', numpy_include, text)
        if _WHEEL_PYTHON.search(text):
            msg = f'{path}: an /opt/python path remains that this tool does not know how to map'
            raise BuildError(msg)
        path.write_text(text)
        fixed += 1
    return fixed


def build_package(package: Path, prefix: Path, jobs: int) -> None:
    """Configure, build and install one ament_cmake interface package into ``prefix``."""
    env = dict(os.environ)
    env['AMENT_PREFIX_PATH'] = os.pathsep.join(
        p for p in (str(prefix), os.environ.get('AMENT_PREFIX_PATH', '')) if p)
    env['CMAKE_PREFIX_PATH'] = str(prefix)
    with tempfile.TemporaryDirectory(prefix=f'build-{package.name}-') as build_dir:
        steps = [
            ['cmake', '-S', str(package), '-B', build_dir, f'-DCMAKE_PREFIX_PATH={prefix}',
             f'-DCMAKE_INSTALL_PREFIX={prefix}', f'-DPython3_EXECUTABLE={sys.executable}',
             '-DBUILD_TESTING=OFF', '-DCMAKE_BUILD_TYPE=Release'],
            ['cmake', '--build', build_dir, '--parallel', str(jobs)],
            ['cmake', '--install', build_dir],
        ]
        for step in steps:
            result = subprocess.run(step, env=env, capture_output=True, text=True, check=False)
            if result.returncode != 0:
                log = (result.stdout + result.stderr)[-4000:]
                msg = f'{package.name}: `{" ".join(step[:2])}` failed:\n{log}'
                raise BuildError(msg)


def main(argv: list[str] | None = None) -> int:
    """Build every interface package that changed since its last build."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--force', action='store_true', help='rebuild even if unchanged')
    parser.add_argument('--jobs', type=int, default=os.cpu_count() or 1)
    args = parser.parse_args(argv)
    prefix = Path(sys.prefix)
    if prefix == Path(sys.base_prefix):
        print('build_interfaces: run this with the Python of the project venv', file=sys.stderr)
        return 2
    for tool in ('cmake', 'cc'):
        if shutil.which(tool) is None:
            print(f'build_interfaces: `{tool}` not found; install cmake and a C compiler '
                  '(Debian: apt-get install cmake build-essential)', file=sys.stderr)
            return 2
    try:
        fix_wheel_include_paths(prefix)
        for package in PACKAGES:
            stamp = prefix / 'share' / package.name / _STAMP
            digest = package_digest(package)
            if not args.force and stamp.is_file() and stamp.read_text().strip() == digest:
                continue
            print(f'build_interfaces: building {package.name} with rosidl into {prefix}',
                  flush=True)
            build_package(package, prefix, args.jobs)
            stamp.write_text(digest + '\n')
    except BuildError as exc:
        print(f'build_interfaces: {exc}', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
