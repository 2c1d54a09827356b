"""Shared fixtures: the package from the build tree (PYTHONPATH, set by ctest), the toposimp
executable of the same build (TOPOSIMP_BINARY), and the repository's test data."""
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = ROOT / "testdata"


@pytest.fixture(scope="session")
def binary():
    path = os.environ.get("TOPOSIMP_BINARY")
    if not path:
        pytest.fail("TOPOSIMP_BINARY is not set (ctest sets it to the build's toposimp)")
    return path


@pytest.fixture(scope="session")
def run_cli(binary):
    def run(*args):
        done = subprocess.run([binary, *map(str, args)], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done
    return run


@pytest.fixture(scope="session")
def borders():
    import geopandas
    return geopandas.read_file(DATA / "nh_borders.gpkg", layer="borders")


@pytest.fixture(scope="session")
def places():
    import geopandas
    return geopandas.read_file(DATA / "nh_borders.gpkg", layer="places")


@pytest.fixture(scope="session")
def states():
    import geopandas
    return geopandas.read_file(DATA / "ne_states_slice.gpkg", layer="states")
