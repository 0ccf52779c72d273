"""`rik assets import` and the assets CLI's bad-input messages. The tests build and export their own meshes."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from test_assets_core import _bar_pull

pytestmark = pytest.mark.slow  # end-to-end runs: out of the everyday tier (-m "not slow")


@pytest.fixture(scope="module")
def bar_files(tmp_path_factory):
    d = tmp_path_factory.mktemp("meshes")
    mesh, _ = _bar_pull()
    mesh.export(d / "bar_m.stl")
    mm = mesh.copy()
    mm.apply_scale(1000)
    mm.export(d / "bar_mm.glb")
    # the file's up axis is y (as glTF tools write): out of the front is +y
    y_up = mesh.copy()
    y_up.apply_transform(trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0]))
    y_up.export(d / "bar_yup.obj")
    return d


def _flat(text: str) -> str:
    """Output with rich's line wrapping undone."""
    return " ".join(text.split())


def _files(path):
    return sorted(p.relative_to(path).as_posix() for p in path.rglob("*") if p.is_file()) if path.exists() else []


def test_import_registers_a_handle_that_builds_and_passes_the_finger_test(rik, bar_files, tmp_path):
    out = tmp_path / "cat"
    r = rik("assets", "import", str(bar_files / "bar_mm.glb"), "--handle", "--type", "two_point", "--id",
            "two_point/my-bar", "--hole-spacing", "0.128", "--units", "mm", "--catalog-dir", str(out))
    assert r.code == 0, r.err
    assert "registered two_point/my-bar-128" in _flat(r.out)
    assert "168.0 x 12.0 mm, projection 35.0 mm, clearance 23.0 x 116.0 mm" in _flat(r.out)
    assert "finger test: a 10 mm finger passes through the loop" in _flat(r.out)
    assert (out / "pictures" / "two_point__my-bar-128" / "fidelity.png").is_file()
    from rik.registry.load import load_catalog

    cat = load_catalog([out])
    handle = cat.handles["two_point/my-bar-128"]
    assert handle.geometry.hole_spacing == 0.128 and handle.mount.kind == "two_screw"
    assert cat.designs["two_point/my-bar"].provenance.origin == "user_mesh"
    # the catalog lists it like any other handle
    listed = rik("catalog", "list", "--type", "two_point", "--catalog", str(out), "--format", "json")
    assert "two_point/my-bar-128" in _flat(listed.out)


def test_import_normalises_the_frame(rik, bar_files, tmp_path):
    out = tmp_path / "cat"
    r = rik("assets", "import", str(bar_files / "bar_yup.obj"), "--type", "two_point", "--id", "two_point/y-up",
            "--hole-spacing", "0.128", "--out", "+y", "--catalog-dir", str(out))
    assert r.code == 0, r.err
    assert "168.0 x 12.0 mm, projection 35.0 mm" in _flat(r.out)


def test_a_mesh_in_millimetres_is_refused_and_nothing_is_written(rik, bar_files, tmp_path):
    out = tmp_path / "cat"
    r = rik("assets", "import", str(bar_files / "bar_mm.glb"), "--type", "two_point", "--id", "two_point/my-bar",
            "--hole-spacing", "0.128", "--catalog-dir", str(out))
    assert r.code == 2
    assert _flat(r.err).endswith("bar_mm.glb: the mesh is 168 units long, more than a two_point handle can be "
                                  "(1.2 m); it looks like millimetres: pass --units mm (or cm, in)")
    assert "Traceback" not in _flat(r.err)
    assert _files(out) == []


def test_unknown_file_type(rik, tmp_path):
    (tmp_path / "handle.xyz").write_text("1 2 3\n")
    r = rik("assets", "import", str(tmp_path / "handle.xyz"), "--type", "knob", "--id", "knob/mine",
            "--catalog-dir", str(tmp_path / "cat"))
    assert r.code == 2
    assert "handle.xyz: unknown mesh file type '.xyz'; rik reads .stl, .obj, .ply, .off, .glb, .gltf" in _flat(r.err)


def test_empty_mesh(rik, tmp_path):
    (tmp_path / "empty.obj").write_text("# nothing here\nv 0 0 0\n")
    r = rik("assets", "import", str(tmp_path / "empty.obj"), "--type", "knob", "--id", "knob/mine",
            "--catalog-dir", str(tmp_path / "cat"))
    assert r.code == 2
    assert "empty.obj: the mesh is empty (no triangles)" in _flat(r.err)


