"""Procedural textures for the simulated cameras: the seabed by kind, and one grey texture for object parts.

Appearance (for cameras, `MjWorld(scene, appearance=Appearance(...))`): the seabed gets a seeded procedural texture
by `texture.kind` (multi-octave noise, sand ripples, gravel, mud, rock) and every object part a textured twin in
`VISUAL_GROUP`: a mesh of the same shape whose texture coordinates run in metres, so one grey noise texture
(paint, fouling blobs, specks) modulates each part's colour at the same scale on every face — flat faces get
corners and blobs a feature matcher can hold on to. The seabed is repeated as square hfield tiles in
`SEABED_TILE_GROUP` (the same grid nodes; the last row and column of tiles run past the world's edge, flat) so that a
camera renders the few tiles in view, not hundreds of thousands of triangles; each tile spans a whole number of
texture periods, so the texture runs on without seams. Rays only see groups 0 and 1; cameras show groups 2 and 3.
Without an appearance the model is exactly the plain one the sonar uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.fft
from numpy.typing import NDArray

from mission.language.world import Texture


@dataclass(frozen=True)
class Appearance:
    """How the world looks to cameras: procedural textures for the seabed and the object parts.

    The seabed texture tiles every `seabed_tile_m` metres with `seabed_texels` texels a side (6 mm a texel by
    default, about one pixel at 6 m range with fx = 1000); the objects share one grey texture tiling every
    `object_tile_m` metres (4 mm a texel by default), multiplied by each part's colour.
    """

    seabed: Texture = field(default_factory=Texture)
    seabed_tile_m: float = 12.0
    """Texture period (m), rounded so that a whole number of periods spans a seabed tile."""
    seabed_texels: int = 2048
    object_tile_m: float = 4.0
    object_texels: int = 1024
    object_seed: int = 0
    seabed_tile_span_m: float = 24.0
    """Side of a seabed tile (m), rounded to whole grid cells."""

    def tiling(self, resolution: float) -> tuple[int, int, float]:
        """(grid cells per tile side, texture periods per tile side, texture period in metres) for a grid.

        >>> Appearance().tiling(1.0)
        (24, 2, 12.0)
        """
        cells = max(2, round(self.seabed_tile_span_m / resolution))
        periods = max(1, round(cells * resolution / self.seabed_tile_m))
        return cells, periods, cells * resolution / periods


_SEABED_RGB: dict[str, tuple[float, float, float]] = {
    "sand": (0.78, 0.72, 0.58), "mud": (0.55, 0.52, 0.45), "gravel": (0.66, 0.64, 0.60), "rock": (0.60, 0.60, 0.58),
}


def band_noise(rng: np.random.Generator, texels: int, tile_m: float, shortest_m: float, longest_m: float,
               beta: float = 2.0) -> NDArray[np.float32]:
    """Seamlessly tiling noise with wavelengths between `shortest_m` and `longest_m` (soft band edges) and a power
    spectrum falling as f^−beta (2 for natural surfaces, 0 for white); zero mean, unit standard deviation.

    >>> n = band_noise(np.random.default_rng(0), 64, 1.0, 0.05, 0.5)
    >>> n.shape, abs(float(n.mean())) < 1e-6, round(float(n.std()), 4)
    ((64, 64), True, 1.0)
    """
    spectrum = scipy.fft.rfft2(rng.standard_normal((texels, texels), dtype=np.float32))
    fy = (np.fft.fftfreq(texels) * (texels / tile_m)).astype(np.float32)  # cycles per metre
    fx = (np.fft.rfftfreq(texels) * (texels / tile_m)).astype(np.float32)
    f2 = fy[:, None] ** 2 + fx[None, :] ** 2
    f2[0, 0] = 1.0
    gain = f2 ** np.float32(-0.25 * beta) * np.exp(-f2 * np.float32(shortest_m**2))
    gain *= -np.expm1(-f2 * np.float32(longest_m**2))
    gain[0, 0] = 0.0
    out = scipy.fft.irfft2(spectrum * gain, s=(texels, texels))
    out -= out.mean()
    std = out.std()
    return np.asarray(out / std if std > 0 else out, dtype=np.float32)


def _smoothstep(lo: float, hi: float, x: NDArray[np.float32]) -> NDArray[np.float32]:
    t = np.clip((x - np.float32(lo)) * np.float32(1.0 / (hi - lo)), 0.0, 1.0)
    return np.asarray(t * t * (3.0 - 2.0 * t), dtype=np.float32)


def _ripples(rng: np.random.Generator, texels: int, tile_m: float, wavelength_m: float) -> NDArray[np.float32]:
    """Sand ripples: asymmetric crests whose wave vector tiles exactly, bent and faded by low-frequency noise."""
    angle = rng.uniform(0.0, math.pi)
    k = np.round(tile_m / wavelength_m * np.array([math.cos(angle), math.sin(angle)]))
    ramp = np.arange(texels, dtype=np.float32) * np.float32(2.0 * math.pi / texels)
    phase = (np.float32(k[0]) * ramp[None, :] + np.float32(k[1]) * ramp[:, None]
             + 2.5 * band_noise(rng, texels, tile_m, 0.5, 4.0))
    crest = np.sin(phase + 0.7 * np.sin(phase))  # steeper lee side than stoss side
    return np.asarray(crest * _smoothstep(-0.8, 0.8, band_noise(rng, texels, tile_m, 1.0, 6.0)), dtype=np.float32)


def seabed_albedo(texture: Texture, texels: int = 2048, tile_m: float = 12.0) -> NDArray[np.float32]:
    """(texels, texels, 3) seabed colour in [0, 1] for a `seabed.texture` spec; the same spec, the same texture.

    Every kind has multi-octave noise from centimetres to metres (shading and blobs) and grain at a few texels
    (corners for feature detectors); `scale` stretches all feature sizes.
    """
    rng = np.random.default_rng(texture.seed)
    s = texture.scale

    def noise(shortest: float, longest: float, beta: float = 2.0) -> NDArray[np.float32]:
        return band_noise(rng, texels, tile_m, shortest * s, longest * s, beta)

    grain = noise(0.008, 0.03, 0.0)
    specks = noise(0.015, 0.05, 1.0)
    if texture.kind == "sand":
        grey = 0.62 * (1.0 + 0.16 * noise(0.03, 3.0) + 0.12 * _ripples(rng, texels, tile_m, 0.12 * s)
                       + 0.10 * grain)
        grey += 0.30 * _smoothstep(2.0, 2.6, specks) - 0.25 * _smoothstep(2.2, 2.8, -specks)  # shell bits, pits
    elif texture.kind == "gravel":
        pebbles = _smoothstep(-0.1, 0.5, noise(0.025, 0.08, 2.0))
        tone = 0.58 + 0.16 * noise(0.04, 0.15, 1.0)
        grey = (1.0 - pebbles) * 0.42 * (1.0 + 0.12 * grain) + pebbles * tone
        grey *= 1.0 + 0.12 * noise(0.2, 3.0)
    elif texture.kind == "mud":
        grey = 0.50 * (1.0 + 0.14 * noise(0.05, 4.0) + 0.07 * grain)
        grey -= 0.22 * _smoothstep(2.1, 2.7, specks)  # burrows
    else:  # rock
        grey = 0.52 * (1.0 + 0.28 * noise(0.02, 4.0, 1.6) + 0.08 * grain)
        grey *= 1.0 - 0.5 * np.exp(-((noise(0.05, 0.8) / 0.12) ** 2))  # cracks where a noise crosses zero
    colour = np.asarray(_SEABED_RGB[texture.kind], dtype=np.float32) / np.float32(0.78)
    return np.asarray(np.clip(np.clip(grey, 0.0, 1.0)[..., None] * colour, 0.0, 1.0), dtype=np.float32)


def object_albedo(seed: int = 0, texels: int = 1024, tile_m: float = 4.0) -> NDArray[np.float32]:
    """(texels, texels) grey in [0, 1] that modulates part colours: paint shading, light fouling, specks.

    Painted steel stays mostly uniform: the object's geometric corners, not its stains, must be the strongest
    Harris corners in a picture (seed 002 §3.1 chooses characteristic points that a Harris detector extracts well),
    while the weak texture still gives dense matchers something to hold on to."""
    rng = np.random.default_rng(seed)
    grey = 0.85 * (1.0 + 0.06 * band_noise(rng, texels, tile_m, 0.02, 1.0) + 0.04
                   * band_noise(rng, texels, tile_m, 0.006, 0.02, 0.0))
    grey *= 1.0 - 0.12 * _smoothstep(0.8, 1.6, band_noise(rng, texels, tile_m, 0.03, 0.3))  # fouling
    specks = band_noise(rng, texels, tile_m, 0.008, 0.03, 0.0)
    grey *= 1.0 - 0.12 * _smoothstep(2.2, 2.9, specks)
    return np.asarray(np.clip(grey, 0.0, 1.0), dtype=np.float32)


def to_bytes(image: NDArray[np.floating[Any]]) -> NDArray[np.uint8]:
    return np.asarray(np.clip(np.rint(255.0 * image), 0, 255), dtype=np.uint8)


__all__ = ["Appearance", "band_noise", "object_albedo", "seabed_albedo", "to_bytes"]
