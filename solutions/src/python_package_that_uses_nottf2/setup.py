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
    # nottf2 is a PyPI package (no rosdep key): it is declared here, where pip reads it
    install_requires=['setuptools', 'nottf2'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='Rotations composed with the nottf2 quaternion helpers and printed.',
    license='MIT',
    entry_points={
        'console_scripts': [
            'operations_showcase = python_package_that_uses_nottf2.operations_showcase:main',
        ],
    },
)
