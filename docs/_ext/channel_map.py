"""Sphinx directive ``skinhil-channel-map``: the table of the default skin's sensors, wire
address → spring (its two masses), layer and rest position x, y, z (mm), computed at build
time from :class:`skinhil.SkinModel`'s mesh and :func:`skinhil.model.geometry.sensor_positions`
so it is the map the board streams."""

from __future__ import annotations

from doc_tables import table
from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.application import Sphinx

LAYERS = {1: "1", 2: "2", 3: "3", 12: "1–2", 23: "2–3"}
"""``Mesh.layer_of_spring`` codes: the layer a spring lies in, or the two it joins."""


class ChannelMap(Directive):
    """``.. skinhil-channel-map::``: one row per sensor of the default 6x6 skin."""

    has_content = False

    def run(self) -> list[nodes.Node]:
        from skinhil import SkinModel
        from skinhil.model.geometry import sensor_positions

        mesh = SkinModel().mesh
        where = sensor_positions(mesh) * 1e3
        rows = [[str(a), f"M{int(i) + 1}–M{int(j) + 1}",
                 LAYERS.get(int(mesh.layer_of_spring[a]), "?"),
                 f"{where[a, 0]:.2f}", f"{where[a, 1]:.2f}", f"{where[a, 2]:.2f}"]
                for a, (i, j) in enumerate(mesh.springs)]
        return [table(["address", "spring", "layer", "x (mm)", "y (mm)", "z (mm)"], rows)]


def setup(app: Sphinx) -> dict[str, object]:
    app.add_directive("skinhil-channel-map", ChannelMap)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
