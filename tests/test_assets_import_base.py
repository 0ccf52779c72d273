"""`rik assets import --base-unit`: a GLB with named nodes plus a YAML mapping becomes a base unit whose rigid
parts are the user's meshes, each decomposed with CoACD. The test builds and exports its own GLB."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from test_assets_import import _files, _flat

W, H, D, T = 0.40, 0.30, 0.30, 0.018  # carcass width, height, depth, board thickness (m)


def _boards(boxes):
    return trimesh.boolean.union([trimesh.creation.box(bounds=b) for b in boxes], engine="manifold")


@pytest.fixture(scope="module")
def glb(tmp_path_factory):
    """A one-drawer cabinet modelled glTF-style: +y up, +z out of the front, millimetres."""
    w, h, d, t = W / 2, H, D, T
    # built in rik's frame (y out of the front, z up, x = y cross z), then turned into glTF's axes (y up, z out
    # of the front): a proper rotation, x_glTF = -x_rik
    carcass = _boards([[[-w, -d, 0], [-w + t, 0, h]], [[w - t, -d, 0], [w, 0, h]], [[-w + t, -d, 0], [w - t, 0, t]],
                       [[-w + t, -d, h - t], [w - t, 0, h]], [[-w + t, -d, t], [w - t, -d + 0.006, h - t]]])
    drawer = _boards([[[-w + 0.002, 0.002, 0.002], [w - 0.002, 0.002 + T, h - 0.002]],  # front panel
                      [[-w + t + 0.005, -0.25, 0.03], [w - t - 0.005, 0.002, 0.04]],  # box bottom
                      [[-w + t + 0.005, -0.25, 0.03], [-w + t + 0.017, 0.002, 0.2]],
                      [[w - t - 0.017, -0.25, 0.03], [w - t - 0.005, 0.002, 0.2]]])
    to_gltf = np.array([[-1, 0, 0, 0], [0, 0, 1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], float)  # rik (x,y,z) -> glTF
    scene = trimesh.Scene()
    for name, mesh in (("Carcass", carcass), ("Drawer", drawer)):
        m = mesh.copy()
        m.apply_transform(to_gltf)
        m.apply_scale(1000)
        m.apply_translation([500, 0, 0])  # not centred in the file
        scene.add_geometry(m, node_name=name, geom_name=f"{name}-mesh")
    path = tmp_path_factory.mktemp("glb") / "cabinet.glb"
    scene.export(path)
    return path


MAPPING = """\
units: mm
up: +y
front: +z
carcass: {node: Carcass, finish: wood/oak}
fronts:
  - id: drawer
    node: Drawer
    kind: drawer
    finish: lacquer/white
    joint: {type: slide, range: [0, 0.2]}
"""


@pytest.mark.slow  # a build, recording or render end to end: out of the everyday tier
def test_import_base_unit_from_glb(rik, glb, tmp_path):
    (tmp_path / "parts.yaml").write_text(MAPPING)
    out = tmp_path / "cat"
    r = rik("assets", "import", str(glb), "--base-unit", "--parts", str(tmp_path / "parts.yaml"), "--id",
            "drawer/my-cabinet", "--catalog-dir", str(out))
    assert r.code == 0, r.err
    flat = _flat(r.out)
    assert "registered drawer/my-cabinet" in flat
    assert "carcass 400 x 300 x 300 mm (w x h x d), fronts: drawer (drawer, slide)" in flat
    from rik.registry.load import load_catalog

    unit = load_catalog([out]).base_units["drawer/my-cabinet"]
    front = unit.fronts[0]
    assert front.size == pytest.approx((W - 0.004, H - 0.004, T), abs=1e-4)
    assert front.center == pytest.approx((0.0, 0.002 + T / 2, H / 2), abs=1e-4)
    assert front.joint.axis == (0.0, 1.0, 0.0)
    assert sorted(unit.meshes) == ["carcass", "drawer"]
    from rik.assets.build import build_asset

    asset, _ = build_asset(load_catalog([out]), "drawer/my-cabinet")
    assert [p.name for p in asset.parts] == ["carcass", "drawer"]
    assert all(p.method == "coacd" and len(p.hulls) >= 4 for p in asset.parts)  # open box, drawer: never one hull


def test_a_missing_node_names_the_mapping_field_and_lists_the_nodes(rik, glb, tmp_path):
    (tmp_path / "parts.yaml").write_text(MAPPING.replace("node: Drawer", "node: Drawr"))
    out = tmp_path / "cat"
    r = rik("assets", "import", str(glb), "--base-unit", "--parts", str(tmp_path / "parts.yaml"), "--id",
            "drawer/my-cabinet", "--catalog-dir", str(out))
    assert r.code == 2
    assert "parts.yaml, field 'fronts.0.node': no node 'Drawr' in" in _flat(r.err)
    assert "cabinet.glb; its nodes are: Carcass, Drawer" in _flat(r.err)
    assert _files(out) == []


def test_a_bad_mapping_field_names_file_line_and_field(rik, glb, tmp_path):
    (tmp_path / "parts.yaml").write_text(MAPPING.replace("type: slide", "type: slider"))
    r = rik("assets", "import", str(glb), "--base-unit", "--parts", str(tmp_path / "parts.yaml"), "--id",
            "drawer/my-cabinet", "--catalog-dir", str(tmp_path / "cat"))
    assert r.code == 2
    assert "parts.yaml:10, field 'fronts.0.joint.type': input should be 'slide' or 'hinge' (got 'slider')" in _flat(
        r.err)


def test_base_unit_needs_its_mapping(rik, glb, tmp_path):
    r = rik("assets", "import", str(glb), "--base-unit", "--id", "drawer/my-cabinet")
    assert r.code == 2
    assert "--base-unit needs --parts PARTS.yaml" in _flat(r.err)


def test_a_base_unit_over_the_face_limit_is_refused_before_anything_is_written(rik, glb, tmp_path):
    (tmp_path / "parts.yaml").write_text(MAPPING)
    out = tmp_path / "cat"
    r = rik("assets", "import", str(glb), "--base-unit", "--parts", str(tmp_path / "parts.yaml"), "--id",
            "drawer/my-cabinet", "--catalog-dir", str(out), "--max-faces", "10")
    assert r.code == 2
    assert "cabinet.glb: the mesh has" in _flat(r.err)
    assert "triangles, more than the limit of 10; simplify it, or raise the limit with --max-faces" in _flat(r.err)
    assert _files(out) == []
