"""The draws' side of the living scene: each draw record's model and normal matrix, world box
and centre, kept as arrays and brought up to date only where something changed.

`SceneState` (vkpbr.scene.state) says which draws a change touched (the subtrees of the
nodes set since the last frame, and the deformed draws whose joints or weights moved);
`DrawTable.update` recomputes those rows alone, once per frame: the model matrices (the
node's world matrix, an instance matrix below it, a deformed draw's frame), the GPU's
Instances records (model + normal matrix, float32, column-major: layouts.STORAGE), the
world boxes the scene's bounds are the union of, and the centres the blended draws are
sorted by. A frame slot then copies the records of the draws changed since it last held
them (render/scene_state.py): moving 100 of 10,000 nodes costs 100 rows, not 10,000.
"""

from __future__ import annotations

import numpy as np

__all__ = ["DrawTable", "normal_matrices", "std140_pairs", "determinants", "blocks"]

# Rows per block of the per-draw arithmetic: a block's (B, 4, 4) arrays stay in the CPU's
# cache across the dozens of strided passes a block takes (4-10x faster for 10,000 draws
# than whole-array passes, which stream 1.3 MB from memory each).
BLOCK = 2048


def blocks(n: int) -> list[slice]:
    """Slices of `n` rows, BLOCK at a time."""
    return [slice(i, min(i + BLOCK, n)) for i in range(0, n, BLOCK)]


