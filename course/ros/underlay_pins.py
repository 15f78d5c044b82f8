"""The pinned upstream sources of the ROS 2 underlay (what PyPI's Jazzy wheels lack).

One :class:`Pin` per upstream repository: its GitHub ``org/repo``, the commit
(a full hash: archives are pinned by commit, never by tarball checksum, see
shared/ros-src/SOURCES.md) and which of its packages are built. Every other
package of the archive gets a ``COLCON_IGNORE`` (shared/ROS_ENV.md: colcon trips
over in-tree packages the wheels already provide, and over test fixtures).

Changing anything here changes the underlay's cache key
(:func:`ros2course.ros.underlay.cache_key`), so the next ``ros2course env --build``
rebuilds; so does raising :data:`REPAIRS_VERSION` when a repair changes.
"""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class Pin:
    """One upstream repository at one commit.

    Attributes:
        org: GitHub organisation (``ros2``).
        repo: repository name (``rclcpp``).
        commit: 40-hex commit id.
        version: upstream version or branch at that commit, for ``doctor``.
        packages: the packages built from it (folder names of their ``package.xml``
            or, for a plain CMake project without one, ``"."``); ``None`` = all.
        first: built in a first colcon pass, before everything else (plain CMake
            projects that ROS packages find with ``find_package`` and that colcon
            cannot order: console_bridge, which console_bridge_vendor would
            otherwise git-clone; shared/ROS_ENV.md).
        patches: names of upstream patches applied after unpacking (see
            :data:`PATCHES`).
        group: colcon pass number (passes run in order; ``first`` means pass 0).
            Needed where packages declare no dependencies colcon can see
            (dqrobotics and sas, shared/ROS_ENV.md).
        into: ``"<repo>/<path>"``: a git submodule, unpacked into that folder of
            another pin instead of being a package of its own.
        mirror_dir: sub-folder of the mirror holding the archive (``"sas"``).
    """

    org: str
    repo: str
    commit: str
    version: str
    packages: tuple[str, ...] | None = None
    first: bool = False
    patches: tuple[str, ...] = ()
    group: int = 1
    into: str | None = None
    mirror_dir: str = ""

    @property
    def archive_name(self) -> str:
        """The mirror's file name: ``<org>--<repo>-<commit>.tar.gz`` (shared/ros-src/SOURCES.md)."""
        return f"{self.org}--{self.repo}-{self.commit}.tar.gz"

    @property
    def url(self) -> str:
        """GitHub's archive URL for this commit (unpacks to ``<repo>-<commit>/``)."""
        return f"https://github.com/{self.org}/{self.repo}/archive/{self.commit}.tar.gz"

    @property
    def colcon_pass(self) -> int:
        """The colcon pass this pin's packages are built in."""
        return 0 if self.first else self.group

    @property
    def top(self) -> str:
        """The archive's top folder."""
        return f"{self.repo}-{self.commit}"


@dataclasses.dataclass(frozen=True)
class Patch:
    """An upstream commit applied on top of a pin (``patch -p1`` in the pin's top folder).

    Attributes:
        name: the file name in the mirror folder.
        url: the same commit as a patch from GitHub (used without a mirror).
        why: one sentence for the log and ``doctor``.
    """

    name: str
    url: str
    why: str


#: Bump when a repair of the sources, the wheels or the build flags changes
#: (shared/ROS_ENV.md, "Building the missing ROS pieces from source").
REPAIRS_VERSION = 1

#: Upstream patches by name.
PATCHES = {
    "ros2pkg-empy4.patch": Patch(
        "ros2pkg-empy4.patch",
        "https://github.com/ros2/ros2cli/commit/f75f4e2499fcd0037eb4ae277d424b4618ae4af3.patch",
        "ros2cli f75f4e2 'Support empy4 and empy3': ros2 pkg create fails with the venv's empy 4 without it",
    ),
}

