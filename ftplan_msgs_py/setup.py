"""ament_python package ftplan_msgs_py: numpy <-> standard ROS message conversions."""
from setuptools import find_packages, setup

package_name = 'ftplan_msgs_py'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', [f'resource/{package_name}']),
        (f'share/{package_name}', ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ftplan developers',
    maintainer_email='ftplan@example.com',
    description='numpy <-> standard ROS 2 message conversions for ftplan.',
    license='Apache-2.0',
)
