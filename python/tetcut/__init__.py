"""tetcut: exact cutting of deformable tetrahedral meshes, over numpy arrays.

Meshes are arrays: vertices ``V`` float64 ``(n, 3)``, tets ``T`` int32 ``(m, 4)``, triangles
``F`` int32 ``(k, 3)``, C-contiguous. A wrong dtype is a TypeError, a wrong shape or layout a
ValueError; what the library refuses (a NaN, an inverted tet, a malformed file) is a
:class:`tetcut.Error` with ``kind``, ``message``, ``file`` and ``line``.

    import tetcut
    V, T = tetcut.make_grid((0, 0, 0), (1, 1, 1), (4, 4, 4))
    cutter = tetcut.Cutter(V, T)
    blade_back, blade_tip = numpy.array([[0.5, -1, -1], [0.5, -1, 2]]), numpy.array([[0.5, 2, -1], [0.5, 2, 2]])
    cutter.cut(*tetcut.swept_blade(blade_back, blade_tip))   # a blade swept down through x = 0.5
    print(cutter.result().num_pieces)                        # 2
"""

import numpy as _numpy

from . import _tetcut
from ._tetcut import (  # noqa: F401  (the public API)
    Cutter,
    CutBatchReport,
    CutResult,
    EmbedReport,
    Error,
    MaterialSurface,
    MeshQuality,
    Scene,
    Session,
    SessionStep,
    SurfaceCheck,
    SurfaceStats,
    SurfaceIntersections,
    check_surface,
    count_surface_intersections,
    embed,
    embedding_lattice,
    load_scene,
    make_bcc,
    make_grid,
    measure_quality,
    measure_surface,
    parse_scene,
    read_series,
    read_surface,
    read_tet_mesh,
    spacing_for_cubes,
    swept_blade,
    write_recording,
    write_series,
    write_surface,
    write_tet_mesh,
)
from . import sim  # noqa: F401

__version__ = "0.1.0"

_CELL_TYPES = {4: "tetra", 3: "triangle"}


def to_meshio(V, cells, cell_data=None, point_data=None):
    """A ``meshio.Mesh`` of vertices ``V`` and tets ``(m, 4)`` or triangles ``(k, 3)``.

    ``cell_data``: ``{name: values (m,)}``, ``point_data``: ``{name: values (n, ...)}``.
    """
    import meshio

    cells = _numpy.asarray(cells)
    if cells.ndim != 2 or cells.shape[1] not in _CELL_TYPES:
        raise ValueError(f"cells must have shape (m, 4) (tets) or (k, 3) (triangles), not {cells.shape}")
    kind = _CELL_TYPES[cells.shape[1]]
    return meshio.Mesh(
        _numpy.asarray(V, dtype=_numpy.float64),
        [(kind, cells)],
        cell_data={name: [_numpy.asarray(values)] for name, values in (cell_data or {}).items()},
        point_data=dict(point_data or {}),
    )


def from_meshio(mesh, cell_type=None):
    """``(V float64 (n, 3), cells int32)`` from a ``meshio.Mesh``: its tets (``"tetra"``), or its
    triangles when it has no tets or ``cell_type="triangle"``. Blocks of that type are joined."""
    if cell_type is None:
        cell_type = "tetra" if any(block.type == "tetra" for block in mesh.cells) else "triangle"
    if cell_type not in _CELL_TYPES.values():
        raise ValueError(f"cell_type must be 'tetra' or 'triangle', not {cell_type!r}")
    blocks = [block.data for block in mesh.cells if block.type == cell_type]
    if not blocks:
        raise ValueError(f"the mesh has no {cell_type} cells (it has {sorted({b.type for b in mesh.cells})})")
    points = _numpy.ascontiguousarray(mesh.points, dtype=_numpy.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"the mesh's points must be 3D, not of shape {points.shape}")
    cells = _numpy.concatenate(blocks)
    if cells.size and (cells.min() < 0 or cells.max() >= len(points)):
        raise ValueError("the mesh's cells name points it does not have")
    return points, _numpy.ascontiguousarray(cells, dtype=_numpy.int32)
