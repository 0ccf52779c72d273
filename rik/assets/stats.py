"""Mesh statistics of paper Figure 3: vertex count, face count, mean edge length and mean face area."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import trimesh


@dataclass(frozen=True)
class MeshStats:
    vertices: int
    faces: int
    mean_edge_mm: float
    mean_face_area_mm2: float
    watertight: bool

    @classmethod
    def of(cls, mesh: trimesh.Trimesh) -> MeshStats:
        return cls(len(mesh.vertices), len(mesh.faces), float(mesh.edges_unique_length.mean()) * 1e3,
                   float(mesh.area_faces.mean()) * 1e6, bool(mesh.is_watertight))
