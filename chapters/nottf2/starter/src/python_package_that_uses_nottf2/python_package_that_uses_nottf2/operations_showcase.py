"""Compose rotations with nottf2's quaternion helpers and print each result (lesson nottf2)."""

from math import pi

# TODO: import nottf2's helpers (pip installs the PyPI package nottf2 as the module marinholab.nottf2)


def main() -> None:
    """Print r1, r1_conj, r2 and r12, one per line, each as NAME=<the Quaternion message>."""
    angle = pi
    # TODO: r1 = half a turn (angle) about the x-axis; print it as r1=...
    # TODO: r1_conj = the inverse of r1; print it as r1_conj=...
    # TODO: r2 = half a turn (angle) about the z-axis; print it as r2=...
    # TODO: r12 = the product r1 r2 (r1 first, then r2); print it as r12=...
    print(f'Nothing computed yet (angle {angle} rad)')


if __name__ == '__main__':
    main()
