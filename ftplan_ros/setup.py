"""ament_python package ftplan_ros: the ROS-free core, the CLI and the nodes."""
from glob import glob

from setuptools import find_packages, setup

package_name = 'ftplan_ros'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', [f'resource/{package_name}']),
        (f'share/{package_name}', ['package.xml']),
        # config/ lives at the repository root, beside both packages.
        (f'share/{package_name}/config/robots',
         glob('../config/robots/*.yaml') + glob('../config/robots/*.urdf')
         + glob('../config/robots/*.srdf')),
        (f'share/{package_name}/config/scenes', glob('../config/scenes/*.yaml')),
        (f'share/{package_name}/config/params', glob('../config/params/*.yaml')),
        (f'share/{package_name}/config/studies', glob('../config/studies/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ftplan developers',
    maintainer_email='ftplan@example.com',
    description='Failure-tolerant motion planning for redundant arms, with ROS 2 nodes.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'ftplan = ftplan_ros.cli:main',
            'ftplan-bringup = ftplan_ros.bringup:main',
            'bringup = ftplan_ros.bringup:main',
            'planner = ftplan_ros.nodes.planner:main',
            'injector = ftplan_ros.nodes.injector:main',
            'executor = ftplan_ros.nodes.executor:main',
            'sim = ftplan_ros.nodes.sim:main',
        ],
    },
)
