"""ament_python build of uvms_cli."""

from setuptools import find_packages, setup

package_name = 'uvms_cli'

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
        'The uvms command: run, launch, replay, plot, report, sweep and doctor, each handed '
        'to the package that does the job.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'uvms = uvms_cli.cli:main',
        ],
    },
)
