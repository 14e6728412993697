"""The mesh matches the paper: counts, numbering, the M6–M11 diagonal, the pyramids."""

import numpy as np

from skinhil import SkinModel


def _pairs(model: SkinModel) -> set[frozenset[int]]:
    # paper numbers, 1-based
    return {frozenset((int(i) + 1, int(j) + 1)) for i, j in model.springs}


def test_counts() -> None:
    m = SkinModel()
    assert m.springs.shape == (338, 2)
    assert m.positions.shape == (77, 3)
    assert int((~m.fixed).sum()) == 25
    assert len(_pairs(m)) == 338  # no duplicates
    kinds = m.mesh.layer_of_spring
    assert [int((kinds == k).sum()) for k in (1, 2, 3, 12, 23)] == [85, 56, 33, 100, 64]


def test_numbering_and_fixed() -> None:
    m = SkinModel()
    # M15 is row 3, column 3 of layer 1: two spacings right of M13, two below M3
    x, y, z = m.positions[14]
    assert np.isclose(x, m.positions[12, 0] + 2e-3) and np.isclose(y, m.positions[2, 1] - 2e-3)
    assert z == 0.0
    free = set(np.flatnonzero(~m.fixed) + 1)
    layer1_free = {r * 6 + c + 1 for r in range(1, 5) for c in range(1, 5)}
    layer2_free = {36 + r * 5 + c + 1 for r in range(1, 4) for c in range(1, 4)}
    assert free == layer1_free | layer2_free
    assert all(m.fixed[61:77])


def test_diagonal_runs_like_m6_m11() -> None:
    pairs = _pairs(SkinModel())
    assert frozenset((6, 11)) in pairs and frozenset((5, 12)) not in pairs
    # every cell of layer 1 has the top-right to bottom-left diagonal, none the other one
    for r in range(5):
        for c in range(5):
            tl = r * 6 + c + 1
            assert frozenset((tl + 1, tl + 6)) in pairs
            assert frozenset((tl, tl + 7)) not in pairs


def test_pyramids() -> None:
    m = SkinModel()
    pairs = _pairs(m)
    # M37 (layer 2, row 1, col 1) sits under the cell M1, M2, M7, M8
    for top in (1, 2, 7, 8):
        assert frozenset((37, top)) in pairs
    np.testing.assert_allclose(m.positions[36, :2], m.positions[[0, 1, 6, 7], :2].mean(axis=0))
    # M62 (layer 3, row 1, col 1) sits under M37, M38, M42, M43
    for top in (37, 38, 42, 43):
        assert frozenset((62, top)) in pairs
    assert m.positions[61, 2] < m.positions[36, 2] < m.positions[0, 2]
