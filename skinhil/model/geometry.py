"""The 3-layer skin mesh at any size: masses, springs and which masses are fixed.

The top layer (layer 1) is a grid of ``rows x cols`` masses (the paper's is 6x6, the default);
layer 2 is ``rows-1 x cols-1`` and layer 3 ``rows-2 x cols-2``: each lower-layer mass sits
under the centre of a 2x2 cell of the layer above (pyramids). The smallest mesh is 3x3 (layer
3 is then a single mass). Masses are numbered as in the paper, 1-based, layer-major then
row-major: at 6x6 layer 1 is M1..M36 (M15 is row 3, column 3), layer 2 M37..M61, layer 3
M62..M77. In code, mass index ``i`` (0-based) is M(i+1).

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

A layer of ``n x m`` masses has ``n(m-1) + (n-1)m + (n-1)(m-1)`` in-layer springs and sends
``4(n-1)(m-1)`` springs down. At 6x6: 85 + 56 + 33 in-layer and 100 + 64 between layers = 338
springs. Masses on the edge of every layer are fixed, and all of layer 3 is fixed: at 6x6, 25
of the 77 masses are free.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from skinhil.errors import ConfigError

MeshSize = tuple[int, int]
"""Top-layer size ``(rows, cols)`` in masses."""

PAPER_SIZE: MeshSize = (6, 6)
"""The paper's top layer: 6x6 masses (77 masses, 338 springs in all)."""
MIN_SIDE = 3
"""Smallest rows or cols of the top layer (layer 3 is then one row or column of masses)."""

LAYER_SIZES: tuple[int, int, int] = (6, 5, 4)
"""Grid side of layers 1, 2, 3 of the paper's mesh."""


def check_size(size: object) -> MeshSize:
    """``size`` as a ``(rows, cols)`` tuple of ints >= 3, or :class:`ConfigError`."""
    try:
        sides: list[object] = list(size)  # type: ignore[call-overload]
    except TypeError:
        sides = []
    if len(sides) != 2:
        raise ConfigError(f"mesh size must be (rows, cols) of the top layer, got {size!r}")
    out = []
    for side in sides:
        if not (isinstance(side, int | np.integer) and not isinstance(side, bool)
                and side >= MIN_SIDE):
            raise ConfigError(f"mesh size {size!r}: rows and cols must be whole numbers >= "
                              f"{MIN_SIDE} (the top layer of a 3-layer pyramid)")
        out.append(int(side))
    return out[0], out[1]


def parse_size(text: str) -> MeshSize:
    """``"16x16"`` (or ``"16"``) → ``(16, 16)``; :class:`ConfigError` for anything else."""
    match = re.fullmatch(r"\s*(\d+)\s*(?:[xX×]\s*(\d+))?\s*", text)
    if match is None:
        raise ConfigError(f"mesh size {text!r} is not ROWSxCOLS (e.g. 6x6 or 16x16)")
    rows = int(match.group(1))
    return check_size((rows, int(match.group(2) or rows)))


def format_size(size: MeshSize) -> str:
    """``(16, 16)`` → ``"16x16"``."""
    return f"{size[0]}x{size[1]}"


def layer_shapes(size: MeshSize = PAPER_SIZE) -> tuple[MeshSize, MeshSize, MeshSize]:
    """``(rows, cols)`` of layers 1, 2, 3 under the pyramid rule."""
    rows, cols = check_size(size)
    return (rows, cols), (rows - 1, cols - 1), (rows - 2, cols - 2)


def mass_count(size: MeshSize = PAPER_SIZE) -> int:
    """Number of masses of the mesh (77 at 6x6)."""
    return sum(r * c for r, c in layer_shapes(size))


def spring_count(size: MeshSize = PAPER_SIZE) -> int:
    """Number of springs, i.e. sensors (338 at 6x6)."""
    shapes = layer_shapes(size)
    in_layer = sum(r * (c - 1) + (r - 1) * c + (r - 1) * (c - 1) for r, c in shapes)
    return in_layer + 4 * sum(r * c for r, c in shapes[1:])


N_MASSES = mass_count(PAPER_SIZE)
"""Masses of the paper's mesh (77)."""
N_SPRINGS = spring_count(PAPER_SIZE)
"""Springs of the paper's mesh (338)."""


def mass_index(layer: int, row: int, col: int, size: MeshSize = PAPER_SIZE) -> int:
    """0-based index of the mass at 0-based ``layer``, ``row``, ``col``."""
    shapes = layer_shapes(size)
    offset = sum(r * c for r, c in shapes[:layer])
    return offset + row * shapes[layer][1] + col


