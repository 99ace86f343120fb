"""ament_python build of uvms_description: the URDF, its hydrodynamics and mesh go to share/."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'uvms_description'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        *[
            ('share/' + package_name + '/' + folder, glob(folder + '/*.*'))
            for folder in sorted(glob('robots/*'))
        ],
        ('share/' + package_name + '/meshes', glob('meshes/*.stl')),
        ('share/' + package_name + '/foxglove', glob('foxglove/*.json')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='UVMS developers',
    maintainer_email='dev@uvms.local',
    description=(
        'Robot descriptions of UVMS, one folder per robot: URDF (or xacro), hydrodynamics, '
        'thrusters, wrist sensor and controller gains; hull mesh, Foxglove layout.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
        ],
    },
)
