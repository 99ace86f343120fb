"""The install commands of the packages with Numba kernels, shared by their setup.py files.

``uvms_model``, ``uvms_control`` and ``uvms_thrusters`` cache compiled kernels beside their
modules. Numba keys the cache by the module's path, so the installed copy needs its own:
``install`` (``colcon build``) and ``develop`` (``colcon build --symlink-install``) compile
them once the files are in place, by running ``python -m PACKAGE.kernel_cache`` there. A
failure only warns; the kernels then compile at the first start of a node.

setup.py runs before any package of the repository is importable, so each one loads this
file by its path::

    KERNEL_SETUP = Path(__file__).resolve().parents[2] / 'tools' / 'kernel_setup.py'
    cmdclass = runpy.run_path(str(KERNEL_SETUP))['kernel_commands'](package_name, ROOT)

Standard library and setuptools only.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from setuptools import Command
from setuptools.command.develop import develop
from setuptools.command.install import install


def compile_kernels(command: Command, package_name: str, package_root: str) -> None:
    """Fill the Numba cache of ``package_name`` as imported from ``package_root``.

    Args:
        command: The setuptools command, which warns on failure.
        package_name: The package whose ``kernel_cache`` module compiles its kernels.
        package_root: The directory the package is imported from (installed or sources).
    """
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join([package_root, env.get('PYTHONPATH', '')])
    # In package_root, so that -m imports the package from there, not from the sources.
    result = subprocess.run([sys.executable, '-m', f'{package_name}.kernel_cache'], env=env,
                            cwd=package_root, check=False)
    if result.returncode != 0:
        command.warn(f'{package_name}: the Numba kernels were not compiled (status '
                     f'{result.returncode}); they compile at the first start of a node')


def kernel_commands(package_name: str, source_root: Path) -> dict[str, type[Command]]:
    """``cmdclass`` of a package's setup(): install and develop, then its kernels compiled.

    Args:
        package_name: The package (``uvms_control``).
        source_root: The directory of its setup.py (what ``develop`` links).
    """

    class InstallWithKernels(install):
        """``setup.py install`` (``colcon build``), then the installed kernels compiled."""

        def run(self) -> None:
            """Install, then compile the kernels of the installed modules."""
            super().run()
            compile_kernels(self, package_name, os.path.abspath(self.install_lib))

    class DevelopWithKernels(develop):
        """``setup.py develop`` (``colcon build --symlink-install``), then the kernels."""

        def run(self) -> None:
            """Link the sources, then compile their kernels (not when uninstalling)."""
            super().run()
            if not self.uninstall:
                compile_kernels(self, package_name, str(source_root.resolve()))

    return {'install': InstallWithKernels, 'develop': DevelopWithKernels}
