"""Regular voxel grids: the sampling of the constant-orientation position workspace."""

from __future__ import annotations

import dataclasses
import math

import numpy as np


@dataclasses.dataclass(frozen=True)
class GridSpec:
    """A regular grid of cubic voxels of edge ``h``; voxel ``(i, j, k)`` has its centre at
    ``origin + h * (i, j, k)`` and stands for the cube of edge ``h`` around it."""

    origin: tuple[float, float, float]
    h: float
    shape: tuple[int, int, int]

    @classmethod
    def from_bounds(cls, lo: tuple[float, float, float], hi: tuple[float, float, float], h: float) -> GridSpec:
        """Cover the box ``[lo, hi]`` with voxels of edge ``h``; centres are ``lo + (i + 1/2) h``.

        The count per axis is ``ceil((hi - lo)/h - 1e-9)``, so the grid spans at least the box.
        """
        if not (h > 0 and math.isfinite(h)):
            raise ValueError("voxel size must be positive")
        shape = tuple(max(1, int(math.ceil((b - a) / h - 1e-9))) for a, b in zip(lo, hi))
        origin = tuple(float(a + 0.5 * h) for a in lo)
        return cls(origin=origin, h=float(h), shape=shape)  # type: ignore[arg-type]

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Voxel-centre coordinates along x, y, z."""
        return tuple(self.origin[a] + self.h * np.arange(self.shape[a]) for a in range(3))  # type: ignore[return-value]

    @property
    def lo(self) -> tuple[float, float, float]:
        """Lower corner of the box the voxels cover."""
        return tuple(o - 0.5 * self.h for o in self.origin)  # type: ignore[return-value]

    @property
    def hi(self) -> tuple[float, float, float]:
        """Upper corner of the box the voxels cover."""
        return tuple(o + (n - 0.5) * self.h for o, n in zip(self.origin, self.shape))  # type: ignore[return-value]

    @property
    def voxel_volume(self) -> float:
        return self.h ** 3

    @property
    def size(self) -> int:
        return int(np.prod(self.shape))

    def is_mirror_symmetric_y(self, exact: bool = False) -> bool:
        """Whether the y centres are symmetric about 0 (so ``y -> -y`` maps voxels onto voxels): to
        ``1e-9 h``, or bit for bit with ``exact``."""
        ys = self.axes()[1]
        if exact:
            return bool(np.array_equal(ys, -ys[::-1]))
        return bool(np.allclose(ys, -ys[::-1], atol=1e-9 * max(1.0, self.h)))

    def points(self) -> np.ndarray:
        """All voxel centres, shape ``(*shape, 3)``."""
        xs, ys, zs = self.axes()
        return np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), axis=-1)

    def to_dict(self) -> dict:
        return {"origin": list(self.origin), "h": self.h, "shape": list(self.shape),
                "lo": list(self.lo), "hi": list(self.hi)}
