from setuptools import find_packages, setup

package_name = 'the_simplest_python_package'

setup(
    name=package_name,
    version='0.0.1',
    packages=find_packages(exclude=['test']),
    data_files=[
        # the empty marker file that puts the package in the ament index (ros2 pkg list)
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        # package.xml next to the package's other shared files (ros2 pkg xml reads it)
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='The smallest ament_python package: nothing in it but the packaging.',
    license='MIT',
    entry_points={
        'console_scripts': [
        ],
    },
)