#: The ROS 2 Jazzy underlay (shared/ros-src/SOURCES.md, first table).
JAZZY = (
    Pin("ros", "console_bridge", "0828d846f2d4940b4e2b5075c6c724991d0cd308", "1.0.2", (".",), first=True),
    Pin("ros2", "console_bridge_vendor", "abb96a9e044e3ba4ecc4679eeb5de9f656737a76", "1.7.1"),
    Pin("ros", "class_loader", "8bad929bd8b2777b8d2b6eff7227b2c5f325b11d", "2.7.0"),
    # ament_copyright: ros2 pkg create; ament_lint_auto: the CMakeLists that ros2 pkg create writes
    # finds it when BUILD_TESTING is on (colcon's default), so a learner's plain colcon build needs it
    Pin("ament", "ament_lint", "6237cc3cf1ae69161d5e4edd2fbf2b0f01f521b9", "jazzy",
        ("ament_lint", "ament_copyright", "ament_lint_auto")),
    Pin("ros2", "launch", "09403fcebedb68dd259e9ab6b35bd8712b6596ec", "3.4.3",
        ("launch", "launch_xml", "launch_yaml", "launch_testing")),
    Pin("ros2", "launch_ros", "62c56e53e86812023697fe330c83d327f54e7b18", "0.26.6",
        ("launch_ros", "ros2launch", "launch_testing_ros")),
    Pin("ros-tooling", "libstatistics_collector", "df4e05887517486ce8325a58d39fc25a5caa3000", "1.7.3"),
    Pin("ros2", "rcl_interfaces", "003987ecb81a32802ab27dd6d325b8c6b8b813cc", "2.0.2",
        ("statistics_msgs", "composition_interfaces")),
    Pin("ros2", "rclcpp", "985e320de3a3549d5bc674876c79a5531bf301c2", "28.1.6"),
    Pin("ros2", "ros2cli", "de6cd27284937044d8dff47a617581c28865210c", "0.32.2",
        ("ros2cli", "ros2action", "ros2component", "ros2interface", "ros2lifecycle", "ros2multicast", "ros2node",
         "ros2param", "ros2pkg", "ros2run", "ros2service", "ros2topic"),
        patches=("ros2pkg-empy4.patch",)),
    Pin("ros2", "rosidl_runtime_py", "df2361f64ecb85f65f4bf22e804424e0f1ac4197", "0.13.1"),
    # tf2 (issue 20's tf2 lessons; not on PyPI): the Python and C++ APIs, tf2_ros' `static_transform_publisher`
    # and `tf2_echo`, tf2_tools' `view_frames`. Left out: tf2_geometry_msgs, tf2_kdl, tf2_eigen (orocos_kdl_vendor
    # would download KDL) and tf2_bullet (shared/ROS_ENV.md, "tf2 from source")
    Pin("ros2", "geometry2", "646342c6164e837d69460e3d28e7a025396544f6", "0.36.4",
        ("tf2", "tf2_msgs", "tf2_py", "tf2_ros_py", "tf2_ros", "tf2_tools")),
    Pin("ros2", "message_filters", "d3eecd6e1103ac44bf4bb9216e89353998b4c152", "4.11.2"),
)

#: SmartArmStack and DQ Robotics (tutorial ch. 29-31), optional, built on top of
#: :data:`JAZZY` (shared/ros-src/sas/SOURCES.md table; shared/ROS_ENV.md,
#: "Building SmartArmStack (sas) from source"): dqrobotics, then its
#: interfaces, then sas, in explicit colcon passes.
SAS = (
    Pin("dqrobotics", "cpp", "674eae4d8804baca6dc22bbbe3afc3b323c05cdf", "2026-04-08", group=0, mirror_dir="sas"),
    Pin("dqrobotics", "cpp-interface-json11", "9e71b5b1654388985d47912811b3f6a180285380", "2026-04-09",
        (".",), group=1, mirror_dir="sas"),
    Pin("dqrobotics", "cpp-interface-vrep", "b7517390d48ff6a5ae6feb56d5c1fdadd20ceeae", "2023-10-10",
        (".",), group=1, mirror_dir="sas"),
    Pin("CoppeliaRobotics", "include", "eb39eb12cb277710920485271e46d53541305f69", "2021-07-07",
        (), into="cpp-interface-vrep/coppeliarobotics/include", mirror_dir="sas"),
    Pin("CoppeliaRobotics", "remoteApi", "93f6af535031fc7dd490960c719494b856c23621", "2021-05-06",
        (), into="cpp-interface-vrep/coppeliarobotics/remoteApi", mirror_dir="sas"),
    Pin("SmartArmStack", "sas_core", "f4e5e944eb3a63f36d38c0723b8c6c952b26e05f", "humble 2023-06-12",
        group=2, mirror_dir="sas"),
    Pin("SmartArmStack", "sas_common", "cc092fd6f156c4cabb6dd48d0476261c1a639067", "humble 2023-06-12",
        group=2, mirror_dir="sas"),
    Pin("SmartArmStack", "sas_msgs", "4bfcff71d02415688249a7f209d38d2d3c855602", "humble 2023-06-06",
        group=2, mirror_dir="sas"),
    Pin("SmartArmStack", "sas_conversions", "827009809773bc7066b5b7e9aeeacd315ac6a168", "humble 2023-05-26",
        group=2, mirror_dir="sas"),
    Pin("SmartArmStack", "sas_robot_driver", "2050db0dcec4c287e914272156d5954cce3c421a", "humble 2023-06-22",
        group=2, mirror_dir="sas"),
)

#: The interfaces of the author's Gazebo and nav2 chapters, optional, built on top of :data:`JAZZY`
#: (shared/ros-src/SOURCES.md, first table; GitHub issue 40): ``ros_gz_interfaces`` (SetEntityPose,
#: EntityWrench, Entity), ``nav2_msgs`` (NavigateToPose) with the CMake helpers of ``nav2_common`` it is
#: built with, and ``geographic_msgs``, which nav2_msgs needs (FollowGPSWaypoints). The navigation2 archive
#: is a subset (``git archive <commit> nav2_msgs nav2_common LICENSE``): the whole repository is large and
#: its other packages need the full nav2 stack. nav2_msgs also needs ``nav_msgs``, which is a wheel (the
#: ``nav2`` extra: ``ros-jazzy-nav-msgs``), not a pin. One colcon pass: colcon orders them by their
#: package.xml dependencies.
NAV2 = (
    Pin("gazebosim", "ros_gz", "739cb42a5846cd12a526b97ba051a2d8cdbe034b", "1.0.5", ("ros_gz_interfaces",)),
    Pin("ros-geographic-info", "geographic_info", "2a0ae99219645b8d29772b997ef31f8e17345d52", "1.0.5",
        ("geographic_msgs",)),
    Pin("ros-navigation", "navigation2", "f4108e5b1c2bce804a1aa0c7be6673a8eb4a1501", "1.3.13",
        ("nav2_common", "nav2_msgs")),
)
