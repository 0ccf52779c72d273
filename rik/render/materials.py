"""Mitsuba materials and lighting, made from the catalog's finishes and from numbers alone (no texture or HDRI
files to download).

Every finish becomes a ``principled`` BSDF (metallic-roughness, as the catalog describes it): brushed metals
are anisotropic along the part's texture u axis, lacquer gets a clear coat, wood a procedural grain texture.
Geoms without a catalog finish (the gripper, the floor) become plastics of their MuJoCo colour.
"""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING

import numpy as np

from rik.schemas.finishes import Finish

if TYPE_CHECKING:
    import mitsuba as mi

WOOD_TEXTURE_SIZE_M = 0.25
"""Length of floor-to-ceiling wood grain the texture covers along u, m (the texture repeats beyond it)."""


def srgb_to_linear(c: np.ndarray | tuple[float, ...]) -> np.ndarray:
    """sRGB components in [0, 1] to linear reflectance."""
    c = np.clip(np.asarray(c, np.float64), 0.0, 1.0)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def linear_to_srgb8(img: np.ndarray) -> np.ndarray:
    """Linear radiance (exposure 1) to 8-bit sRGB: clip to [0, 1], sRGB transfer curve, round."""
    x = np.clip(np.nan_to_num(np.asarray(img, np.float32), nan=0.0), 0.0, 1.0)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(x * 255.0).astype(np.uint8)


@cache
def _wood_grain(seed: int = 7, size: tuple[int, int] = (128, 512)) -> np.ndarray:
    """A grain pattern in [0, 1]: growth rings seen along a board, wobbling, with fine fibre noise. Rows are v,
    columns u (the grain runs along u)."""
    rng = np.random.default_rng(seed)
    h, w = size
    v = np.linspace(0.0, 1.0, h, endpoint=False)[:, None]
    u = np.linspace(0.0, 1.0, w, endpoint=False)[None, :]
    wobble = sum(rng.uniform(0.005, 0.02) * np.sin(2 * np.pi * (k * u + rng.uniform())) for k in (1, 2, 3))
    rings = 0.5 + 0.5 * np.sin(2 * np.pi * 14.0 * (v + wobble) + 3.0 * np.sin(2 * np.pi * 3.0 * v))
    fibres = rng.normal(0.0, 1.0, (h, 1)) * 0.5 + rng.normal(0.0, 1.0, (h, w)) * 0.15
    return np.clip(0.65 * rings**3 + 0.35 + 0.08 * fibres, 0.0, 1.0)


def _wood_bitmap(base_color: np.ndarray) -> mi.Bitmap:
    import mitsuba as mi

    grain = _wood_grain()[..., None]
    dark = base_color * 0.55
    img = (dark + (base_color - dark) * grain).astype(np.float32)
    return mi.Bitmap(img)


def finish_bsdf(finish: Finish) -> dict[str, object]:
    """The Mitsuba BSDF dict of a catalog finish."""
    color = srgb_to_linear(finish.base_color)
    bsdf: dict[str, object] = {"type": "principled", "metallic": float(finish.metallic),
                            "roughness": float(max(finish.roughness, 0.03))}
    if finish.pattern == "wood_grain" or finish.kind == "wood":
        bsdf["base_color"] = {"type": "bitmap", "bitmap": _wood_bitmap(color), "wrap_mode": "mirror",
                              "to_uv": _uv_scale(1.0 / WOOD_TEXTURE_SIZE_M, 1.0 / (WOOD_TEXTURE_SIZE_M / 4))}
    else:
        bsdf["base_color"] = {"type": "rgb", "value": color.tolist()}
    if finish.pattern == "brushed":
        bsdf["anisotropic"] = 0.7
    if finish.kind == "lacquer":
        bsdf["clearcoat"] = 0.5
        bsdf["clearcoat_gloss"] = 0.8
    if finish.kind == "rubber":
        bsdf["specular"] = 0.3
    return bsdf


def plastic_bsdf(rgba: np.ndarray, roughness: float = 0.45) -> dict[str, object]:
    """A dielectric of a MuJoCo colour (sRGB ``rgba``), for geoms without a catalog finish."""
    return {"type": "principled", "base_color": {"type": "rgb", "value": srgb_to_linear(rgba[:3]).tolist()},
            "metallic": 0.0, "roughness": roughness}


def _uv_scale(su: float, sv: float) -> mi.ScalarTransform4f:
    import mitsuba as mi

    return mi.ScalarTransform4f().scale([su, sv, 1.0])


@cache
def _room_envmap(height: int = 64) -> np.ndarray:
    """A lat-long environment of an indoor room: a bright ceiling, a window, walls darkening to a floor.

    Mitsuba's lat-long maps are Y-up; the renderer rotates the emitter so that +v points along MuJoCo's +z."""
    h, w = height, 2 * height
    theta = (np.arange(h) + 0.5) / h * np.pi  # 0 at the zenith
    phi = (np.arange(w) + 0.5) / w * 2 * np.pi
    up = np.cos(theta)[:, None] * np.ones((1, w))
    wall = np.array([0.80, 0.78, 0.74])
    env = (0.35 + 0.45 * np.clip(up, 0, 1))[..., None] * wall
    env = np.where(up[..., None] < 0, (0.25 + 0.1 * (1 + up))[..., None] * np.array([0.55, 0.5, 0.45]), env)
    window = (np.abs(phi[None, :] - 1.2 * np.pi) < 0.35) & (up > 0.05) & (up < 0.6)
    env[window] = [3.0, 3.1, 3.3]
    return env.astype(np.float32)


def lighting(key_direction: np.ndarray, key_irradiance: float = 2.5, ambient: float = 1.0) -> dict[str, object]:
    """Emitters for a Mitsuba scene dict: the room environment plus a directional key light along
    ``key_direction`` (world, MuJoCo's z up) that casts the shadows MuJoCo's key light casts."""
    import mitsuba as mi

    env = _room_envmap() * ambient
    d = np.asarray(key_direction, np.float64)
    return {
        "room": {"type": "envmap", "bitmap": mi.Bitmap(env),
                 "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], 90)},
        "key": {"type": "directional", "direction": (d / np.linalg.norm(d)).tolist(),
                "irradiance": {"type": "rgb", "value": [key_irradiance] * 3}},
    }
