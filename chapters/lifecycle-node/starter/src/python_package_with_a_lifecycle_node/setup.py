from setuptools import find_packages, setup

package_name = 'python_package_with_a_lifecycle_node'

setup(
    name=package_name,
    version='0.0.1',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='A managed (lifecycle) node whose heartbeat publisher only publishes while the node is active.',
    license='MIT',
    entry_points={
        'console_scripts': [
            'lifecycle_heartbeat_node = python_package_with_a_lifecycle_node.lifecycle_heartbeat_node:main',
        ],
    },
)
