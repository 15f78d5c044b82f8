from setuptools import find_packages, setup

package_name = 'python_package_that_uses_the_services'

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
    description='A server and a client of the tutorial\'s WhatIsThePoint service.',
    license='MIT',
    entry_points={
        'console_scripts': [
            # TODO 2: register both executables, what_is_the_point_service_server_node and
            #         what_is_the_point_service_client_node: 'NAME = PACKAGE.MODULE:FUNCTION'
        ],
    },
)
