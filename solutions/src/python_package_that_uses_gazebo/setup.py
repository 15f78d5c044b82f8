from glob import glob

from setuptools import find_packages, setup

package_name = 'python_package_that_uses_gazebo'

setup(
    name=package_name,
    version='0.0.1',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/launch', glob('launch/*_launch.py')),
        ('share/' + package_name + '/config_bridge', glob('config_bridge/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='Three nodes that move a box in a Gazebo world.',
    license='MIT',
    entry_points={
        'console_scripts': [
            'send_poses_to_gazebo_node = python_package_that_uses_gazebo.send_poses_to_gazebo_node:main',
            'send_wrenches_to_gazebo_node = python_package_that_uses_gazebo.send_wrenches_to_gazebo_node:main',
            'control_shape_thrust_node = python_package_that_uses_gazebo.control_shape_thrust_node:main',
        ],
    },
)
