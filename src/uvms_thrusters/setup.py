"""ament_python build of uvms_thrusters."""

import os
import subprocess
import sys

from setuptools import find_packages, setup
from setuptools.command.develop import develop
from setuptools.command.install import install

package_name = 'uvms_thrusters'


def compile_kernels(command, package_root):
    """Fill the Numba cache of the package at ``package_root`` (its kernels, for its path).

    Numba caches beside each module, keyed by its path: the installed copy needs its own
    cache, or a node compiles for seconds at its first start. A failure only warns; the
    kernels then compile at the first start.
    """
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([package_root, env.get('PYTHONPATH', '')])
    # In package_root, so that -m imports the package from there, not from the sources.
    result = subprocess.run([sys.executable, '-m', f'{package_name}.kernel_cache'], env=env,
                            cwd=package_root, check=False)
    if result.returncode != 0:
        command.warn(f'{package_name}: the Numba kernels were not compiled (status '
                     f'{result.returncode}); they compile at the first start of a node')


class InstallWithKernels(install):
    """``setup.py install`` (``colcon build``), then the installed kernels compiled."""

    def run(self):
        """Install, then compile the kernels of the installed modules."""
        super().run()
        compile_kernels(self, os.path.abspath(self.install_lib))


class DevelopWithKernels(develop):
    """``setup.py develop`` (``colcon build --symlink-install``), then the kernels compiled."""

    def run(self):
        """Link the sources, then compile their kernels (not when uninstalling)."""
        super().run()
        if not self.uninstall:
            compile_kernels(self, os.path.abspath(os.path.dirname(__file__)))


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='UVMS developers',
    maintainer_email='dev@uvms.local',
    description=(
        'Thruster allocation (eq. 10), Healey thruster dynamics (eq. 11-15) and their kernels, '
        'fault injection and detection, and the thruster_allocator node.'
    ),
    license='Apache-2.0',
    cmdclass={'install': InstallWithKernels, 'develop': DevelopWithKernels},
    entry_points={
        'console_scripts': [
            'thruster_allocator = uvms_thrusters.entry_points:thruster_allocator',
        ],
    },
)
