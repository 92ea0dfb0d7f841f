# Dynamic surfaces from Python (issue #58): heights handed over by a program (Renderer.update_layer) draw as the
# same heights read from a file; only what is made from them is rebuilt; frames of an animation (set_frame) are
# the command's frames.
import os

import numpy
import pytest

import qdmr
from conftest import PLANE, SMALL, SOURCE_DIR, run_cli

WATER = os.path.join(SOURCE_DIR, "scenes", "water.json")
QDM = {"/materials/bricks/technique/name": "qdm", "/materials/bricks/technique/depth_scale": 0.1,
       "/materials/bricks/shadow/mode": "hard"}


def bits(array):
    return numpy.ascontiguousarray(array, dtype=numpy.float32).view(numpy.uint32)


def heights(seed):
    """A smooth 64x64 field in [0, 1] (float32 values, exact in an EXR)."""
    y, x = numpy.mgrid[0:64, 0:64] / 64.0
    phase = seed * 0.7
    return (0.5 + 0.25 * numpy.sin(2 * numpy.pi * (3 * x + phase)) * numpy.cos(2 * numpy.pi * (2 * y - phase))).astype(numpy.float32)


def test_handed_over_heights_draw_as_the_same_heights_from_a_file(tmp_path):
    field = heights(1)
    qdmr.write_image(field, tmp_path / "h.exr")
    from_file = qdmr.load_scene(PLANE, {**SMALL, **QDM, "/materials/bricks/layers/0/height": {"file": str(tmp_path / "h.exr")}})
    reference = qdmr.Renderer(threads=2)
    reference.set_scene(from_file)
    expected = reference.draw().color

    renderer = qdmr.Renderer(threads=1)
    renderer.set_scene(qdmr.load_scene(PLANE, {**SMALL, **QDM}))
    before = renderer.draw().color.copy()
    renderer.update_layer("bricks", 0, height=field)
    frame = renderer.draw()
    assert numpy.array_equal(bits(frame.color), bits(expected))
    assert not numpy.array_equal(bits(frame.color), bits(before))  # the test can fail
    # What the heights make is dynamic and was rebuilt; the albedo was kept.
    plan = renderer.plan
    built = {s["what"] for s in renderer.stats["prepare"]["steps"]}
    assert built == {"height", "normal"}, built
    assert {t["purpose"] for t in plan["textures"] if t["dynamic"]} == {"height", "normal"}
    assert len(plan["dynamic_items"]) == renderer.stats["prepare"]["items_built"]
    # A second update: the next heights.
    renderer.update_layer("bricks", 0, height=heights(2))
    assert not numpy.array_equal(bits(renderer.draw().color), bits(expected))


def test_update_layer_refuses_what_it_cannot_draw():
    renderer = qdmr.Renderer(threads=1)
    with pytest.raises(RuntimeError, match="no scene"):
        renderer.update_layer("bricks", 0, height=heights(1))
    renderer.set_scene(qdmr.load_scene(PLANE, {**SMALL, **QDM}))
    with pytest.raises(ValueError, match="no material 'brick'"):
        renderer.update_layer("brick", 0, height=heights(1))
    with pytest.raises(ValueError, match="has layers 0 to 0, not 3"):
        renderer.update_layer("bricks", 3, height=heights(1))
    with pytest.raises(ValueError, match="shape"):
        renderer.update_layer("bricks", 0, height=numpy.zeros((4, 4, 3), numpy.float32))
    bad = heights(1)
    bad[5, 7] = numpy.nan
    with pytest.raises(ValueError, match=r"the height at \(7, 58\) is not finite"):
        renderer.update_layer("bricks", 0, height=bad)
    with pytest.raises(TypeError):
        renderer.update_layer("bricks", 0, height="heights")


def test_set_frame_draws_the_commands_frame(cli, tmp_path):
    sets = {"/materials/water/layers/0/height/size": 64}
    out = tmp_path / "f_%02d.exr"
    run_cli(cli, "render", WATER, "--frames", "2:3", "-o", str(out), "--width", "96", "--height", "54",
            *[a for p, v in sets.items() for a in ("--set", f"{p}={v}")])
    renderer = qdmr.Renderer(threads=1)
    renderer.set_scene(qdmr.load_scene(WATER, {**SMALL, **sets}))
    renderer.set_frame(3)
    assert numpy.array_equal(bits(renderer.draw().color), bits(qdmr.read_image(tmp_path / "f_03.exr")))
    with pytest.raises(ValueError, match="outside the animation's frames 0 to 119"):
        renderer.set_frame(120)


def test_an_amortized_frame_alone_is_the_frame_of_the_sequence(cli, tmp_path):
    """Baked AO amortized over 3 frames: `--frame 4` replays frames 2 and 3 first, so it draws the bits of frame 4
    of `--frames 0:4`, on another thread count too; and so does set_frame."""
    sets = ["--set", "/materials/water/layers/0/height/size=64",
            "--set", '/materials/water/ao={"mode": "baked", "amortize_frames": 3}', "--width", "96", "--height", "54"]
    run_cli(cli, "render", WATER, "--frames", "0:4", "-o", str(tmp_path / "s_%02d.exr"), "--threads", "2", *sets)
    run_cli(cli, "render", WATER, "--frame", "4", "-o", str(tmp_path / "one.exr"), "--threads", "1", *sets)
    sequence = bits(qdmr.read_image(tmp_path / "s_04.exr"))
    assert numpy.array_equal(sequence, bits(qdmr.read_image(tmp_path / "one.exr")))
    renderer = qdmr.Renderer(threads=1)
    renderer.set_scene(qdmr.load_scene(WATER, {**SMALL, "/materials/water/layers/0/height/size": 64,
                                               "/materials/water/ao": {"mode": "baked", "amortize_frames": 3}}))
    renderer.set_frame(4)
    assert numpy.array_equal(bits(renderer.draw().color), sequence)
