"""Visual-gap metrics (FID, KID, EMD, bootstrap, split-half floor) against closed forms on synthetic features, and
the image-folder -> encoder -> report pipeline end to end with randomly initialised encoders."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import ortho_group, wasserstein_distance

from rik.errors import RikError
from rik.render.metrics import (
    FLOOR,
    bootstrap_pairs,
    emd,
    fid,
    frechet_distance,
    kid,
    percentile_interval,
    split_half,
)

# --- FID -----------------------------------------------------------------------------------------------------


def test_frechet_distance_diagonal_closed_form() -> None:
    rng = np.random.default_rng(0)
    mu1, mu2 = rng.normal(size=6), rng.normal(size=6)
    a, b = rng.uniform(0.1, 3, 6), rng.uniform(0.1, 3, 6)
    expected = np.sum((mu1 - mu2) ** 2) + np.sum((np.sqrt(a) - np.sqrt(b)) ** 2)
    assert frechet_distance(mu1, np.diag(a), mu2, np.diag(b)) == pytest.approx(expected, rel=1e-10)
    # rotating both Gaussians by one orthogonal matrix changes nothing
    q = ortho_group.rvs(6, random_state=1)
    rotated = frechet_distance(q @ mu1, q @ np.diag(a) @ q.T, q @ mu2, q @ np.diag(b) @ q.T)
    assert rotated == pytest.approx(expected, rel=1e-8)


def test_frechet_distance_one_dimension_and_scalars() -> None:
    # 1-D Gaussians: (mu1 - mu2)^2 + (sigma1 - sigma2)^2
    assert frechet_distance(np.array([1.0]), np.array([[4.0]]), np.array([-2.0]), np.array([[9.0]])) == \
        pytest.approx(9.0 + 1.0)


def test_frechet_distance_symmetric_nonnegative_zero_on_identity_and_singular() -> None:
    rng = np.random.default_rng(2)
    x = rng.normal(size=(5, 40))  # rank-4 covariance in 40-d: sqrtm-based code goes complex here
    y = rng.normal(size=(5, 40)) + 0.3
    s1, s2 = np.cov(x, rowvar=False), np.cov(y, rowvar=False)
    m1, m2 = x.mean(0), y.mean(0)
    d12, d21 = frechet_distance(m1, s1, m2, s2), frechet_distance(m2, s2, m1, s1)
    assert isinstance(d12, float) and np.isfinite(d12) and d12 > 0
    assert d12 == pytest.approx(d21, rel=1e-8)
    assert frechet_distance(m1, s1, m1, s1) == pytest.approx(0.0, abs=1e-8)


@pytest.mark.parametrize("n,d", [(7, 30), (60, 5)])  # the n x n SVD route and the d x d route
def test_fid_equals_frechet_distance_of_fitted_gaussians(n: int, d: int) -> None:
    rng = np.random.default_rng(3)
    a = rng.normal(size=(n, d)) * rng.uniform(0.5, 2, d)
    b = rng.normal(size=(n + 3, d)) + 0.2
    expected = frechet_distance(a.mean(0), np.cov(a, rowvar=False), b.mean(0), np.cov(b, rowvar=False))
    assert fid(a, b) == pytest.approx(expected, rel=1e-6)
    assert fid(b, a) == pytest.approx(expected, rel=1e-6)
    assert fid(a, a) == pytest.approx(0.0, abs=1e-9)
    assert fid(a, a[::-1]) == pytest.approx(0.0, abs=1e-9)


def test_fid_of_large_gaussian_samples_approaches_closed_form() -> None:
    rng = np.random.default_rng(4)
    mu1, mu2 = np.array([0.0, 1.0, -1.0]), np.array([0.5, 0.0, -1.0])
    a_var, b_var = np.array([1.0, 4.0, 0.25]), np.array([2.0, 1.0, 0.25])
    x = mu1 + rng.normal(size=(40000, 3)) * np.sqrt(a_var)
    y = mu2 + rng.normal(size=(40000, 3)) * np.sqrt(b_var)
    expected = np.sum((mu1 - mu2) ** 2) + np.sum((np.sqrt(a_var) - np.sqrt(b_var)) ** 2)
    assert fid(x, y) == pytest.approx(expected, abs=0.03)


def test_fid_refuses_bad_shapes() -> None:
    with pytest.raises(RikError, match="feature dimensions differ: 3 and 4"):
        fid(np.zeros((5, 3)), np.zeros((5, 4)))
    with pytest.raises(RikError, match="needs at least 2 images, got 1"):
        fid(np.zeros((1, 3)), np.zeros((5, 3)))


# --- EMD -----------------------------------------------------------------------------------------------------


def test_emd_of_shifted_set_is_the_shift_length_and_permutation_is_zero() -> None:
    rng = np.random.default_rng(5)
    x = rng.normal(size=(9, 4))
    shift = np.array([3.0, -4.0, 0.0, 12.0])  # length 13
    assert emd(x, x + shift) == pytest.approx(13.0, rel=1e-12)
    assert emd(x, x[rng.permutation(9)]) == pytest.approx(0.0, abs=1e-12)


def test_emd_hand_built_matching() -> None:
    # {0, 10} against {1, 12} on a line: optimal matching 0-1, 10-12 -> mean cost 1.5
    assert emd(np.array([[0.0], [10.0]]), np.array([[12.0], [1.0]])) == pytest.approx(1.5)


def test_emd_unequal_sizes_solves_the_transport_problem() -> None:
    rng = np.random.default_rng(6)
    a, b = rng.normal(size=7), rng.normal(size=11) + 0.5
    assert emd(a[:, None], b[:, None]) == pytest.approx(wasserstein_distance(a, b), rel=1e-7)
    x = rng.normal(size=(5, 3))
    assert emd(x, np.vstack([x, x])) == pytest.approx(0.0, abs=1e-9)  # same distribution, each point twice


def test_emd_refuses_huge_unequal_problem() -> None:
    with pytest.raises(RikError, match="subsample both to the same size"):
        emd(np.zeros((600, 2)), np.zeros((500, 2)))


# --- KID -----------------------------------------------------------------------------------------------------


def test_kid_matches_closed_form_for_uniform_distributions() -> None:
    # d = 1, k(x, y) = (xy + 1)^3: MMD^2 = (m3x - m3y)^2 + 3 (m2x - m2y)^2 + 3 (m1x - m1y)^2 in raw moments.
    # X ~ U(-1, 1): moments (0, 1/3, 0); Y ~ U(0, 2): (1, 4/3, 2) -> 4 + 3 + 3 = 10.
    # One estimate on 1500 + 1500 points has a standard deviation of about 0.5, so average 12 independent ones.
    rng = np.random.default_rng(7)
    draws = [kid(rng.uniform(-1, 1, (1500, 1)), rng.uniform(0, 2, (1500, 1)), subset_size=1500).mean
             for _ in range(12)]
    assert np.mean(draws) == pytest.approx(10.0, abs=0.5)
    subsets = kid(rng.uniform(-1, 1, (1500, 1)), rng.uniform(0, 2, (1500, 1)), subsets=10, subset_size=500, seed=1)
    assert subsets.mean == pytest.approx(10.0, rel=0.25) and subsets.std > 0


def test_kid_equals_brute_force_unbiased_estimator() -> None:
    rng = np.random.default_rng(8)
    x, y = rng.normal(size=(6, 3)), rng.normal(size=(6, 3)) + 0.4

    def k(u: np.ndarray, v: np.ndarray) -> float:
        return (u @ v / 3 + 1) ** 3

    within_x = sum(k(x[i], x[j]) for i in range(6) for j in range(6) if i != j) / 30
    within_y = sum(k(y[i], y[j]) for i in range(6) for j in range(6) if i != j) / 30
    cross = sum(k(x[i], y[j]) for i in range(6) for j in range(6)) / 36
    value = kid(x, y)
    assert value.mean == pytest.approx(within_x + within_y - 2 * cross, rel=1e-12)
    assert value.std == 0.0  # subsets of the whole sets are all the same


def test_kid_is_unbiased_where_fid_is_not() -> None:
    rng = np.random.default_rng(9)
    kids, fids, shifted = [], [], []
    for _ in range(300):
        a, b = rng.uniform(-1, 1, (10, 4)), rng.uniform(-1, 1, (10, 4))
        kids.append(kid(a, b).mean)
        fids.append(fid(a, b))
        shifted.append(kid(a, b + 0.5).mean)
    kids_arr = np.array(kids)
    assert abs(kids_arr.mean()) < 3 * kids_arr.std() / np.sqrt(len(kids_arr))  # mean 0 within 3 standard errors
    assert np.mean(fids) > 10 * np.std(fids) / np.sqrt(len(fids))  # FID's small-sample bias: clearly above 0
    assert np.mean(shifted) > 10 * np.std(shifted) / np.sqrt(len(shifted))


# --- bootstrap and split-half --------------------------------------------------------------------------------


def test_percentile_interval_is_recentred_on_the_point() -> None:
    samples = np.linspace(10, 20, 101)  # all above the point, as resamples with repeated images are for FID
    lo, hi = percentile_interval(5.0, samples, level=0.9)
    raw_lo, raw_hi = np.percentile(samples, [5, 95])
    assert lo <= 5.0 <= hi
    assert hi - lo == pytest.approx(raw_hi - raw_lo)
    assert (lo + hi) / 2 == pytest.approx(5.0)


def test_bootstrap_intervals_contain_point_and_are_seeded() -> None:
    rng = np.random.default_rng(10)
    a, b = rng.normal(size=(30, 8)), rng.normal(size=(30, 8)) + 0.3
    row = bootstrap_pairs([(a, b)], resamples=100, seed=3, name="x")
    for iv in (row.fid, row.kid, row.emd):
        assert iv.low <= iv.value <= iv.high and iv.low < iv.high
    assert row.fid.value == pytest.approx(fid(a, b)) and row.emd.value == pytest.approx(emd(a, b))
    assert bootstrap_pairs([(a, b)], resamples=100, seed=3, name="x") == row
    assert bootstrap_pairs([(a, b)], resamples=100, seed=4, name="x").fid.low != row.fid.low
    wider = bootstrap_pairs([(a[:8], b[:8])], resamples=100, seed=3)
    assert wider.emd.high - wider.emd.low > row.emd.high - row.emd.low  # fewer images, wider interval


def test_split_half_floor_and_gap() -> None:
    rng = np.random.default_rng(11)
    scale = np.linspace(0.3, 2, 32)
    real = rng.normal(size=(80, 32)) * scale
    same = rng.normal(size=(80, 32)) * scale
    sim = rng.normal(size=(80, 32)) * scale + 0.8
    result = split_half(real, {"same": same, "sim": sim}, resamples=100, seed=0)
    assert [r.name for r in result.rows] == ["same", "sim", FLOOR]
    assert result.n_half == 40 and all(r.n == 40 for r in result.rows)
    floor, gap, null = result.row(FLOOR), result.row("sim"), result.row("same")
    assert floor.fid.value > 1  # small-sample bias: two halves of one set are far from FID 0
    for metric in ("fid", "kid", "emd"):
        assert getattr(gap, metric).low > getattr(floor, metric).high
    assert null.fid.low < floor.fid.high and null.kid.low < 0 < null.kid.high
    assert json.loads(json.dumps(result.to_dict()))["rows"][2]["name"] == FLOOR


def test_split_half_refuses_unequal_sets() -> None:
    with pytest.raises(RikError, match="'sim' has 9 images and real has 10; compare at equal N"):
        split_half(np.zeros((10, 3)), {"sim": np.zeros((9, 3))})


# --- image folders, encoders and the pipeline ----------------------------------------------------------------


def make_images(folder: Path, count: int, shift: tuple[float, float, float] = (0, 0, 0), seed: int = 0,
                size: int = 32) -> Path:
    """``count`` PNGs of noisy grey texture, colour-shifted by ``shift`` (in [0, 1] units)."""
    from PIL import Image

    rng = np.random.default_rng(seed)
    folder.mkdir(parents=True, exist_ok=True)
    for i in range(count):
        img = np.clip(0.25 + 0.5 * rng.uniform(size=(size, size, 3)) + np.array(shift), 0, 1)
        Image.fromarray((img * 255).astype(np.uint8)).save(folder / f"{i:03d}.png")
    return folder


@pytest.fixture(scope="module")
def folders(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("images")
    return {"real": make_images(root / "real", 12, seed=1),
            "sim": make_images(root / "sim", 12, (0.3, -0.2, 0.1), seed=2),
            "rerendered": make_images(root / "rerendered", 12, (0.03, 0.0, 0.0), seed=3),
            "sim10": make_images(root / "sim10", 10, (0.3, -0.2, 0.1), seed=4)}


def test_visual_gap_end_to_end_random_resnet18(folders: dict[str, Path]) -> None:
    from rik.render.visual_gap import results_json, results_markdown, visual_gap

    res = visual_gap(folders["real"], folders["sim"], folders["rerendered"], "resnet18", bootstrap=50, seed=0,
                     image_size=64)
    assert res.random_weights and res.feature_dim == 512 and res.n_per_set == 12 and res.n_half == 6
    assert [r.name for r in res.rows] == ["sim", "rerendered", FLOOR]
    floor, sim, rer = res.row(FLOOR), res.row("sim"), res.row("rerendered")
    assert sim.fid.value > floor.fid.high and sim.emd.value > floor.emd.high and sim.kid.low > floor.kid.high
    assert rer.fid.value < sim.fid.value
    again = visual_gap(folders["real"], folders["sim"], folders["rerendered"], "resnet18", bootstrap=50, seed=0,
                       image_size=64)
    assert again.to_dict() == res.to_dict()  # deterministic
    data = json.loads(results_json([res]))["results"][0]
    assert data["encoder"] == "resnet18" and data["random_weights"] is True and "random-feature" in data["note"]
    assert data["rows"][0]["fid"]["value"] == pytest.approx(sim.fid.value)
    md = results_markdown([res])
    assert "RANDOM weights" in md and "| real split-half floor | 6 |" in md


def test_visual_gap_subsamples_to_common_n(folders: dict[str, Path]) -> None:
    from rik.render.visual_gap import visual_gap

    with pytest.raises(RikError, match=r"image folders differ in size \(real 12, sim 10 images\); FID and EMD are only comparable at equal N: pass --n 10"):
        visual_gap(folders["real"], folders["sim10"], image_size=64)
    res = visual_gap(folders["real"], folders["sim10"], n=10, bootstrap=20, image_size=64)
    assert res.n_per_set == 10 and res.n_half == 5 and res.images_found == {"real": 12, "sim": 10}
    with pytest.raises(RikError, match="--n 11: more than the smallest set"):
        visual_gap(folders["real"], folders["sim10"], n=11, image_size=64)


def test_cli_prints_table_and_writes_reports(folders: dict[str, Path], tmp_path: Path) -> None:
    import typer
    from typer.testing import CliRunner

    from rik.cli.render import visual_gap

    app = typer.Typer()
    app.command()(visual_gap)
    few = {k: make_images(tmp_path / k, 6, shift, seed=s)
           for k, shift, s in (("real", (0, 0, 0), 1), ("sim", (0.3, -0.2, 0.1), 2))}
    result = CliRunner().invoke(app, ["--real", str(few["real"]), "--sim", str(few["sim"]), "--bootstrap", "20",
                                      "--json", str(tmp_path / "gap.json"), "--out", str(tmp_path / "rep")])
    assert result.exit_code == 0, result.output
    for text in ("visual gap, encoder resnet18 (RANDOM weights", "real split-half floor", "FID [95% CI]",
                 "random-feature baseline", "N = 6 images per set, every comparison 3 vs 3"):
        assert text in result.output
    data = json.loads((tmp_path / "gap.json").read_text())
    assert data == json.loads((tmp_path / "rep" / "visual_gap.json").read_text())
    assert [r["name"] for r in data["results"][0]["rows"]] == ["sim", FLOOR]
    assert "| sim | 3 |" in (tmp_path / "rep" / "visual_gap.md").read_text()
    bad = CliRunner().invoke(app, ["--real", str(few["real"]), "--encoder", "resnet-18"])
    assert isinstance(bad.exception, RikError)
    assert "unknown encoder 'resnet-18'" in str(bad.exception) and "did you mean 'resnet18'" in str(bad.exception)


def test_visual_gap_needs_something_to_compare(folders: dict[str, Path]) -> None:
    from rik.render.visual_gap import visual_gap

    with pytest.raises(RikError, match=r"give --sim or --rerendered \(or both\)"):
        visual_gap(folders["real"])


def test_empty_folder_and_corrupt_image(folders: dict[str, Path], tmp_path: Path) -> None:
    from rik.render.visual_gap import visual_gap

    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "notes.txt").write_text("not an image")
    with pytest.raises(RikError, match=r"--sim .*empty: no images \(.png, .jpg or .jpeg files\) in the folder"):
        visual_gap(folders["real"], empty)
    bad = make_images(tmp_path / "bad", 12, seed=5)
    (bad / "sub").mkdir()
    (bad / "sub" / "frame.png").write_bytes(b"this is not a PNG")
    with pytest.raises(RikError, match=r"bad/sub/frame.png: not a readable image"):
        visual_gap(folders["real"], bad)
    with pytest.raises(RikError, match=r"--rerendered .*nowhere: not a directory"):
        visual_gap(folders["real"], rerendered=tmp_path / "nowhere")


def test_unknown_encoder_and_missing_weights(tmp_path: Path) -> None:
    from rik.render.encoders import load_encoder, parse_spec

    with pytest.raises(RikError, match=r"unknown encoder 'resnt50' .*did you mean 'resnet50'"):
        parse_spec("resnt50")
    with pytest.raises(RikError, match=r"did you mean 'clip-vit-b-32' or 'clip-vit-b-32-gelu'"):
        parse_spec("clip")
    assert parse_spec("ResNet18:/w/r.pth").weights == Path("/w/r.pth")
    with pytest.raises(RikError, match=r"nope.pth: weights file for encoder 'resnet18' not found"):
        load_encoder(f"resnet18:{tmp_path / 'nope.pth'}")
    with pytest.raises(RikError, match=r"encoder 'clip-vit-b-32': image size 64 not supported \(only 224\)"):
        load_encoder("clip-vit-b-32", image_size=64)


def test_weights_that_do_not_fit_the_architecture(tmp_path: Path) -> None:
    import torch
    import torchvision

    from rik.render.encoders import load_encoder

    r18 = tmp_path / "resnet18.pth"
    torch.save(torchvision.models.resnet18(weights=None).state_dict(), r18)
    with pytest.raises(RikError, match=r"resnet18.pth: weights do not match encoder 'resnet50': missing keys layer1.0.conv3.weight, .*shape mismatch layer1.0.conv1.weight \(file \(64, 64, 3, 3\), model \(64, 64, 1, 1\)\)"):
        load_encoder(f"resnet50:{r18}")
    bogus = tmp_path / "bogus.pth"
    torch.save({"foo.weight": torch.zeros(3)}, bogus)
    with pytest.raises(RikError, match=r"bogus.pth: weights do not match encoder 'resnet18': missing keys conv1.weight, bn1.weight, bn1.bias and \d+ more; unexpected keys foo.weight"):
        load_encoder(f"resnet18:{bogus}")
    text = tmp_path / "notes.pth"
    text.write_text("hello")
    with pytest.raises(RikError, match=r"notes.pth: cannot read weights"):
        load_encoder(f"resnet18:{text}")


def test_weights_file_is_loaded(folders: dict[str, Path], tmp_path: Path) -> None:
    import torch
    import torchvision
    from safetensors.torch import save_file

    from rik.render.encoders import load_encoder

    torch.manual_seed(123)
    state = torchvision.models.resnet18(weights=None).state_dict()
    torch.save({"state_dict": {f"module.{k}": v for k, v in state.items()}}, tmp_path / "wrapped.pth")
    save_file({k: v.contiguous() for k, v in state.items() if not k.endswith("num_batches_tracked")},
              str(tmp_path / "r18.safetensors"))
    images = sorted(folders["real"].glob("*.png"))[:4]
    random = load_encoder("resnet18", image_size=64)
    from_pth = load_encoder(f"resnet18:{tmp_path / 'wrapped.pth'}", image_size=64)
    from_st = load_encoder(f"resnet18:{tmp_path / 'r18.safetensors'}", image_size=64)
    assert random.random and not from_pth.random
    f_random, f_pth, f_st = (e.encode(images) for e in (random, from_pth, from_st))
    assert f_pth.shape == (4, 512)
    np.testing.assert_allclose(f_pth, f_st, rtol=1e-6)
    assert not np.allclose(f_pth, f_random)
    np.testing.assert_array_equal(load_encoder("resnet18", image_size=64).encode(images), f_random)


def test_resnet50_random_features(folders: dict[str, Path]) -> None:
    from rik.render.encoders import load_encoder

    feats = load_encoder("resnet50", image_size=64).encode(sorted(folders["sim"].glob("*.png"))[:3])
    assert feats.shape == (3, 2048) and np.all(np.isfinite(feats)) and feats.std() > 0


@pytest.mark.slow  # a build, recording or render end to end: out of the everyday tier
@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # torch.jit is deprecated; OpenAI's file is one
def test_clip_vit_b_32_random_features_and_mismatched_weights(folders: dict[str, Path], tmp_path: Path) -> None:
    import torch

    from rik.render.encoders import load_encoder

    feats = load_encoder("clip-vit-b-32").encode(sorted(folders["real"].glob("*.png"))[:4])
    assert feats.shape == (4, 512)
    np.testing.assert_allclose(np.linalg.norm(feats, axis=1), 1.0, rtol=1e-5)  # L2-normalised embedding

    class Tiny(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.lin = torch.nn.Linear(2, 2)

        def forward(self, x: torch.Tensor) -> torch.Tensor:
            return self.lin(x)

    archive = tmp_path / "ViT-B-32.pt"  # a TorchScript archive, like OpenAI's own checkpoint file
    torch.jit.save(torch.jit.script(Tiny()), str(archive))
    with pytest.raises(RikError, match=r"ViT-B-32.pt: weights do not match encoder 'clip-vit-b-32': missing keys .*unexpected keys lin.weight, lin.bias"):
        load_encoder(f"clip-vit-b-32:{archive}")
    with pytest.raises(RikError, match=r"ViT-B-32.pt: a TorchScript archive, not a state dict"):
        load_encoder(f"resnet18:{archive}")


def test_bootstrap_resample_of_all_images_reproduces_the_metrics() -> None:
    from rik.render.metrics import _PairSampler

    rng = np.random.default_rng(12)
    a, b = rng.normal(size=(9, 20)) + 5.0, rng.normal(size=(9, 20)) * 2 + 5.5  # far from the origin: Grams stay exact
    f, k, e = _PairSampler(a, b).resample(np.arange(9), np.arange(9))
    assert f == pytest.approx(fid(a, b), rel=1e-7)
    assert k == pytest.approx(kid(a, b).mean, rel=1e-9)
    assert e == pytest.approx(emd(a, b), rel=1e-12)
    ia, ib = np.array([0, 0, 3, 4, 5, 5, 5, 8]), np.array([1, 2, 2, 2, 6, 7, 7, 7])  # repeats: plug-in FID still
    f2, _, _ = _PairSampler(a, b).resample(ia, ib)
    assert f2 == pytest.approx(fid(a[ia], b[ib]), rel=1e-7)
