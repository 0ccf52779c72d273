"""A variant's ``scene.xml``: floor, lights, sky and a front camera around ``<include file="model.xml"/>``.

MuJoCo's ``MjSpec`` has no include element (it would inline the model), so the scene, which only frames the
model, is written from this template, as MuJoCo Menagerie's scenes are.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rik.schemas import BaseUnit

SCENE = """<mujoco model="{name} scene">
  <include file="model.xml"/>

  <statistic center="0 0 {cz:.4g}" extent="{extent:.4g}"/>

  <visual>
    <headlight diffuse="0.6 0.6 0.6" ambient="0.3 0.3 0.3" specular="0 0 0"/>
    <rgba haze="0.15 0.25 0.35 1"/>
    <global azimuth="110" elevation="-20" offwidth="1280" offheight="960"/>
  </visual>

  <asset>
    <texture type="skybox" builtin="gradient" rgb1="0.3 0.5 0.7" rgb2="0 0 0" width="512" height="3072"/>
    <texture type="2d" name="floor" builtin="checker" mark="edge" rgb1="0.2 0.3 0.4" rgb2="0.1 0.2 0.3"
      markrgb="0.8 0.8 0.8" width="300" height="300"/>
    <material name="floor" texture="floor" texuniform="true" texrepeat="5 5" reflectance="0.2"/>
  </asset>

  <worldbody>
    <light pos="{lx:.4g} {ly:.4g} {lz:.4g}" dir="{dx:.4g} {dy:.4g} {dz:.4g}" directional="true"/>
    <geom name="floor" size="0 0 0.05" type="plane" material="floor"/>
    <camera name="front" pos="{px:.4g} {py:.4g} {pz:.4g}" xyaxes="{xyaxes}" fovy="45"/>
  </worldbody>
</mujoco>
"""

VIEW_DIRECTION = (0.45, 1.0, 0.55)
"""From the base unit's centre towards the camera: in front, a little to the left and above (base-unit frame)."""


def _normalise(v: tuple[float, float, float]) -> tuple[float, float, float]:
    n = math.sqrt(sum(c * c for c in v))
    return (v[0] / n, v[1] / n, v[2] / n)


def _cross(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, float, float]:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def scene_xml(name: str, unit: BaseUnit) -> str:
    """The scene of a variant of ``unit``: the camera frames the carcass with its fronts open."""
    c = unit.carcass
    center = (0.0, -c.depth / 2 + 0.15, unit.install_height + c.height / 2)
    size = max(c.width, c.height, c.depth)
    distance = 1.35 * size + 0.6
    back = _normalise(VIEW_DIRECTION)
    pos = tuple(center[i] + distance * back[i] for i in range(3))
    x_axis = _normalise(_cross((0.0, 0.0, 1.0), back))
    y_axis = _cross(back, x_axis)
    xyaxes = " ".join(f"{v:.4f}" for v in (*x_axis, *y_axis))
    top = unit.install_height + c.height
    return SCENE.format(name=name, cz=center[2], extent=max(size, top), lx=0.5, ly=2.0, lz=top + 1.5,
                        dx=-0.2, dy=-0.6, dz=-0.77, px=pos[0], py=pos[1], pz=pos[2], xyaxes=xyaxes)