def _cofactors(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cofactor matrices and determinants of (..., 3, 3) matrices (inverse transpose =
    cofactors / determinant): a few vector operations for any number of matrices, where
    np.linalg.inv loops in LAPACK. Read straight from the strided components: callers pass
    cache-sized blocks (BLOCK), where that beats a transposing copy several times."""
    cof = np.empty((3, 3, *a.shape[:-2]), a.dtype)
    for i in range(3):
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            np.subtract(a[..., i1, j1] * a[..., i2, j2], a[..., i1, j2] * a[..., i2, j1], out=cof[i, j])
    det = a[..., 0, 0] * cof[0, 0] + a[..., 0, 1] * cof[0, 1] + a[..., 0, 2] * cof[0, 2]
    return cof, det  # cof[row][column][...]


def determinant_of_parts(a00: np.ndarray, a01: np.ndarray, a02: np.ndarray,
                         a10: np.ndarray, a11: np.ndarray, a12: np.ndarray,
                         a20: np.ndarray, a21: np.ndarray, a22: np.ndarray) -> np.ndarray:
    """det of 3x3 matrices given as their nine parts (arrays alike): cofactors of row 0."""
    return (a00 * (a11 * a22 - a12 * a21) - a01 * (a10 * a22 - a12 * a20)
            + a02 * (a10 * a21 - a11 * a20))


def determinants(a: np.ndarray) -> np.ndarray:
    """det of (N, 3, 3) matrices, a block at a time."""
    out = np.empty(len(a))
    for b in blocks(len(a)):
        m = a[b]
        out[b] = determinant_of_parts(*(m[:, i, j] for i in range(3) for j in range(3)))
    return out


def normal_matrices(model: np.ndarray) -> np.ndarray:
    """(..., 4, 4) normal matrices (the inverse transpose of the 3x3 part) of model
    matrices; a singular one (a hidden draw's zero matrix) keeps its 3x3 part."""
    a = model[..., :3, :3]
    cof, det = _cofactors(a)
    ok = np.abs(det) > 1e-30
    scale = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    out = np.zeros_like(model)
    out[..., :3, :3] = np.moveaxis(cof * scale, (0, 1), (-2, -1))
    if not ok.all():
        out[~ok, :3, :3] = a[~ok]
    out[..., 3, 3] = 1.0
    return out


def std140_pairs(model: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """(D, 2, 4, 4) float32: each model matrix and its normal matrix as GLSL's column-major
    mat4 (Instances records: layouts.STORAGE), into `out` when given."""
    out = np.empty((len(model), 2, 4, 4), np.float32) if out is None else out
    out[:, 0] = np.swapaxes(model, -1, -2)
    cof, det = _cofactors(model[:, :3, :3])
    ok = np.abs(det) > 1e-30
    # Column-major N = cof / det: out[d, 1, column j, row i] = cof[i, j, d] / det[d].
    out[:, 1, :3, :3] = np.transpose(cof / np.where(ok, det, np.inf), (2, 1, 0))
    if not ok.all():  # a singular one (a hidden draw's zero matrix) keeps its 3x3 part
        out[~ok, 1, :3, :3] = np.swapaxes(model[~ok, :3, :3], -1, -2)
    out[:, 1, :3, 3] = 0.0
    out[:, 1, 3] = (0.0, 0.0, 0.0, 1.0)
    return out


class DrawTable:
    """D draw records' models, Instances records, world boxes and centres.

    mesh_boxes : (D, 2, 3) each draw's mesh bounds (min, max) in its own (model) space.
    rest : (D, 4, 4) the models as loaded: the table starts from them, so an unchanged scene
        renders bit for bit as it was loaded.
    """

    def __init__(self, mesh_boxes: np.ndarray, rest: np.ndarray) -> None:
        self.mesh_boxes = np.asarray(mesh_boxes, np.float64).reshape(-1, 2, 3)
        self.models = np.array(rest, np.float64).reshape(-1, 4, 4)
        self.records = std140_pairs(self.models)
        self._mesh_centre = self.mesh_boxes.mean(axis=1)
        self._mesh_half = (self.mesh_boxes[:, 1] - self.mesh_boxes[:, 0]) / 2
        self.lo = np.empty((len(self.models), 3))  # world boxes (min, max); empty: hidden
        self.hi = np.empty((len(self.models), 3))
        self.centers = np.empty((len(self.models), 3))
        self._place(slice(None), self.models)

    def __len__(self) -> int:
        return len(self.models)

    def grow(self, mesh_boxes: np.ndarray) -> None:
        """Rows for new draws with these mesh boxes, hidden (zero models) until updated."""
        n = len(mesh_boxes)
        self.mesh_boxes = np.concatenate([self.mesh_boxes, mesh_boxes])
        self._mesh_centre = self.mesh_boxes.mean(axis=1)
        self._mesh_half = (self.mesh_boxes[:, 1] - self.mesh_boxes[:, 0]) / 2
        self.models = np.concatenate([self.models, np.zeros((n, 4, 4))])
        self.records = np.concatenate([self.records, std140_pairs(np.zeros((n, 4, 4)))])
        self.centers = np.concatenate([self.centers, np.zeros((n, 3))])
        self.lo = np.concatenate([self.lo, np.full((n, 3), np.inf)])
        self.hi = np.concatenate([self.hi, np.full((n, 3), -np.inf)])

    def update(self, rows: np.ndarray | slice, models: np.ndarray) -> None:
        """Rows `rows` (indices, or a slice of consecutive ones) take `models` ((R, 4, 4),
        zero for a hidden draw): their records, boxes and centres follow."""
        self.models[rows] = models
        first = (rows.start or 0) if isinstance(rows, slice) else 0
        for b in blocks(len(models)):
            if isinstance(rows, slice):  # (a run of rows: written in place)
                at = slice(first + b.start, first + b.stop)
                std140_pairs(models[b], self.records[at])
                self._place(at, models[b])
            else:
                self.records[rows[b]] = std140_pairs(models[b])
                self._place(rows[b], models[b])

    def _place(self, rows: np.ndarray | slice, m: np.ndarray) -> None:
        """World centres and boxes of rows `rows`: centre = M c + t, half size = |M| h
        (the mesh box's centre c and half size h)."""
        a = np.ascontiguousarray(m[:, :3, :3])  # (strided einsums cost several times more)
        centre = np.einsum("dij,dj->di", a, self._mesh_centre[rows]) + m[:, :3, 3]
        self.centers[rows] = centre
        hidden = ~a.reshape(-1, 9).any(axis=1)
        np.abs(a, out=a)
        half = np.einsum("dij,dj->di", a, self._mesh_half[rows])
        if hidden.any():
            centre[hidden], half[hidden] = 0.0, -np.inf  # an empty box
        self.lo[rows], self.hi[rows] = centre - half, centre + half

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """World bounds (min, max) of the shown draws; zeros when nothing is shown."""
        if not len(self.lo):
            return np.zeros(3), np.zeros(3)
        # Column by column: NumPy's axis-0 reduction of (D, 3) runs 3-wide inner loops (30x).
        lo = np.array([self.lo[:, k].min() for k in range(3)])
        hi = np.array([self.hi[:, k].max() for k in range(3)])
        if not np.all(lo <= hi):
            return np.zeros(3), np.zeros(3)
        return lo, hi
