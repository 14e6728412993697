"""The paper's 3-layer skin mesh: masses, springs and which masses are fixed.

Layer 1 is a 6x6 grid of masses, layer 2 a 5x5 grid, layer 3 a 4x4 grid; each lower-layer
mass sits under the centre of a 2x2 cell of the layer above (pyramids). Masses are numbered as
in the paper, 1-based, layer-major then row-major: layer 1 is M1..M36 (M15 is row 3, column 3),
layer 2 M37..M61, layer 3 M62..M77. In code, mass index ``i`` (0-based) is the paper's
M(i+1).

Coordinates (metres): x grows with the column, y grows towards row 1 (row 1 is the top row of
the paper's figure), z is 0 on layer 1 and ``-layer_gap_m`` per layer below; every layer is
centred on x = y = 0, so a lower mass lies exactly under the centre of its cell.

Springs (each with a parallel damper), in this order, which is also the sensor order:

1. for each layer 1, 2, 3: the row neighbours (row-major), the column neighbours (row-major),
   then one diagonal per cell (row-major), running from the cell's top-right mass to its
   bottom-left mass, as M6–M11 in the paper's Figure 1B (cell M5, M6, M11, M12 splits into
   triangles M5-M6-M11 and M6-M11-M12);
2. between layers 1 and 2, then between layers 2 and 3: for each lower mass in number order,
   the springs to its cell's top-left, top-right, bottom-left and bottom-right masses.

Counts: 85 + 56 + 33 in-layer and 100 + 64 between layers = 338 springs. Masses on the edge
of every layer are fixed, and all of layer 3 is fixed: 25 of the 77 masses are free.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

LAYER_SIZES: tuple[int, int, int] = (6, 5, 4)
"""Grid side of layers 1, 2, 3."""

N_MASSES = sum(n * n for n in LAYER_SIZES)
N_SPRINGS = 338


@dataclass(frozen=True)
class Mesh:
    """The mesh geometry: rest positions (m), springs (0-based mass pairs), fixed masses."""

    positions: np.ndarray
    """(77, 3) rest positions in metres."""
    springs: np.ndarray
    """(338, 2) int64 0-based mass indices (index i is the paper's M(i+1))."""
    fixed: np.ndarray
    """(77,) bool, True where the mass is held fixed."""
    layer_of_spring: np.ndarray
    """(338,) int: 1, 2, 3 for in-layer springs, 12 or 23 for springs between layers."""

    @property
    def free(self) -> np.ndarray:
        """0-based indices of the free masses, ascending (25 of them)."""
        return np.flatnonzero(~self.fixed)


def _layer_offset(layer: int) -> int:
    return sum(n * n for n in LAYER_SIZES[:layer])


def mass_index(layer: int, row: int, col: int) -> int:
    """0-based index of the mass at 0-based ``layer``, ``row``, ``col``."""
    n = LAYER_SIZES[layer]
    return _layer_offset(layer) + row * n + col


def build_mesh(spacing_m: float, layer_gap_m: float) -> Mesh:
    """Build the paper's mesh with lateral ``spacing_m`` and vertical ``layer_gap_m`` (m)."""
    positions = np.zeros((N_MASSES, 3))
    fixed = np.zeros(N_MASSES, dtype=bool)
    for layer, n in enumerate(LAYER_SIZES):
        half = (n - 1) / 2.0
        for r in range(n):
            for c in range(n):
                i = mass_index(layer, r, c)
                positions[i] = ((c - half) * spacing_m, (half - r) * spacing_m,
                                -layer * layer_gap_m)
                fixed[i] = layer == 2 or r in (0, n - 1) or c in (0, n - 1)

    springs: list[tuple[int, int]] = []
    kinds: list[int] = []
    for layer, n in enumerate(LAYER_SIZES):
        row_pairs = [(mass_index(layer, r, c), mass_index(layer, r, c + 1))
                     for r in range(n) for c in range(n - 1)]
        col_pairs = [(mass_index(layer, r, c), mass_index(layer, r + 1, c))
                     for r in range(n - 1) for c in range(n)]
        diag_pairs = [(mass_index(layer, r, c + 1), mass_index(layer, r + 1, c))
                      for r in range(n - 1) for c in range(n - 1)]
        for pairs in (row_pairs, col_pairs, diag_pairs):
            springs.extend(pairs)
            kinds.extend([layer + 1] * len(pairs))
    for upper in (0, 1):
        n_low = LAYER_SIZES[upper + 1]
        for r in range(n_low):
            for c in range(n_low):
                low = mass_index(upper + 1, r, c)
                for dr, dc in ((0, 0), (0, 1), (1, 0), (1, 1)):
                    springs.append((low, mass_index(upper, r + dr, c + dc)))
                    kinds.append(12 if upper == 0 else 23)
    spring_arr = np.asarray(springs, dtype=np.int64)
    if spring_arr.shape != (N_SPRINGS, 2):  # pragma: no cover - geometry is fixed
        raise RuntimeError(f"mesh has {len(springs)} springs, expected {N_SPRINGS}")
    return Mesh(positions=positions, springs=spring_arr, fixed=fixed,
                layer_of_spring=np.asarray(kinds, dtype=np.int64))
