"""conftest.py: the small meshes the tests cook, and where the assimp test models are."""
import os

import numpy as np
import pytest

import cbvh
import reference

MODELS = "/usr/share/assimp/models"


class Scene:
    """A mesh, its corners in double, and the cbvh file cooked from it."""

    def __init__(self, name, vertices, triangles, materials, **options):
        self.name = name
        self.vertices, self.triangles, self.materials = vertices, triangles, materials
        self.tris = reference.corners(vertices, triangles)
        self.data = cbvh.cook(vertices, triangles, materials=materials, **options)
        self.file = cbvh.open(self.data)
        self.extent = float(np.abs(self.tris).max())


@pytest.fixture(scope="session", params=["sphere-wide4", "soup-wide4", "soup-binary-quantized"])
def scene(request):
    if request.param == "sphere-wide4":
        return Scene(request.param, *reference.sphere_mesh())
    if request.param == "soup-wide4":
        return Scene(request.param, *reference.triangle_soup())
    # Quantized vertices: the queries see the decoded vertices, which the reference then takes too.
    s = Scene(request.param, *reference.triangle_soup(seed=5), layout="binary", quantize_vertices=True,
              max_leaf_size=2)
    s.tris = s.file.triangles.astype(np.float64)
    return s


@pytest.fixture(scope="session")
def wuson(tmp_path_factory):
    """Wuson.ply (3.7K triangles) cooked by `cbvh cook` (through cook_file)."""
    source = os.path.join(MODELS, "PLY", "Wuson.ply")
    if not os.path.exists(source):
        pytest.skip("assimp-testmodels is not installed (%s)" % source)
    path = str(tmp_path_factory.mktemp("wuson") / "wuson.cbvh")
    cbvh.cook_file(source, path)
    return path
