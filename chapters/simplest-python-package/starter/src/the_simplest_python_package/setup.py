from setuptools import find_packages, setup

package_name = 'the_simplest_python_package'

setup(
    name=package_name,
    version='0.0.0',
    # find_packages() installs every folder with an __init__.py (TODO 1 creates one)
    packages=find_packages(exclude=['test']),
    data_files=[
        # TODO 3: install the ament index marker: the file resource/<package_name>
        #         goes to 'share/ament_index/resource_index/packages'
        # TODO 4: install package.xml to 'share/' + package_name
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='TODO: Package description',
    license='TODO: License declaration',
    entry_points={
        'console_scripts': [
        ],
    },
)

# TODO 1: create the Python package: the_simplest_python_package/__init__.py (empty is fine)
# TODO 2: create the empty marker file resource/the_simplest_python_package
# TODO 5: create setup.cfg so that executables land in lib/the_simplest_python_package
