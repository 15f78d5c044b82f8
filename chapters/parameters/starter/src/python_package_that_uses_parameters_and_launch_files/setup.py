import os
from glob import glob

from setuptools import find_packages, setup

package_name = 'python_package_that_uses_parameters_and_launch_files'

setup(
    name=package_name,
    version='0.0.1',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # TODO (launch-files lesson): install the files of launch/ into share/<package_name>/launch,
        # e.g. with os.path.join(...) and glob(...)
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='A configurable AmazingQuote publisher and the launch file that configures it.',
    license='MIT',
    entry_points={
        'console_scripts': [
            # TODO (parameters lesson): register amazing_quote_configurable_publisher_node
        ],
    },
)