def test_open_mesh(rik, tmp_path):
    sheet = trimesh.creation.box(extents=[0.03, 0.03, 0.02])
    sheet.update_faces(sheet.face_normals[:, 2] < 0.5)  # drop the top: an open cup
    sheet = sheet.subdivide().subdivide()
    sheet.export(tmp_path / "cup.stl")
    r = rik("assets", "import", str(tmp_path / "cup.stl"), "--type", "knob", "--id", "knob/mine",
            "--catalog-dir", str(tmp_path / "cat"))
    assert r.code == 2
    assert "cup.stl: the mesh is not a closed solid after cleaning" in _flat(r.err)
    assert "rik needs a watertight, manifold mesh; close it in a mesh editor" in _flat(r.err)
    assert _files(tmp_path / "cat") == []


def test_importing_the_same_design_twice_is_refused(rik, bar_files, tmp_path):
    out = tmp_path / "cat"
    args = ("assets", "import", str(bar_files / "bar_m.stl"), "--type", "two_point", "--id", "two_point/twice",
            "--hole-spacing", "0.128", "--catalog-dir", str(out))
    assert rik(*args).code == 0
    before = {p: (out / p).read_bytes() for p in _files(out)}
    r = rik(*args)
    assert r.code == 2
    assert "two_point__twice.yaml already exists: design two_point/twice was imported before" in _flat(r.err)
    assert {p: (out / p).read_bytes() for p in _files(out)} == before


def test_a_changed_mesh_file_is_detected(rik, bar_files, tmp_path):
    out = tmp_path / "cat"
    assert rik("assets", "import", str(bar_files / "bar_m.stl"), "--type", "two_point", "--id", "two_point/edited",
               "--hole-spacing", "0.128", "--catalog-dir", str(out)).code == 0
    mesh_file = out / "meshes" / "two_point__edited.stl"
    mesh = trimesh.load(mesh_file)
    mesh.apply_scale(1.01)
    mesh.export(mesh_file)
    r = rik("assets", "build", "two_point/edited-128", "--catalog", str(out), "--seed", "7")
    assert r.code == 2
    assert "two_point__edited.stl: the mesh file changed since it was imported (sha256 differs from " \
           "generator.sha256); import it again" in _flat(r.err)


def test_a_generator_parameter_out_of_range_names_file_entry_and_field(rik, tmp_path):
    overlay = tmp_path / "knob.yaml"
    overlay.write_text(
        "designs:\n"
        "  - id: knob/too-thick\n    type: knob\n    subtype: mushroom\n    name: Too thick\n"
        "    generator: {name: knob_lathe, profile: mushroom, neck_ratio: 1.5, head_ratio: 0.5}\n"
        "    provenance: {origin: parametric, reference: test}\n")
    r = rik("assets", "build", "knob/mushroom-30", "--catalog", str(overlay))
    assert r.code == 2
    assert "knob.yaml:6, entry designs[0] 'knob/too-thick', field 'generator.knob_lathe.neck_ratio'" in _flat(r.err)


def test_a_missing_mesh_file_of_an_imported_design(rik, tmp_path):
    overlay = tmp_path / "mine.yaml"
    overlay.write_text(
        "designs:\n"
        "  - id: knob/lost\n    type: knob\n    subtype: imported\n    name: Lost\n"
        f"    generator: {{name: user_mesh, file: meshes/lost.stl, sha256: '{'0' * 64}'}}\n"
        "    provenance: {origin: user_mesh, reference: test}\n"
        "handles:\n"
        "  - id: knob/lost-30\n    design: knob/lost\n    size: '30'\n    finish: metal/stainless\n"
        "    geometry: {length: 0.03, width: 0.03, projection: 0.025, grip_diameter: 0.03}\n"
        "    mount: {kind: single_screw}\n    mass: 0.03\n    licence: MIT\n")
    r = rik("catalog", "list", "--catalog", str(overlay))
    assert r.code == 2
    assert "entry designs[0] 'knob/lost', field 'generator.file': no mesh file" in _flat(r.err)
    assert "meshes/lost.stl (paths are relative to the YAML file)" in _flat(r.err)


