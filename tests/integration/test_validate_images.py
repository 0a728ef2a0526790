"""`restir validate --images`: the harness applied to images from any renderer, as a user of
another renderer runs it (EXR files on disk, the command line), on our own ReSTIR DI and on its
deliberately biased variant (debug.mutation=temporal_overweight: the history's weight fed back,
about +57% on this scene)."""
import numpy as np
import pytest

import restir
from restir.cli import main
from restir.image_io import write_exr

RUNS = 32  # per side: image-level MDB about 12% at 24x24 x 8 frames


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    scene = restir.load_scene("builtin:cornell-box")
    sides = (("ours", "restir-di", {}, 1, 100), ("biased", "restir-di", {"debug.mutation": "temporal_overweight"}, 1, 100),
             ("reference", "pt", {}, 4, 5000))
    for name, method, settings, spp, seed0 in sides:
        (root / name).mkdir()
        for k in range(RUNS):
            r = restir.render(scene, method=method, spp=spp, frames=8, width=24, height=24, max_depth=2,
                              seed=seed0 + k, settings=settings)
            write_exr(str(root / name / f"run_{k:02d}.exr"), r.image)
    r = restir.render(scene, method="pt", spp=256, frames=8, width=24, height=24, max_depth=2, seed=7)
    write_exr(str(root / "converged.exr"), r.image)
    np.save(str(root / "converged_var.npy"), r.batch_variance_of_mean.astype(np.float32))
    return root


def test_unbiased_runs_pass(runs, capsys):
    code = main(["validate", "--images", str(runs / "ours" / "*.exr"), "--reference", str(runs / "reference" / "*.exr"),
                 "--max-mdb", "15%"])
    out = capsys.readouterr().out
    assert code == 0 and "verdict: pass" in out, out


def test_biased_runs_fail(runs, capsys):
    for ref in (["--reference", str(runs / "reference" / "*.exr")],
                ["--reference", str(runs / "converged.exr"), "--reference-variance", str(runs / "converged_var.npy")],
                ["--reference", str(runs / "converged.exr")]):
        code = main(["validate", "--images", str(runs / "biased" / "*.exr"), *ref, "--zmap", str(runs / "z.png")])
        out = capsys.readouterr().out
        assert code == 1 and "verdict: fail" in out, (ref, out)
    assert (runs / "z.png").is_file()


def test_reference_rendered_here(runs, capsys):
    """No --reference: the path tracer renders it on the named scene at the images' size."""
    code = main(["validate", "builtin:cornell-box", "--images", str(runs / "biased" / "*.exr"), "--max-depth", "2",
                 "--ref-runs", "8", "--frames", "4"])
    out = capsys.readouterr().out
    assert code == 1 and "verdict: fail" in out, out


def test_input_errors(runs, tmp_path, capsys):
    write_exr(str(tmp_path / "small.exr"), np.zeros((8, 8, 3), np.float32))
    write_exr(str(tmp_path / "big.exr"), np.zeros((16, 8, 3), np.float32))
    cases = [
        (["--images", str(tmp_path / "none*.exr"), "--reference", str(runs / "converged.exr")], "no file matches"),
        (["--images", str(tmp_path / "small.exr"), "--reference", str(runs / "converged.exr")], "at least 2"),
        (["--images", str(tmp_path / "*.exr"), "--reference", str(runs / "converged.exr")], "differ in size"),
        (["--images", str(runs / "ours" / "*.exr"), "--reference", str(tmp_path / "small.exr")], "the reference is 8x8"),
        (["--images", str(runs / "ours" / "*.exr")], "needs --reference images or a SCENE"),
        (["builtin:cornell-box", "--reference", str(runs / "converged.exr")], "go with --images"),
    ]
    for args, msg in cases:
        assert main(["validate", *args]) == 2
        err = capsys.readouterr().err
        assert msg in err, (args, err)
