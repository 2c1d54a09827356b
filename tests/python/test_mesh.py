"""toposimp.simplify_mesh, read_mesh and write_mesh on numpy arrays: the command line's results,
exact round trips, errors as exceptions."""
import numpy
import pytest

import toposimp
from conftest import DATA


def test_read_write_round_trip_is_exact(tmp_path):
    mesh = toposimp.read_mesh(DATA / "mesh" / "torus.off")
    assert mesh.vertices.shape == (2400, 3) and mesh.faces.shape == (4800, 3)
    assert mesh.vertices.dtype == numpy.float64 and mesh.report["format"] == "OFF"
    rng = numpy.random.default_rng(7)
    shaken = mesh.vertices + rng.normal(scale=1e-3, size=mesh.vertices.shape)
    colours = {c: rng.integers(0, 256, len(shaken)).astype("uint8") for c in ("red", "green", "blue")}
    colours["quality"] = rng.random(len(shaken))
    for name in ("a.ply", "b.obj", "c.off"):
        assert toposimp.write_mesh(tmp_path / name, (shaken, mesh.faces, colours)) == (
            ["vertex quality"] if name != "a.ply" else [])
        back = toposimp.read_mesh(tmp_path / name)
        assert numpy.array_equal(back.vertices, shaken), name
        assert numpy.array_equal(back.faces, mesh.faces), name
        for c in ("red", "green", "blue"):
            # OBJ and OFF hold colours from 0 to 1 (float32), PLY in the type given.
            values = back.vertex_attributes[c]
            scaled = numpy.rint(values.astype(float) * 255) if values.dtype.kind == "f" else values
            assert numpy.array_equal(scaled.astype(int), colours[c].astype(int)), name
    with pytest.raises(toposimp.OutputError, match="exists"):
        toposimp.write_mesh(tmp_path / "a.ply", (shaken, mesh.faces))


@pytest.mark.parametrize("options,args", [({"keep": 0.1}, ["--keep", "10%"]), ({"keep_faces": 500}, ["--keep-faces", "500"]),
                                          ({"max_error": 0.05}, ["--max-error", "0.05"])])
def test_simplify_matches_the_command_line(run_cli, tmp_path, options, args):
    mesh = toposimp.read_mesh(DATA / "mesh" / "torus.off")
    ours = toposimp.simplify_mesh(mesh.vertices, mesh.faces, measure=None, **options)
    run_cli("mesh", DATA / "mesh" / "torus.off", "-o", tmp_path / "t.ply", "--no-hausdorff", *args)
    theirs = toposimp.read_mesh(tmp_path / "t.ply")
    assert numpy.array_equal(ours.vertices, theirs.vertices)
    assert numpy.array_equal(ours.faces, theirs.faces)
    assert ours.report["faces_out"] == len(ours.faces) < 4800


def test_terrain_with_attributes_and_threads(run_cli, tmp_path):
    hills = toposimp.read_mesh(DATA / "mesh" / "hills.obj")
    height = {"height": hills.vertices[:, 2].copy()}
    one = toposimp.simplify_mesh(hills.vertices, hills.faces, max_error=0.5, terrain=True, threads=1, vertex_attributes=height)
    two = toposimp.simplify_mesh(hills.vertices, hills.faces, max_error=0.5, terrain=True, threads=2, vertex_attributes=height)
    assert numpy.array_equal(one.vertices, two.vertices) and numpy.array_equal(one.faces, two.faces)
    assert one.report["terrain"] and one.report["vertical_error"]["max"] <= 0.5
    assert one.report["guaranteed_vertical_error"] == 0.5
    assert len(one.vertex_attributes["height"]) == len(one.vertices)
    assert one.report["attributes"]["vertex"] == ["height"]


def test_bad_meshes_raise():
    mesh = toposimp.read_mesh(DATA / "mesh" / "torus.off")
    with pytest.raises(toposimp.InputError, match="face 0 has corner 99999"):
        toposimp.simplify_mesh(mesh.vertices, mesh.faces + 99999 - mesh.faces[0, 0])
    with pytest.raises(toposimp.UsageError, match=r"shape \(n, 3\)"):
        toposimp.simplify_mesh(mesh.vertices[:, :2], mesh.faces)
    with pytest.raises(toposimp.UsageError, match="one target"):
        toposimp.simplify_mesh(mesh.vertices, mesh.faces, keep=0.1, keep_faces=10)
    # Three faces on one edge: not a surface.
    fan = numpy.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], dtype=float)
    with pytest.raises(toposimp.InputError, match="more than two faces"):
        toposimp.simplify_mesh(fan, numpy.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]))
    with pytest.raises(toposimp.InputError, match="cannot open"):
        toposimp.read_mesh("/nonexistent/x.ply")
    with pytest.raises(toposimp.UsageError, match="not a mesh format"):
        toposimp.write_mesh("/tmp/x.xyz", (mesh.vertices, mesh.faces))


def test_contact_check_after_or_each():
    # The bridge deck's first result meets itself: simplified again, every collapse checked; the
    # same mesh as contact_check="each" gives.
    deck = toposimp.read_mesh(DATA / "mesh" / "bridge-deck.obj")
    after = toposimp.simplify_mesh(deck.vertices, deck.faces, keep=0.2, measure=None)
    each = toposimp.simplify_mesh(deck.vertices, deck.faces, keep=0.2, measure=None, contact_check="each")
    assert after.report["contact_check"]["mode"] == "after" and after.report["contact_check"]["simplified_again"]
    assert each.report["contact_check"]["mode"] == "each" and not each.report["contact_check"]["simplified_again"]
    assert numpy.array_equal(after.vertices, each.vertices) and numpy.array_equal(after.faces, each.faces)
    with pytest.raises(toposimp.UsageError, match="contact_check is 'after' or 'each'"):
        toposimp.simplify_mesh(deck.vertices, deck.faces, contact_check="never")
