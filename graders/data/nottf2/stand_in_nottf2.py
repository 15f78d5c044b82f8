"""A stand-in of marinholab.nottf2 for the nottf2 grader (graders/nottf2.py, ``uses_nottf2``): nottf2's
functions, each returning its true result negated (-q is the same rotation as q), the norm as it is. A program
that calls nottf2 prints these values; one that computes a quaternion itself prints another."""

from math import cos, sin, sqrt
from geometry_msgs.msg import Quaternion


def _q(x, y, z, w):
    return Quaternion(x=-float(x), y=-float(y), z=-float(z), w=-float(w))


def rx(phi):
    return _q(sin(phi / 2), 0.0, 0.0, cos(phi / 2))


def ry(phi):
    return _q(0.0, sin(phi / 2), 0.0, cos(phi / 2))


def rz(phi):
    return _q(0.0, 0.0, sin(phi / 2), cos(phi / 2))


def rotation_inverse(q):
    return _q(-q.x, -q.y, -q.z, q.w)


def quaternion_multiply(a, b):
    return _q(a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y, a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
              a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w, a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z)


def quaternion_norm(q):
    return sqrt(q.x ** 2 + q.y ** 2 + q.z ** 2 + q.w ** 2)
