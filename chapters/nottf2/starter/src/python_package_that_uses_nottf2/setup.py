from setuptools import find_packages, setup

package_name = 'python_package_that_uses_nottf2'

setup(
    name=package_name,
    version='0.0.1',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    # TODO: declare nottf2 (its PyPI name) beside setuptools
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='Rotations composed with the nottf2 quaternion helpers and printed.',
    license='MIT',
    entry_points={
        'console_scripts': [
            # TODO: add the operations_showcase executable: 'NAME = PACKAGE.MODULE:FUNCTION'
        ],
    },
)
