"""Grader for ``custom-interfaces`` (seed ch. 16-17; contract in shared/LESSONS.md).

The contract is about the package itself, so this grader reads what colcon
installed: the package manifest, the ament index entry rosidl writes
(what ``ros2 interface package`` lists) and the generated Python types,
imported in a fresh interpreter of the sourced workspace
(:func:`ros2course.kit.topics_services.generated_fields`), the way a learner's
node would import them.
"""

from __future__ import annotations

from pathlib import Path

from ros2course import kit
from ros2course.kit import Check, Session
from ros2course.kit.topics_services import fields, generated_fields

PACKAGE = "package_with_interfaces"
#: field -> type as ``get_fields_and_field_types()`` spells it (seed ch. 17.4 and 17.6).
MESSAGE = {"id": "int32", "quote": "string", "philosopher_name": "string"}
REQUEST = {"quote": "package_with_interfaces/AmazingQuote"}
RESPONSE = {"point": "geometry_msgs/Point"}
INDEXED = ["msg/AmazingQuote.msg", "srv/WhatIsThePoint.srv"]
#: package.xml entries seed ch. 17.2 asks for: (kind, name) -> how a learner writes it.
MANIFEST = {
    ("buildtool", "rosidl_default_generators"): "<buildtool_depend>rosidl_default_generators</buildtool_depend>",
    ("exec", "rosidl_default_runtime"): "<exec_depend>rosidl_default_runtime</exec_depend>",
    ("group", "rosidl_interface_packages"): "<member_of_group>rosidl_interface_packages</member_of_group>",
    ("depend", "geometry_msgs"): "<depend>geometry_msgs</depend>",
}

#: No node is observed: the generated types are inspected in a subprocess.
WINDOW = 0.0

CHECKS = [
    Check("build", "The package builds with colcon", 2),
    Check("ament_cmake", "package_with_interfaces is an ament_cmake package", 1,
          "interfaces need an ament_cmake package: <build_type>ament_cmake</build_type> in package.xml's <export>"),
    Check("manifest", "package.xml declares what interface packages need", 2,
          "seed ch. 17.2: buildtool_depend rosidl_default_generators, exec_depend rosidl_default_runtime, "
          "member_of_group rosidl_interface_packages, and depend geometry_msgs"),
    Check("interfaces_indexed", "ros2 interface package lists msg/AmazingQuote and srv/WhatIsThePoint", 2,
          "list both files in rosidl_generate_interfaces(${PROJECT_NAME} \"msg/AmazingQuote.msg\" "
          "\"srv/WhatIsThePoint.srv\" DEPENDENCIES geometry_msgs), then colcon build"),
    Check("message_fields", "AmazingQuote has exactly: int32 id, string quote, string philosopher_name", 3,
          "msg/AmazingQuote.msg holds three lines: 'int32 id', 'string quote', 'string philosopher_name'"),
    Check("request_fields", "WhatIsThePoint's request is exactly: AmazingQuote quote", 2,
          "above the '---' in srv/WhatIsThePoint.srv: 'AmazingQuote quote' (same package: no package prefix)"),
    Check("response_fields", "WhatIsThePoint's response is exactly: geometry_msgs/Point point", 2,
          "below the '---': 'geometry_msgs/Point point' (another package: with its prefix)"),
]


def _check_manifest(s: Session) -> None:
    found = kit.source_package(s, PACKAGE)
    if found is None:
        s.record("ament_cmake", False, f"no package {PACKAGE} in src/", "<build_type>ament_cmake</build_type>")
        s.record("manifest", False, f"no package {PACKAGE} in src/", "the interface dependencies in package.xml")
        return
    pkg = found[1]
    build_type = pkg.get_build_type()
    s.record("ament_cmake", build_type == "ament_cmake", f"build type: {build_type}",
             "build type: ament_cmake")
    have = {("buildtool", d.name) for d in pkg.buildtool_depends}
    have |= {("exec", d.name) for d in pkg.exec_depends}
    have |= {("group", g.name) for g in pkg.member_of_groups}
    both = {d.name for d in pkg.build_depends} & {d.name for d in pkg.exec_depends}
    have |= {("depend", name) for name in both}  # <depend> is a build and an exec dependency
    missing = [text for key, text in MANIFEST.items() if key not in have]
    s.record("manifest", not missing, "missing: " + ", ".join(missing) if missing else "all four entries present",
             ", ".join(MANIFEST.values()), fraction=(len(MANIFEST) - len(missing)) / len(MANIFEST))


def _check_index(s: Session) -> None:
    prefix = None
    for entry in s.overlay().get("AMENT_PREFIX_PATH", "").split(":"):
        if entry and Path(entry, "share", "ament_index", "resource_index", "packages", PACKAGE).is_file():
            prefix = Path(entry)
            break
    expected = "the rosidl_interfaces index lists " + " and ".join(INDEXED)
    if prefix is None:
        s.record("interfaces_indexed", False, f"{PACKAGE} is not installed in the workspace", expected)
        return
    index = prefix / "share" / "ament_index" / "resource_index" / "rosidl_interfaces" / PACKAGE
    listed = index.read_text(encoding="utf-8").split() if index.is_file() else []
    interfaces = [line for line in listed if line.endswith((".msg", ".srv"))]
    missing = [name for name in INDEXED if name not in interfaces]
    s.record("interfaces_indexed", not missing,
             f"listed: {', '.join(interfaces) or 'nothing (no rosidl_generate_interfaces?)'}", expected,
             fraction=(len(INDEXED) - len(missing)) / len(INDEXED))


def grade(s: Session) -> None:
    """Read package.xml and the ament index, then import the generated types in a fresh interpreter."""
    _check_manifest(s)
    _check_index(s)
    with s.phase("observe"):
        types = generated_fields(s, [(PACKAGE, "msg", "AmazingQuote"), (PACKAGE, "srv", "WhatIsThePoint")])
    msg, srv = f"{PACKAGE}/msg/AmazingQuote", f"{PACKAGE}/srv/WhatIsThePoint"
    fields(s, "message_fields", "AmazingQuote", types.get(msg), MESSAGE, types.get(f"{msg}.error"))
    fields(s, "request_fields", "WhatIsThePoint.Request", types.get(f"{srv}.Request"), REQUEST,
           types.get(f"{srv}.error"))
    fields(s, "response_fields", "WhatIsThePoint.Response", types.get(f"{srv}.Response"), RESPONSE,
           types.get(f"{srv}.error"))
