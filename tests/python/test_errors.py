# Bad input from Python: qdmr's messages as SceneError (a ValueError) naming the field, InputError (an OSError)
# naming the file, TypeError naming the parameter; nothing written, nothing crashed. Also run under ASan
# (tests/CMakeLists.txt, label python-asan).
import json
import os

import numpy
import pytest

import qdmr
from conftest import PLANE, SMALL, SOURCE_DIR

SPEC = {"scene": PLANE, "width": 32, "height": 18, "frames": 1, "warmup": 0,
        "axes": [{"name": "technique", "path": "/materials/bricks/technique/name", "values": ["pom", "qdm"]}]}


def test_exception_classes():
    assert issubclass(qdmr.SceneError, ValueError) and issubclass(qdmr.InputError, OSError)


def test_missing_scene_file_is_an_input_error(tmp_path):
    missing = tmp_path / "nope.json"
    with pytest.raises(qdmr.InputError, match="nope.json"):
        qdmr.load_scene(missing)
    with pytest.raises(qdmr.InputError, match="not a regular file|directory"):
        qdmr.load_scene(tmp_path)


def test_bad_override_names_the_field():
    with pytest.raises(qdmr.SceneError, match="/camera/fov_deg"):
        qdmr.load_scene(PLANE, {"/camera/fov_deg": 500})
    with pytest.raises(qdmr.SceneError, match="/camera/fov_deg"):
        qdmr.load_scene(PLANE, ["/camera/fov_deg=-3"])
    with pytest.raises(qdmr.SceneError, match="unknown key 'nowhere'"):
        qdmr.load_scene(PLANE, {"/nowhere/x": 1})


def test_bad_scene_dict_names_the_field():
    scene = json.load(open(PLANE))
    scene["camera"]["fovv_deg"] = 30  # a misspelt key: refused, with a suggestion
    with pytest.raises(qdmr.SceneError, match="/camera.*fovv_deg"):
        qdmr.load_scene(scene)
    scene = json.load(open(PLANE))
    scene["materials"]["bricks"]["layers"][0]["albedo"] = "missing.png"
    with pytest.raises(qdmr.InputError, match="/materials/bricks/layers/0/albedo: file not found: .*missing.png"):
        qdmr.load_scene(scene, base_dir=SOURCE_DIR)


def with_mesh(path):
    scene = json.load(open(PLANE))
    scene["objects"][0]["mesh"] = {"type": "obj", "file": str(path)}
    return scene