def test_build_needs_ids_or_all_and_suggests_close_ids(rik):
    r = rik("assets", "build")
    assert r.code == 2 and "name at least one handle or base unit id, or pass --all" in _flat(r.err)
    r = rik("assets", "build", "two_point/bow-12")
    assert r.code == 2
    assert "no handle or base unit 'two_point/bow-12' in the catalog; did you mean 'two_point/bow-128'" in _flat(r.err)


def test_fidelity_refuses_a_base_unit_with_the_reason(rik):
    r = rik("assets", "fidelity", "door/double-80")
    assert r.code == 2
    assert "door/double-80 is a base unit: its collision is its own panels (exact, zero deviation)" in _flat(r.err)


def test_build_reports_a_corrupt_cache_entry_and_rebuilds_it(rik):
    from rik.assets.build import asset_key
    from rik.assets.cache import AssetCache
    from rik.registry.load import load_catalog

    assert rik("assets", "build", "flap/drop-down-60").code == 0
    key = asset_key(load_catalog(), "flap/drop-down-60")
    payload = AssetCache().path(key) / "asset.npz"
    payload.write_bytes(b"not an npz")
    r = rik("assets", "build", "flap/drop-down-60")
    assert r.code == 0
    assert "failed its sha256 check; it was removed and will be rebuilt" in _flat(r.out)
    assert "0 built, 1 rebuilt after a failed hash check, 0 from the cache" in _flat(r.out)
    again = rik("assets", "build", "flap/drop-down-60")
    assert "1 from the cache" in _flat(again.out)


# ---- size limit, and nothing registered before every stage has passed ------------------------------------------
def test_a_mesh_over_the_face_limit_is_refused_before_anything_is_written(rik, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    trimesh.creation.icosphere(subdivisions=4, radius=0.015).export(tmp_path / "dense.stl")  # 5,120 triangles
    r = rik("assets", "import", "dense.stl", "--type", "knob", "--id", "knob/dense", "--catalog-dir", "cat",
            "--max-faces", "1000")
    assert r.code == 2
    assert r.err == ("rik: error: dense.stl: the mesh has 5,120 triangles, more than the limit of 1,000; simplify "
                     "it, or raise the limit with --max-faces 5120\n")
    assert _files(tmp_path / "cat") == []
    ok = rik("assets", "import", "dense.stl", "--type", "knob", "--id", "knob/dense", "--catalog-dir", "cat",
             "--max-faces", "5120")
    assert ok.code == 0, ok.err


def test_a_failure_after_the_decomposition_leaves_nothing_registered(rik, bar_files, tmp_path):
    out = tmp_path / "cat"
    out.mkdir()
    (out / "pictures").write_text("a file where the pictures folder goes\n")
    r = rik("assets", "import", str(bar_files / "bar_m.stl"), "--type", "two_point", "--id", "two_point/blocked",
            "--hole-spacing", "0.128", "--catalog-dir", str(out))
    assert r.code == 2
    assert len(r.err.splitlines()) == 1 and "Traceback" not in r.err
    assert "cannot create the folder" in _flat(r.err) and "pictures" in _flat(r.err)
    assert _files(out) == ["pictures"]  # no YAML, no mesh: the handle is not registered
    from rik.registry.load import load_catalog

    assert "two_point/blocked-128" not in load_catalog([out]).handles


@pytest.mark.parametrize(("broken", "faces"), [([0], 5), (slice(None), 320)])
def test_a_mesh_with_nan_vertices_fails_with_one_line_and_no_warning(rik, tmp_path, monkeypatch, broken, faces):
    import warnings

    monkeypatch.chdir(tmp_path)
    sphere = trimesh.creation.icosphere(subdivisions=2, radius=0.015)  # 320 triangles; vertex 0 is in 5
    vertices = sphere.vertices.copy()
    vertices[broken] = np.nan
    trimesh.Trimesh(vertices, sphere.faces, process=False).export(tmp_path / "nan.stl")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = rik("assets", "import", "nan.stl", "--type", "knob", "--id", "knob/nan", "--catalog-dir", "cat")
    assert r.code == 2
    assert r.err == (f"rik: error: nan.stl: {faces} of its 320 triangles have corners that are not finite numbers "
                     "(NaN or infinity); the file is damaged: export it again\n")
    assert [str(w.message) for w in caught] == []  # no numpy RuntimeWarning before the error
    assert _files(tmp_path / "cat") == []