def mass_position(index: int, size: MeshSize = PAPER_SIZE) -> tuple[int, int, int]:
    """0-based ``(layer, row, col)`` of the 0-based mass ``index`` (inverse of mass_index)."""
    if not 0 <= index < mass_count(size):
        raise ConfigError(f"mass M{index + 1} does not exist on a {format_size(size)} skin "
                          f"(M1..M{mass_count(size)})")
    for layer, (rows, cols) in enumerate(layer_shapes(size)):
        if index < rows * cols:
            return layer, index // cols, index % cols
        index -= rows * cols
    raise AssertionError("unreachable")  # pragma: no cover


@dataclass(frozen=True)
class Mesh:
    """The mesh geometry: rest positions (m), springs (0-based mass pairs), fixed masses."""

    positions: np.ndarray
    """(n_masses, 3) rest positions in metres."""
    springs: np.ndarray
    """(n_springs, 2) int64 0-based mass indices (index i is M(i+1))."""
    fixed: np.ndarray
    """(n_masses,) bool, True where the mass is held fixed."""
    layer_of_spring: np.ndarray
    """(n_springs,) int: 1, 2, 3 for in-layer springs, 12 or 23 for springs between layers."""
    size: MeshSize = PAPER_SIZE
    """Top-layer ``(rows, cols)``."""

    @property
    def free(self) -> np.ndarray:
        """0-based indices of the free masses, ascending (25 of them at 6x6)."""
        return np.flatnonzero(~self.fixed)


def sensor_positions(mesh: Mesh) -> np.ndarray:
    """(n_springs, 3) rest position (m) of each sensor: the midpoint of its spring; x to the
    right and y up on the skin, 0 at its centre; z 0 at the top layer, negative below."""
    return 0.5 * (mesh.positions[mesh.springs[:, 0]] + mesh.positions[mesh.springs[:, 1]])


def sensor_label(mesh: Mesh, address: int) -> str:
    """``S12 M8-M9``: the sensor's address and the 1-based numbers of its spring's masses."""
    i, j = mesh.springs[address]
    return f"S{address} M{int(i) + 1}-M{int(j) + 1}"


def build_mesh(spacing_m: float, layer_gap_m: float, size: MeshSize = PAPER_SIZE) -> Mesh:
    """The mesh of top-layer ``size`` with lateral ``spacing_m`` and vertical ``layer_gap_m``
    (m)."""
    shapes = layer_shapes(size)
    offsets = np.cumsum([0] + [r * c for r, c in shapes])
    positions = np.zeros((int(offsets[-1]), 3))
    fixed = np.zeros(int(offsets[-1]), dtype=bool)
    grids = []
    springs: list[np.ndarray] = []
    kinds: list[np.ndarray] = []
    for layer, (rows, cols) in enumerate(shapes):
        grid = offsets[layer] + np.arange(rows * cols).reshape(rows, cols)
        grids.append(grid)
        r, c = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
        positions[grid] = np.stack([(c - (cols - 1) / 2.0) * spacing_m,
                                    ((rows - 1) / 2.0 - r) * spacing_m,
                                    np.full(r.shape, -layer * layer_gap_m)], axis=-1)
        fixed[grid] = (layer == 2) | (r == 0) | (r == rows - 1) | (c == 0) | (c == cols - 1)
        for a, b in ((grid[:, :-1], grid[:, 1:]), (grid[:-1, :], grid[1:, :]),
                     (grid[:-1, 1:], grid[1:, :-1])):
            springs.append(np.stack([a.ravel(), b.ravel()], axis=1))
            kinds.append(np.full(a.size, layer + 1))
    for upper in (0, 1):
        top, low = grids[upper], grids[upper + 1]
        corners = (top[:-1, :-1], top[:-1, 1:], top[1:, :-1], top[1:, 1:])
        pairs = np.stack([np.repeat(low.ravel(), 4),
                          np.stack([k.ravel() for k in corners], axis=1).ravel()], axis=1)
        springs.append(pairs)
        kinds.append(np.full(len(pairs), 12 if upper == 0 else 23))
    spring_arr = np.ascontiguousarray(np.concatenate(springs).astype(np.int64))
    return Mesh(positions=positions, springs=spring_arr, fixed=fixed,
                layer_of_spring=np.concatenate(kinds).astype(np.int64), size=shapes[0])
