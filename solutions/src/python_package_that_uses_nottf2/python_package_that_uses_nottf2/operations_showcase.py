"""Compose rotations with nottf2's quaternion helpers and print each result.

nottf2 (pip: nottf2, import: marinholab.nottf2) returns geometry_msgs/msg/Quaternion
messages; an f-string shows a message with all four fields, so every line ends
with NAME=geometry_msgs.msg.Quaternion(x=..., y=..., z=..., w=...).
"""

from math import pi

import marinholab.nottf2 as nottf2


def main() -> None:
    """Print half a turn about x, its inverse, half a turn about z, and the two composed."""
    angle = pi

    r1 = nottf2.rx(phi=angle)
    print(f'Half a turn ({angle} rad) about the x-axis: r1={r1}')

    r1_conj = nottf2.rotation_inverse(r1)
    print(f'Its inverse, which undoes it: r1_conj={r1_conj}')

    r2 = nottf2.rz(phi=angle)
    print(f'Half a turn ({angle} rad) about the z-axis: r2={r2}')

    r12 = nottf2.quaternion_multiply(r1, r2)
    print(f'The product r1 * r2 (r1 first, then r2 in its frame): r12={r12}')


if __name__ == '__main__':
    main()
