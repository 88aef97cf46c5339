"""`clpde surface FLOW MESH -o OUTDIR` end to end on small grids."""

import imageio.v3 as iio
import numpy as np
import trimesh

from clpde.cli import main


def test_surface_heat_on_a_generated_shape(tmp_path, capsys):
    out = tmp_path / "heat"
    assert main(["surface", "heat", "sphere", "-o", str(out), "--resolution", "24", "--size", "64"]) == 0
    before, after = iio.imread(out / "before.png"), iio.imread(out / "after.png")
    assert before.shape == after.shape == (64, 128, 3)
    # heat smooths the checkerboard: fewer saturated colours after
    assert np.std(after.astype(float)) < np.std(before.astype(float))
    mesh = trimesh.load(out / "result.ply", force="mesh")
    assert len(mesh.faces) > 100 and mesh.visual.vertex_colors.shape[0] == len(mesh.vertices)
    assert "wrote 4 files" in capsys.readouterr().err


def test_surface_on_a_mesh_file_and_errors(tmp_path, capsys):
    path = tmp_path / "ball.ply"
    trimesh.creation.icosphere(3, radius=2.0).export(path)
    out = tmp_path / "curv"
    assert main(["surface", "curvature", str(path), "-o", str(out), "--resolution", "24", "--size", "48"]) == 0
    assert (out / "result.glb").stat().st_size > 0
    assert main(["surface", "heat", str(tmp_path / "missing.obj"), "-o", str(out)]) == 2
    assert "neither a mesh file" in capsys.readouterr().err
    assert main(["surface", "flowvis", "sphere", "-o", str(out), "--direction", "none"]) == 2
