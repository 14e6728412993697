"""A docutils table from a header and rows of text: the generated reference pages' tables."""

from __future__ import annotations

from docutils import nodes


def table(header: list[str], rows: list[list[str]]) -> nodes.table:
    """A table node: ``header`` as its head row, ``rows`` as its body, every cell text."""
    table = nodes.table()
    group = nodes.tgroup(cols=len(header))
    table += group
    for _ in header:
        group += nodes.colspec(colwidth=1)
    head = nodes.thead()
    group += head
    body = nodes.tbody()
    group += body
    for cells, parent in [(header, head)] + [(r, body) for r in rows]:
        row = nodes.row()
        for cell in cells:
            entry = nodes.entry()
            entry += nodes.paragraph(text=cell)
            row += entry
        parent += row
    return table
