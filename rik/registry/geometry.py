"""Small vector helpers for the catalog's geometric checks (plain tuples: no numpy at CLI start-up)."""

from __future__ import annotations

from collections.abc import Iterable

Vec = tuple[float, float, float]


def vec3(values: Iterable[float]) -> Vec:
    """Three numbers as a tuple of floats (a position, a direction or extents); ValueError unless exactly three."""
    x, y, z = values
    return float(x), float(y), float(z)


def dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def rotate(quat: tuple[float, float, float, float], v: Vec) -> Vec:
    """Rotate ``v`` by the unit quaternion ``quat`` = (w, x, y, z)."""
    w, x, y, z = quat
    n = (w * w + x * x + y * y + z * z) ** 0.5
    w, x, y, z = w / n, x / n, y / n, z / n
    t = cross((x, y, z), v)
    t = (2 * t[0], 2 * t[1], 2 * t[2])
    u = cross((x, y, z), t)
    return (v[0] + w * t[0] + u[0], v[1] + w * t[1] + u[1], v[2] + w * t[2] + u[2])


def site_axes(quat: tuple[float, float, float, float]) -> tuple[Vec, Vec, Vec]:
    """The x, y and z axes of a site frame, in the parent frame."""
    return rotate(quat, (1.0, 0.0, 0.0)), rotate(quat, (0.0, 1.0, 0.0)), rotate(quat, (0.0, 0.0, 1.0))
