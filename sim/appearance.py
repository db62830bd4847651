"""How a world looks to the camera beyond its geometry, for worlds that ask for it
(``appearance:`` in a world description, e.g. house_hard): printed labels, per-seed
lighting, per-object colour jitter and an RGB-D camera's depth noise.

Everything is off by default: house and open_floor render exactly as they always did.

- ``lighting``: the light's direction (given to the renderer, EGL and TinyRenderer both
  take it) and a per-seed white balance, brightness and ambient lift applied to the colour
  image (the EGL renderer ignores pybullet's light colour and coefficients).
- ``depth_noise``: per pixel, sigma(z) = a + b (z - z0)^2 [m] (a Kinect-style axial
  model), plus dropouts (NaN) at depth edges and, ever less often, on surfaces seen at
  grazing angles, and a few random ones; drawn from a stream seeded by the world seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ColorJitter:
    """Per object: hue turned by up to ``hue`` (fraction of the colour circle), saturation
    and brightness scaled by up to ``saturation`` and ``value``."""

    hue: float = 0.015
    saturation: float = 0.10
    value: float = 0.12


@dataclass(frozen=True)
class LightingRange:
    """What a seed draws the lighting from: the light's elevation [deg] and azimuth (any),
    the brightness gain, the per-channel white-balance spread and the ambient lift."""

    elevation: tuple[float, float] = (25.0, 80.0)
    brightness: tuple[float, float] = (0.75, 1.15)
    tint: float = 0.08
    ambient: tuple[float, float] = (0.0, 0.06)


@dataclass(frozen=True)
class DepthNoise:
    """sigma(z) = a + b (z - z0)^2 [m]; ``dropout``: the chance a pixel on a depth edge
    returns nothing, falling linearly to 0 for surfaces seen ``grazing_deg`` off facing the
    camera; ``speckle``: the chance any pixel returns nothing."""

    a: float = 0.0012
    b: float = 0.0019
    z0: float = 0.4
    dropout: float = 0.7
    grazing_deg: float = 80.0
    speckle: float = 0.001


@dataclass(frozen=True)
class Appearance:
    """What a world draws beyond plain colours. All off: the default."""

    labels: bool = False
    lighting: LightingRange | None = None
    color_jitter: ColorJitter | None = None
    depth_noise: DepthNoise | None = None

    @property
    def plain(self) -> bool:
        return not (self.labels or self.lighting or self.color_jitter or self.depth_noise)


@dataclass(frozen=True)
class Lighting:
    """One seed's lighting: ``direction`` (towards the light, world frame) for the renderer;
    ``gain`` (r, g, b) and ``ambient`` applied to the colour image: out = in * gain +
    ambient * 255."""

    direction: tuple[float, float, float]
    gain: tuple[float, float, float]
    ambient: float = 0.0

    @classmethod
    def draw(cls, rng: np.random.Generator, r: LightingRange) -> Lighting:
        el = math.radians(rng.uniform(*r.elevation))
        az = rng.uniform(-math.pi, math.pi)
        direction = (math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el))
        bright = rng.uniform(*r.brightness)
        tint = rng.uniform(-r.tint, r.tint, 3)
        tint -= tint.mean()  # white balance: shifts between channels
        gr, gg, gb = (float(bright * (1 + t)) for t in tint)
        return cls(direction, (gr, gg, gb), float(rng.uniform(*r.ambient)))

    def apply(self, rgb: np.ndarray) -> np.ndarray:
        out = rgb.astype(np.float32) * np.asarray(self.gain, np.float32) + 255.0 * self.ambient
        return np.clip(out + 0.5, 0, 255).astype(np.uint8)


def noisy_depth(depth: np.ndarray, rng: np.random.Generator, model: DepthNoise, fx: float) -> np.ndarray:
    """``depth`` (float32 [h, w] metres, NaN = no return) as an RGB-D camera measures it."""
    z = depth.astype(np.float32, copy=True)
    valid = np.isfinite(z)
    if not valid.any():
        return z
    zv = np.where(valid, z, 0.0)
    sigma = model.a + model.b * (zv - model.z0) ** 2
    z = z + (rng.standard_normal(z.shape).astype(np.float32) * sigma.astype(np.float32))
    # surface slope from the depth gradient: dz per lateral metre (a pixel spans z / fx)
    zp = np.pad(np.where(valid, depth, np.nan), 1, mode="edge")
    gx = np.fmax(np.abs(zp[1:-1, 2:] - zp[1:-1, 1:-1]), np.abs(zp[1:-1, 1:-1] - zp[1:-1, :-2]))
    gy = np.fmax(np.abs(zp[2:, 1:-1] - zp[1:-1, 1:-1]), np.abs(zp[1:-1, 1:-1] - zp[:-2, 1:-1]))
    slope = np.fmax(gx, gy) * fx / np.maximum(zv, 1e-3)
    slope = np.where(np.isfinite(slope), slope, np.inf)  # next to a hole: an edge
    # the chance of a dropout grows from 0 at grazing_deg to ``dropout`` at 90 deg (edges)
    angle = np.degrees(np.arctan(slope))
    g = model.grazing_deg
    chance = model.dropout * np.clip((angle - g) / max(90.0 - g, 1e-6), 0.0, 1.0)
    drop = valid & (rng.random(z.shape) < chance)
    drop |= valid & (rng.random(z.shape) < model.speckle)
    z[drop] = np.nan
    z[~valid] = np.nan
    return z