def test_the_exception_follows_the_kind_of_error_not_its_words(tmp_path):
    scenes = os.path.dirname(PLANE)
    # A value whose words sound like a file problem is still a bad value ...
    with pytest.raises(qdmr.SceneError, match="cannot read file not found"):
        qdmr.load_scene(PLANE, {"/materials/bricks/technique/name": "cannot read file not found"})
    # ... and a mesh file's content is a value too (the OBJ reader's message says "cannot read")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n")
    with pytest.raises(qdmr.SceneError, match="cannot read the face index 'x'"):
        qdmr.load_scene(with_mesh(bad), base_dir=scenes)
    # A file refused as a whole is an InputError whatever its message says: empty, a missing material library.
    empty = tmp_path / "empty.json"
    empty.write_text("")
    with pytest.raises(qdmr.InputError, match="empty.json.*is empty"):
        qdmr.load_scene(empty)
    no_mtl = tmp_path / "no_mtl.obj"
    no_mtl.write_text("mtllib absent.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(qdmr.InputError, match="material library not found: .*absent.mtl"):
        qdmr.load_scene(with_mesh(no_mtl), base_dir=scenes)
    with pytest.raises(qdmr.InputError, match="absent.obj"):
        qdmr.load_scene(with_mesh(tmp_path / "absent.obj"), base_dir=scenes)


def test_argument_types_name_the_parameter(tmp_path):
    cases = [
        (lambda: qdmr.load_scene(3), "scene"),
        (lambda: qdmr.load_scene(PLANE, overrides=5), "overrides"),
        (lambda: qdmr.load_scene(PLANE, {"/camera/fov_deg": object()}), "overrides"),
        (lambda: qdmr.load_scene(PLANE, {1: 2}), "overrides key"),
        (lambda: qdmr.Renderer(threads="2"), "threads"),
        (lambda: qdmr.Renderer(threads=True), "threads"),
        (lambda: qdmr.Renderer(tile=8.0), "tile"),
        (lambda: qdmr.Renderer(isa=2), "isa"),
        (lambda: qdmr.Renderer(aovs="depth"), "aovs"),
        (lambda: qdmr.Renderer().set_scene(qdmr.load_scene(PLANE), aovs=[3]), "aovs"),
        (lambda: qdmr.Renderer().set_scene(PLANE), "scene"),
        (lambda: qdmr.plan({"output": {}}), "scene"),
        (lambda: qdmr.read_image(5), "path"),
        (lambda: qdmr.write_image("pixels", tmp_path / "x.exr"), "image"),
        (lambda: qdmr.write_image(numpy.zeros((2, 2), numpy.float32), 7), "path"),
        (lambda: qdmr.write_image(numpy.zeros((2, 2), numpy.float32), tmp_path / "x.exr", srgb=1), "srgb"),
        (lambda: qdmr.write_image(numpy.zeros((2, 2), numpy.float32), tmp_path / "x.exr", threads="1"), "threads"),
        (lambda: qdmr.study.run(SPEC, 5), "out"),
        (lambda: qdmr.study.run(3, tmp_path / "s"), "spec"),
        (lambda: qdmr.study.run(SPEC, tmp_path / "s", resume="yes"), "resume"),
        (lambda: qdmr.check.run(None), "manifest"),
    ]
    for call, parameter in cases:
        with pytest.raises(TypeError, match=parameter):
            call()
    assert not os.listdir(tmp_path)


def test_bad_values():
    with pytest.raises(ValueError, match="tile"):
        qdmr.Renderer(tile=12)
    with pytest.raises(ValueError, match="threads"):
        qdmr.Renderer(threads=0)
    with pytest.raises(ValueError, match="isa.*'mmx'"):
        qdmr.Renderer(isa="mmx")
    with pytest.raises(ValueError, match="unknown AOV 'dpeth'"):
        qdmr.Renderer(aovs=["dpeth"])
    renderer = qdmr.Renderer(threads=1)
    with pytest.raises(RuntimeError, match="no scene"):
        renderer.draw()
    with pytest.raises(ValueError, match="shape"):
        qdmr.write_image(numpy.zeros((2, 2, 7), numpy.float32), "x.exr")
    with pytest.raises(ValueError, match="threads"):
        qdmr.write_image(numpy.zeros((2, 2), numpy.float32), "x.exr", threads=0)


def test_memory_limit_refuses_before_building():
    renderer = qdmr.Renderer(threads=1, max_memory_mib=1)
    with pytest.raises(qdmr.SceneError, match="more than the limit"):
        renderer.set_scene(qdmr.load_scene(PLANE))


def test_image_files(tmp_path):
    with pytest.raises(qdmr.InputError, match="absent.exr"):
        qdmr.read_image(tmp_path / "absent.exr")
    (tmp_path / "text.png").write_text("not a png")
    with pytest.raises(qdmr.InputError, match="text.png"):
        qdmr.read_image(tmp_path / "text.png")
    with pytest.raises(qdmr.InputError, match="no_folder"):
        qdmr.write_image(numpy.zeros((2, 2, 3), numpy.float32), tmp_path / "no_folder" / "x.exr")
    with pytest.raises(qdmr.InputError, match="x.bmp"):
        qdmr.write_image(numpy.zeros((2, 2, 3), numpy.float32), tmp_path / "x.bmp")
    assert sorted(os.listdir(tmp_path)) == ["text.png"]  # nothing partial left


def test_bad_specs_and_manifests(tmp_path):
    with pytest.raises(qdmr.SceneError, match="/axes/0/values"):
        qdmr.study.run({**SPEC, "axes": [{**SPEC["axes"][0], "values": []}]}, tmp_path / "s")
    with pytest.raises(qdmr.SceneError, match="unknown key 'widht'; did you mean 'width'"):
        qdmr.study.run({**SPEC, "widht": 3}, tmp_path / "s")
    with pytest.raises(qdmr.InputError, match="nope.json"):
        qdmr.study.run(tmp_path / "nope.json", tmp_path / "s")
    with pytest.raises(qdmr.InputError, match="/scene: file not found: .*absent.json"):
        qdmr.study.run({**SPEC, "scene": str(tmp_path / "absent.json")}, tmp_path / "s")
    manifest = tmp_path / "m.json"
    manifest.write_text(json.dumps({"bits_version": qdmr.bits_version, "checks": [{"name": "a b", "scene": PLANE}]}))
    with pytest.raises(qdmr.SceneError, match="/checks/0/name"):
        qdmr.check.run(manifest)
    with pytest.raises(qdmr.InputError):
        qdmr.study.load(tmp_path)
    with pytest.raises(qdmr.InputError, match="m.json: cannot create the results folder"):
        qdmr.study.run(SPEC, manifest)  # a file where the results folder would be
    assert sorted(os.listdir(tmp_path)) == ["m.json"]
