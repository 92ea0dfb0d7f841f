"""qdmr from Python: scenes, the persistent Renderer with frames as numpy arrays, qdmr's image files, studies
(in process or on a Dask cluster) and golden-image checks. docs/python.md describes it.

    import qdmr
    scene = qdmr.load_scene("scenes/plane.json", {"/output/width": 480, "/output/height": 270})
    renderer = qdmr.Renderer(threads=2)
    renderer.set_scene(scene, aovs=["depth"])
    frame = renderer.draw()
    frame.color        # float32 (270, 480, 3), linear RGB, row 0 at the top
    frame["depth"]     # float32 (270, 480)
"""
from ._qdmr import (  # noqa: F401
    Frame,
    InputError,
    Renderer,
    Scene,
    SceneError,
    __version__,
    aov_names,
    bits_version,
    isas,
    load_scene,
    plan,
    read_image,
    write_image,
)
from . import check, study  # noqa: F401,E402

__all__ = [
    "Frame", "InputError", "Renderer", "Scene", "SceneError", "aov_names", "bits_version", "check", "isas",
    "load_scene", "plan", "read_image", "study", "write_image",
]
