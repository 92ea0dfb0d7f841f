#!/usr/bin/env python3
"""Writes tests/bad_inputs/files/ and tests/bad_inputs/cases.json: the malformed inputs checked by
tests/cli/bad_inputs_corpus_test.cpp. Re-run after editing (needs oiiotool for the few valid images the bad
ones are cut from); the output is deterministic except the files oiiotool made and those cut from them: they carry
its command line, with the absolute path of files/ (so they differ when run in another checkout), and the EXR and
TIFF ones the date written. Special files (FIFOs, sockets, devices, a directory) are not
stored: the test makes them at run time under special/ in its copy of files/ (see the test).

Placeholders in args and messages: {in} is the test's copy of files/, {out} its empty output folder."""
import json, os, shutil, struct, subprocess, zlib

HERE = os.path.dirname(os.path.abspath(__file__))
FILES = os.path.join(HERE, "files")
cases = []
generated = []  # large files: written by the test from prefix + repeat * count + suffix, not stored


def put(rel, data):
    if data is None:
        return  # written by put_big
    path = os.path.join(FILES, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def put_big(rel, *parts):
    """A large file, not stored: the test writes text * count for each (text, count) of parts, in order."""
    generated.append({"path": rel, "parts": [[t, n] for t, n in parts]})
    return "".join(t * n for t, n in parts)


def case(name, args, message, code=2):
    assert all(c["name"] != name for c in cases), name
    cases.append({"name": name, "args": args, "exit": code, "message": message})


def render(*extra, scene="{in}/base.json"):
    return ["render", scene, "-o", "{out}/image.png", *extra]


if os.path.isdir(FILES):
    shutil.rmtree(FILES)
os.makedirs(FILES)

# --- valid inputs the bad ones are made from ------------------------------------------------------------
def oiio(*args):
    subprocess.run(["oiiotool", *args], check=True, capture_output=True)

put("images/.keep", "")
os.remove(os.path.join(FILES, "images/.keep"))
oiio("--pattern", "checker:width=8:height=8", "64x64", "3", "-d", "uint8", "-o", os.path.join(FILES, "images/good.png"))
oiio("--pattern", "fill:topleft=0:topright=1:bottomleft=0:bottomright=1", "64x64", "1", "-d", "uint8",
     "-o", os.path.join(FILES, "images/good_h.png"))
oiio("--pattern", "noise:type=white:seed=3", "64x64", "3", "-d", "uint8", "-o", os.path.join(FILES, "images/noise.jpg"))
oiio("--pattern", "noise:type=white:seed=4", "64x64", "3", "-d", "uint8", "-o", os.path.join(FILES, "images/noise.png"))
oiio("--pattern", "noise:type=white:seed=5", "64x64", "3", "-d", "float", "-o", os.path.join(FILES, "images/noise.exr"))
oiio("--pattern", "noise:type=white:seed=6", "64x64", "3", "-d", "uint8", "-o", os.path.join(FILES, "images/noise.tif"))
oiio("--pattern", "constant:color=0.5,0.5,0.5,0.5,0.5", "8x8", "5", "-d", "uint8", "-o", os.path.join(FILES, "images/five_channels.tif"))
oiio("--pattern", "constant:color=0.5,0.5,0.5", "8x8", "3", "-d", "uint8", "-o", os.path.join(FILES, "images/image.bmp"))
oiio("--pattern", "constant:color=0.5,0.5,0.5", "8x8", "3", "-d", "uint8", "-o", os.path.join(FILES, "images/image.tga"))

def read(rel):
    with open(os.path.join(FILES, rel), "rb") as f:
        return f.read()

png, jpg, exr, tif = read("images/noise.png"), read("images/noise.jpg"), read("images/noise.exr"), read("images/noise.tif")
os.remove(os.path.join(FILES, "images/noise.png"))

base = {
    "output": {"width": 1920, "height": 1080},
    "materials": {"m": {"layers": [{"albedo": "images/good.png", "height": {"file": "images/good_h.png"}}],
                        "technique": {"name": "pom"}}},
    "objects": [{"mesh": {"type": "plane"}, "material": "m"}],
}
put("base.json", json.dumps(base, indent=1))

def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

def png_header_only(w, h, color=2, depth=8):
    return b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, depth, color, 0, 0, 0))

def exr_size_at(data, name, kind):
    """Where the declared size of the attribute name (of type kind) is in an EXR header, and that size."""
    key = name + b"\0" + kind + b"\0"
    at = data.index(key) + len(key)
    return at, struct.unpack_from("<i", data, at)[0]

def exr_window(data, xmin, ymin, xmax, ymax):
    at, size = exr_size_at(data, b"dataWindow", b"box2i")
    assert size == 16
    return data[:at + 4] + struct.pack("<iiii", xmin, ymin, xmax, ymax) + data[at + 20:]

def exr_sized(data, name, kind, size, padding=b""):
    """The attribute name declaring size bytes instead of its own, padding appended to its value."""
    at, old = exr_size_at(data, name, kind)
    return data[:at] + struct.pack("<i", size) + data[at + 4:at + 4 + old] + padding + data[at + 4 + old:]

def jpeg_size(data, w, h):
    """The JPEG with its frame header (SOF0) declaring w x h pixels."""
    at = data.index(b"\xff\xc0") + 5
    return data[:at] + struct.pack(">HH", h, w) + data[at + 4:]

def tiff_gray(w, h, pixels):
    """A little-endian 8-bit grey TIFF of one uncompressed strip declaring w x h pixels, holding pixels."""
    tags = [(256, 4, w), (257, 4, h), (258, 3, 8), (259, 3, 1), (262, 3, 1), (273, 4, 10 + 12 * 9 + 4),
            (277, 3, 1), (278, 4, h), (279, 4, w * h)]
    return (b"II*\0" + struct.pack("<IH", 8, len(tags)) + b"".join(struct.pack("<HHII", t, k, 1, v) for t, k, v in tags)
            + struct.pack("<I", 0) + pixels)

def jpeg_segment(marker, payload):
    return bytes([0xFF, marker]) + struct.pack(">H", len(payload) + 2) + payload

# Photoshop's image resource 0x0404 (IPTC) holding a record (1C 02 ...) that claims 32752 bytes.
iptc_past_end = b"8BIM\x04\x04\0\0" + struct.pack(">I", 12) + b"\x1c\x02\x78\x7f\xf0caption"

# --- bad images: (file, reason fragment) --------------------------------------------------------------
images = [
    ("empty.png", b"", "is empty (0 bytes)"),
    ("text.png", b"this is not an image\n", "cannot read"),
    ("garbage.png", bytes((i * 7919) % 256 for i in range(4096)), "cannot read"),
    ("png_signature_only.png", png[:8], "cannot read"),
    ("png_header_only.png", png_header_only(64, 64), "cannot read"),
    ("png_truncated_half.png", png[: len(png) // 2], "cannot read"),
    ("png_truncated_last_byte.png", png[:-13], "cannot read"),
    ("png_bad_crc.png", png[:40] + bytes([png[40] ^ 0xFF]) + png[41:], "cannot read"),
    ("png_zero_width.png", png_header_only(0, 64) + png[33:], "cannot read"),
    ("png_huge.png", png_header_only(100000, 100000) + png[33:], "cannot read"),
    ("png_wide.png", png_header_only(20000, 1) + png[33:], "outside 1..16384"),
    # libpng allocates and clears a chunk's declared length before reading it.
    ("png_chunk_past_end.png", png_header_only(64, 64) + struct.pack(">I", 7000000) + b"zTXt" + bytes(100) +
     png_chunk(b"IEND", b""), "truncated PNG (the chunk at byte 33 claims 7000000 bytes"),
    # Found by fuzz_obj (as an MTL bump map): every chunk fits, but the file ends before IEND; OpenImageIO read
    # past the end and leaked its error string. Refused by qdmr's chunk walk before the decoder opens it.
    ("png_no_iend.png", png_header_only(64, 64) + png_chunk(b"tEXt", b"k\0v") + b"\x00",
     "truncated PNG (it does not end with an IEND chunk)"),
    ("jpeg_truncated_half.jpg", jpg[: len(jpg) // 2], "truncated JPEG"),
    ("jpeg_truncated_end.jpg", jpg[:-2], "truncated JPEG"),
    ("jpeg_soi_only.jpg", jpg[:2], "cannot read"),
    ("jpeg_header_only.jpg", jpg[:300], "cannot read"),
    # Found by fuzz_image: OpenImageIO 2.4's IPTC decoder read past a Photoshop (APP13) segment whose record
    # claims more bytes than the segment has (a heap-buffer-overflow under ASan). qdmr walks a JPEG's segments
    # first: metadata segments are dropped before the reader sees the file (a JPEG with whole ones reads fine:
    # tests/io/jpeg_segments_test.cpp), and a file whose segments are not whole is refused, as these two.
    ("jpeg_not_a_marker_then_iptc.jpg", jpg[:2] + b"\xff\x00" * 4 + jpeg_segment(0xED, b"Photoshop 3.0\0" + iptc_past_end)
     + jpg[2:], "damaged JPEG (byte 2 is not a marker, before the first scan)"),
    ("jpeg_iptc_past_end.jpg", jpg[:2] + b"\xff\xed\x7f\xff" + b"Photoshop 3.0\0" + iptc_past_end,
     "truncated JPEG (the FFED segment at byte 2 claims 32767 bytes after its marker"),
    ("exr_truncated.exr", exr[: len(exr) // 2], "cannot read"),
    ("exr_magic_only.exr", exr[:4], "cannot read"),
    # Header fields OpenEXR allocates from before anything is checked: refused by qdmr's walk of the header.
    ("exr_attribute_past_end.exr", exr[:8] + b"comments\0string\0" + struct.pack("<i", 200000000) + b"x" * 64,
     "attribute 'comments' claims 200000000 bytes"),
    ("exr_data_window_huge.exr", exr_window(exr, 0, 0, 99999, 99999), "size 100000x100000 is outside 1..16384"),
    ("tiff_truncated.tif", tif[: len(tif) // 2], "cannot read"),
    ("tiff_header_only.tif", tif[:8], "cannot read"),
    ("five_channels.tif", None, "5 channels (textures take 1 to 4)"),
    ("image.bmp", None, "unsupported image format 'bmp'"),
    ("image.tga", None, "unsupported image format"),
    ("pgm_maxval_0.pgm", b"P5\n4 4\n0\n" + bytes(16), "PNM maxval 0 is outside 1..65535"),
    ("ppm_maxval_0.ppm", b"P6\n4 4\n0\n" + bytes(48), "PNM maxval 0 is outside 1..65535"),
    ("pgm_ascii_maxval_0.pgm", b"P2\n2 2\n0\n0 0 0 0\n", "PNM maxval 0 is outside 1..65535"),
    ("pgm_maxval_too_big.pgm", b"P5\n4 4\n70000\n" + bytes(32), "PNM maxval 70000 is outside 1..65535"),
    ("pgm_zero_width.pgm", b"P5\n0 4\n255\n", "is empty"),
    ("pgm_zero_height.pgm", b"P5\n4 0\n255\n", "is empty"),
    ("pgm_negative_width.pgm", b"P5\n-4 4\n255\n" + bytes(16), "cannot read"),
    ("pgm_no_maxval.pgm", b"P5\n4 4\n", "cannot read"),
    ("pgm_truncated.pgm", b"P5\n64 64\n255\n" + bytes(100), "truncated"),
    ("pgm_16bit_truncated.pgm", b"P5\n16 16\n65535\n" + bytes(256), "truncated"),
    ("ppm_truncated.ppm", b"P6\n16 16\n255\n" + bytes(16 * 16 * 3 - 1), "truncated"),
    ("pbm_truncated.pbm", b"P4\n64 64\n" + bytes(10), "truncated"),
    ("pgm_huge.pgm", b"P5\n100000 100000\n255\n" + bytes(16), "outside 1..16384"),
    ("pgm_garbage_header.pgm", b"P5\nfoo bar\n255\n", "cannot read"),
    # Small files declaring large images (fuzz_image's slow units: seconds and gigabytes before the decoder gave
    # up); qdmr refuses them without committing the image's memory. A plain PNM needs a byte per value at least.
    ("tiff_declares_16384x16384.tif", tiff_gray(16384, 16384, bytes(64)), "cannot read"),
    ("png_declares_16384x10240.png", png_header_only(16384, 10240, color=0) + png_chunk(b"IDAT", zlib.compress(bytes(100)))
     + png_chunk(b"IEND", b""), "cannot read"),
    ("jpeg_declares_16384x10240.jpg", jpeg_size(jpg, 16384, 10240), "cannot read"),
    ("exr_declares_16384x10240.exr", exr_window(exr, 0, 0, 16383, 10239), "cannot read"),
    ("pgm_ascii_declares_16384x10240.pgm", b"P2\n16384 10240\n255\n0 0 0 0\n", "truncated: the header promises 167772160 values"),
    ("pbm_ascii_declares_16384x16384.pbm", b"P1\n16384 16384\n0101\n", "truncated: the header promises 268435456 values"),
    ("ppm_ascii_one_value_short.ppm", b"P3\n2 2\n255\n" + b"0 " * 11, "cannot read"),
    # OpenEXR 3.1 reads a known attribute type by its type, not its declared size, and the next attribute from
    # where that value ended; qdmr's header walk requires the declared size. The R, G, B channel list is 55 bytes.
    ("exr_channel_list_longer_than_declared.exr", exr_sized(exr, b"channels", b"chlist", 54),
     "attribute 'channels' holds a channel list of 55 bytes, it claims 54"),
    ("exr_box_larger_than_its_type.exr", exr_sized(exr, b"dataWindow", b"box2i", 18, bytes(2)),
     "attribute 'dataWindow' of type box2i claims 18 bytes, the type has 16"),
    ("pfm_zero_scale.pfm", b"Pf\n4 4\n0\n" + bytes(64), "its scale '0' is not a finite nonzero number"),
    ("pfm_scale_overflows.pfm", b"Pf\n4 4\n-1e99\n" + bytes(64), "its scale '-1e99' is not a finite nonzero number"),
    ("pfm_no_scale.pfm", b"PF\n4 4\n", "PFM header is malformed (no scale)"),
    ("pfm_truncated.pfm", b"PF\n16 16\n-1.0\n" + bytes(16 * 16 * 12 - 1), "truncated"),
]
for name, data, _ in images:
    if data is not None:
        put("images/" + name, data)

roles = {
    "albedo": lambda f: ["--set", "/materials/m/layers/0/albedo=" + f],
    "height": lambda f: ["--set", '/materials/m/layers/0/height={"file": "%s"}' % f],
    "normal": lambda f: ["--set", "/materials/m/layers/0/normal=" + f],
    "orm": lambda f: ["--set", "/materials/m/layers/0/orm=" + f],
}
for name, _, reason in images:
    stem = name.replace(".", "_")
    for role, option in roles.items():
        case("image_%s_as_%s" % (stem, role), render(*option("images/" + name)), reason)
    case("image_%s_as_bake_input" % stem, ["bake", "cone", "{in}/images/" + name, "-o", "{out}/cone.exr"], reason)
# The blend weights map, another image input.
for name in ["empty.png", "png_truncated_half.png", "pgm_maxval_0.pgm", "jpeg_truncated_half.jpg"]:
    case("image_%s_as_weights" % name.replace(".", "_"),
         render("--set", '/materials/m/layers/-={"height": {"file": "images/good_h.png"}}',
                "--set", "/materials/m/blend/weights/source=file", "--set", "/materials/m/blend/weights/file=images/" + name),
         [r for n, _, r in images if n == name][0])

# --- special files (made by the test under special/): every input kind --------------------------------
specials = {
    "fifo": "is a FIFO (named pipe), not a regular file",
    "socket": "is a socket, not a regular file",
    "zero": "is a character device, not a regular file",
    "urandom": "is a character device, not a regular file",
    "null": "is a character device, not a regular file",
    "folder": "is a directory, not a file",
}
for s, reason in specials.items():
    case("special_%s_as_scene" % s, render(scene="{in}/special/" + s), reason)
    for role, option in roles.items():
        case("special_%s_as_%s" % (s, role), render(*option("special/" + s)), reason)
    case("special_%s_as_obj" % s, render("--set", '/objects/0={"mesh": {"type": "obj", "file": "special/%s"}}' % s), reason)
    put("obj/mtl_is_%s.mtl" % s, "")  # placeholder name kept free; the OBJ names the special file directly
    os.remove(os.path.join(FILES, "obj/mtl_is_%s.mtl" % s))
    put("obj/mtllib_%s.obj" % s, "mtllib ../special/%s\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n" % s)
    case("special_%s_as_mtl" % s, render("--set", '/objects/0={"mesh": {"type": "obj", "file": "obj/mtllib_%s.obj"}}' % s),
         reason if s != "folder" else "is a directory")
    put("obj/map_%s.mtl" % s, "newmtl a\nmap_Kd ../special/%s\n" % s)
    put("obj/map_%s.obj" % s, "mtllib map_%s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n" % s)
    case("special_%s_as_mtl_map" % s, render("--set", '/objects/0={"mesh": {"type": "obj", "file": "obj/map_%s.obj"}}' % s), reason)
    case("special_%s_as_bake_input" % s, ["bake", "cone", "{in}/special/" + s, "-o", "{out}/cone.exr"], reason)
case("device_path_dev_zero_as_scene", render(scene="/dev/zero"), "is a character device")
case("device_path_dev_zero_as_height", render("--set", '/materials/m/layers/0/height={"file": "/dev/zero"}'), "is a character device")
case("device_path_dev_urandom_as_albedo", render("--set", "/materials/m/layers/0/albedo=/dev/urandom"), "is a character device")

# --- MTL maps that are bad files ----------------------------------------------------------------------
for name in ["empty.png", "png_truncated_half.png", "jpeg_truncated_half.jpg", "pgm_maxval_0.pgm", "garbage.png"]:
    stem = name.replace(".", "_")
    for key in ["map_Kd", "disp", "bump", "norm"]:
        put("obj/%s_%s.mtl" % (key, stem), "newmtl a\n%s ../images/%s\n" % (key, name))
        put("obj/%s_%s.obj" % (key, stem), "mtllib %s_%s.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n" % (key, stem))
        case("mtl_%s_%s" % (key, stem), render("--set", '/objects/0={"mesh": {"type": "obj", "file": "obj/%s_%s.obj"}}' % (key, stem)),
             [r for n, _, r in images if n == name][0])

# --- OBJ and MTL files --------------------------------------------------------------------------------
tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
objs = [
    ("empty.obj", "", "is empty (0 bytes)"),
    ("comments_only.obj", "# nothing\n# here\n", "no faces"),
    ("vertices_only.obj", tri, "no faces"),
    ("face_two_vertices.obj", tri + "f 1 2\n", "line 4: a face needs at least 3 vertices, this one has 2"),
    ("face_one_vertex.obj", tri + "f 1\n", "line 4: a face needs at least 3 vertices, this one has 1"),
    ("face_no_vertices.obj", tri + "f\n", "line 4: a face needs at least 3 vertices, this one has 0"),
    ("face_two_then_good.obj", tri + "f 1 2 3\nf 2 3\n", "line 5: a face needs at least 3 vertices"),
    ("face_index_zero.obj", tri + "f 0 1 2\n", "line 4: face index 0"),
    ("face_index_too_big.obj", tri + "f 1 2 4\n", "line 4: position index 4 in '4' is out of range"),
    ("face_index_huge.obj", tri + "f 1 2 99999999999999999999\n", "line 4: cannot read the face index"),
    ("face_index_negative_too_far.obj", tri + "f -1 -2 -4\n", "line 4: position index -4"),
    ("face_index_forward_negative.obj", "f -1 -2 -3\n" + tri, "line 1: position index -1"),
    ("face_uv_out_of_range.obj", tri + "vt 0 0\nf 1/1 2/2 3/1\n", "texture coordinate index 2"),
    ("face_normal_out_of_range.obj", tri + "vn 0 0 1\nf 1//1 2//2 3//1\n", "normal index 2"),
    ("face_index_word.obj", tri + "f a b c\n", "line 4: cannot read the face index 'a'"),
    ("face_index_float.obj", tri + "f 1.5 2 3\n", "cannot read the face index '1.5'"),
    ("face_too_many_slashes.obj", tri + "f 1/1/1/1 2 3\n", "line 4:"),
    ("face_one_megabyte_line.obj", put_big("obj/face_one_megabyte_line.obj", (tri + "f", 1), (" 1 2 3", 180000), ("\n", 1)) and None,
     "a concave face of 540000 corners (23171 of them concave) is too complex to triangulate"),
    ("ngon_collinear_only.obj", "".join("v %d %d 0\n" % (i, 2 * i) for i in range(6)) + "f 1 2 3 4 5 6\n",
     "obj/ngon_collinear_only.obj is degenerate (no area)"),
    ("vertex_nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: position component 'nan' is not a finite number"),
    ("vertex_inf.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: position component 'inf'"),
    ("vertex_minus_inf.obj", "v 0 0 0\nv 0 -inf 0\nv 0 1 0\nf 1 2 3\n", "line 2: position component '-inf'"),
    ("vertex_overflow.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n", "position of vertex 2 is not finite"),
    ("vertex_huge_exponent.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: position component '1e999'"),
    ("vertex_word.obj", "v 0 0 0\nv one 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: position component 'one'"),
    ("uv_nan.obj", tri + "vt nan 0\nf 1/1 2/1 3/1\n", "line 4: texture coordinate component 'nan'"),
    ("normal_inf.obj", tri + "vn 0 0 inf\nf 1//1 2//1 3//1\n", "line 4: normal component 'inf'"),
    ("binary_garbage.obj", bytes((i * 31337) % 256 for i in range(2048)), None),
    ("missing_mtl.obj", "mtllib nowhere.mtl\n" + tri + "f 1 2 3\n", "material library not found"),
    ("unknown_material.obj", "mtllib one.mtl\n" + tri + "usemtl other\nf 1 2 3\n", "not found in .mtl"),
    ("empty_mtl.obj", "mtllib empty.mtl\n" + tri + "f 1 2 3\n", "empty.mtl is empty (0 bytes)"),
    ("mtl_map_missing.obj", "mtllib map_missing.mtl\n" + tri + "usemtl a\nf 1 2 3\n", "file not found"),
    ("long_comment_line.obj", put_big("obj/long_comment_line.obj", ("#", 1), ("x", 2000000), ("\n" + tri + "f 1 2\n", 1)) and None, "line 5: a face needs at least 3 vertices"),
    ("long_vertex_line.obj", put_big("obj/long_vertex_line.obj", ("v 0 0 0 ", 1), ("1 ", 500000), ("\nv 1 0 0\nv 0 1 0\nf 1 2\n", 1)) and None, "line 4: a face needs at least 3 vertices"),
]
for name, text, message in objs:
    put("obj/" + name, text)
put("obj/one.mtl", "newmtl one\nKd 1 0 0\n")
put("obj/empty.mtl", "")
put("obj/map_missing.mtl", "newmtl a\nmap_Kd nowhere.png\n")
for name, _, message in objs:
    if message is None:
        continue
    case("obj_" + name.replace(".", "_"), render("--set", '/objects/0={"mesh": {"type": "obj", "file": "obj/%s"}}' % name), message)
# N-gons qdmr accepts (`qdmr plan` says what they became; nothing is written): a convex 1000-gon, a concave
# 100-gon (a star), a self-intersecting one (a pentagram: each corner joined to the second next) and a collinear
# one beside a triangle, dropped and counted.
import math
def ngon(points):
    return "".join("v %.9f %.9f 0\n" % p for p in points) + "f " + " ".join(str(i + 1) for i in range(len(points))) + "\n"
ngons = [
    ("ngon_convex_1000.obj", ngon([(math.cos(2 * math.pi * i / 1000), math.sin(2 * math.pi * i / 1000)) for i in range(1000)]),
     "1000 vertices, 998 triangles"),
    ("ngon_concave_100.obj", ngon([((1.0 if i % 2 == 0 else 0.35) * math.cos(2 * math.pi * i / 100),
                                    (1.0 if i % 2 == 0 else 0.35) * math.sin(2 * math.pi * i / 100)) for i in range(100)]),
     "100 vertices, 98 triangles"),
    ("face_300_corners_on_3_points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf " + " ".join(["1", "2", "3"] * 100) + "\n",
     "3 vertices, 298 triangles"),  # a triangle wound 100 times: it crosses itself, n - 2 triangles
    ("ngon_self_intersecting.obj", ngon([(math.cos(2 * math.pi * (2 * i % 5) / 5), math.sin(2 * math.pi * (2 * i % 5) / 5)) for i in range(5)]),
     "5 vertices, 3 triangles"),
    ("ngon_collinear.obj", tri + "".join("v %d %d 1\n" % (i, 2 * i) for i in range(6)) + "f 1 2 3\nf 4 5 6 7 8 9\n",
     "3 vertices, 1 triangles, 0.00 MiB, 1 degenerate faces dropped"),
]
for name, text, message in ngons:
    put("obj/" + name, text)
    case("obj_" + name.replace(".", "_"), ["plan", "{in}/base.json", "--set", '/objects/0={"mesh": {"type": "obj", "file": "obj/%s"}}' % name],
         message, code=0)
case("obj_binary_garbage_obj", render("--set", '/objects/0={"mesh": {"type": "obj", "file": "obj/binary_garbage.obj"}}'), "obj/binary_garbage.obj")

# --- scene files -------------------------------------------------------------------------------------
scenes = [
    ("empty.json", "", "is empty (0 bytes)"),
    ("whitespace.json", "  \n\n ", "parse error at line 3"),
    ("truncated.json", json.dumps(base)[:60], "parse error"),
    ("trailing_comma.json", '{"objects": [],}', "parse error"),
    ("comment.json", '// a scene\n{"objects": []}', "parse error at line 1"),
    ("nan_literal.json", '{"output": {"width": NaN}, "objects": []}', "parse error"),
    ("number_overflow.json", '{"output": {"width": 1e400}, "objects": []}', "number_overflow.json: number overflow parsing '1e400'"),
    ("width_float_overflow.json", '{"output": {"width": 1e300}, "objects": []}', "expected a finite number"),
    ("null_root.json", "null", "expected an object, got null"),
    ("array_root.json", "[]", "expected an object, got array"),
    ("string_root.json", '"scene"', "expected an object, got string"),
    ("nested_100.json", "[" * 100 + "]" * 100, "nesting deeper than 64 levels"),
    ("nested_100000.json", put_big("scenes/nested_100000.json", ("[", 100000), ("]", 100000)) and None, "nesting deeper than 64 levels"),
    ("nested_objects.json", '{"a":' * 1000 + "1" + "}" * 1000, "nesting deeper than 64 levels"),
    ("nested_unclosed.json", put_big("scenes/nested_unclosed.json", ("[", 1000000)) and None, "nesting deeper than 64 levels"),
    ("binary.json", bytes((i * 7) % 256 for i in range(1000)), "parse error"),
    ("utf16.json", '{"objects": []}'.encode("utf-16"), "parse error"),
    ("long_key.json", put_big("scenes/long_key.json", ('{"', 1), ("k", 1000000), ('": 1, "objects": []}', 1)) and None, "unknown key 'kkkkkkkk"),
    ("long_string.json", put_big("scenes/long_string.json", ('{"materials": {"m": {"layers": [{"albedo": "', 1), ("a", 100000), ('"}]}}, "objects": []}', 1)) and None, "File name too long"),
    ("width_zero.json", '{"output": {"width": 0}, "objects": []}', "/output/width: must be an integer from 1 to 16384, got 0"),
    ("width_negative.json", '{"output": {"width": -1}, "objects": []}', "/output/width: must be an integer from 1 to 16384, got -1"),
    ("width_fraction.json", '{"output": {"width": 1.5}, "objects": []}', "/output/width: expected an integer, got 1.5"),
    ("width_string.json", '{"output": {"width": "wide"}, "objects": []}', "/output/width: expected a number, got string"),
    ("too_many_pixels.json", '{"output": {"width": 16384, "height": 16384}, "objects": []}', "more than the limit"),
    ("fov_zero.json", '{"camera": {"fov_deg": 0}, "objects": []}', "/camera/fov_deg"),
    ("fov_180.json", '{"camera": {"fov_deg": 180}, "objects": []}', "/camera/fov_deg"),
    ("near_after_far.json", '{"camera": {"near": 10, "far": 1}, "objects": []}', "/camera/"),
    ("unknown_key.json", '{"outptu": {}, "objects": []}', "unknown key 'outptu'; did you mean 'output'?"),
    ("unknown_material.json", '{"objects": [{"mesh": {"type": "plane"}, "material": "none"}]}', "/objects/0/material"),
    ("objects_not_array.json", '{"objects": {}}', "/objects: expected an array"),
    ("mesh_unknown_type.json", '{"objects": [{"mesh": {"type": "teapot"}}]}', "/objects/0/mesh/type: unknown value 'teapot'"),
    ("obj_missing_file.json", '{"objects": [{"mesh": {"type": "obj", "file": "nothing.obj"}}]}', "file not found"),
    ("obj_empty_path.json", '{"objects": [{"mesh": {"type": "obj", "file": ""}}]}', "expected a file path, got an empty string"),
    ("obj_path_is_folder.json", '{"objects": [{"mesh": {"type": "obj", "file": "."}}]}', "is a directory, not a file"),
    ("texture_path_is_folder.json", '{"materials": {"m": {"layers": [{"albedo": "."}]}}, "objects": [{"mesh": {"type": "plane"}, "material": "m"}]}', "is a directory, not a file"),
    ("procedural_size_zero.json", '{"materials": {"m": {"layers": [{"height": {"procedural": "noise", "size": 0}}]}}, "objects": [{"mesh": {"type": "plane"}, "material": "m"}]}', "/materials/m/layers/0/height/size"),
    ("procedural_size_huge.json", '{"materials": {"m": {"layers": [{"height": {"procedural": "noise", "size": 1000000}}]}}, "objects": [{"mesh": {"type": "plane"}, "material": "m"}]}', "/materials/m/layers/0/height/size"),
    ("too_many_layers.json", '{"materials": {"m": {"layers": [{}, {}, {}, {}, {}]}}, "objects": [{"mesh": {"type": "plane"}, "material": "m"}]}', "/materials/m/layers"),
    ("light_nan_direction.json", '{"lights": [{"type": "directional", "direction": [0, 0, 0]}], "objects": []}', "/lights/0/direction"),
]
for name, text, message in scenes:
    put("scenes/" + name, text)
    case("scene_" + name.replace(".", "_"), render(scene="{in}/scenes/" + name), message)
case("scene_missing", render(scene="{in}/scenes/nothing.json"), "file not found")
# A scene larger than the 16 MiB limit: a valid JSON document padded with spaces.
put_big("scenes/oversized.json", ('{"objects": []}', 1), (" ", 16 * 1024 * 1024))
case("scene_oversized", render(scene="{in}/scenes/oversized.json"), "more than the limit of 16777216 bytes for a scene file")

# --- command-line arguments ---------------------------------------------------------------------------
args = [
    ("threads_zero", render("--threads", "0"), "--threads: must be from 1 to 256, got 0"),
    ("threads_negative", render("--threads", "-3"), "--threads: must be from 1 to 256, got -3"),
    ("threads_too_many", render("--threads", "257"), "--threads: must be from 1 to 256, got 257"),
    ("threads_overflow", render("--threads", "99999999999"), "--threads"),
    ("threads_word", render("--threads", "many"), "--threads"),
    ("tile_zero", render("--tile", "0"), "--tile: must be a multiple of 8 between 8 and 1024, got 0"),
    ("tile_seven", render("--tile", "7"), "--tile: must be a multiple of 8 between 8 and 1024, got 7"),
    ("tile_negative", render("--tile", "-8"), "--tile: must be a multiple of 8 between 8 and 1024, got -8"),
    ("tile_huge", render("--tile", "2048"), "--tile: must be a multiple of 8 between 8 and 1024, got 2048"),
    ("width_zero", render("--width", "0"), "/output/width: must be an integer from 1 to 16384, got 0"),
    ("width_negative", render("--width", "-1920"), "/output/width: must be an integer from 1 to 16384, got -1920"),
    ("width_huge", render("--width", "65536"), "/output/width: must be an integer from 1 to 16384, got 65536"),
    ("width_word", render("--width", "wide"), "--width"),
    ("height_zero", render("--height", "0"), "/output/height: must be an integer from 1 to 16384, got 0"),
    ("height_huge", render("--height", "100000"), "/output/height: must be an integer from 1 to 16384"),
    ("pixels_over_limit", render("--width", "16384", "--height", "16384"), "more than the limit"),
    ("max_memory_zero", render("--max-memory", "0"), "--max-memory: must be from 1 to 1073741824 (MiB), got 0"),
    ("max_memory_negative", render("--max-memory", "-5"), "--max-memory: must be from 1 to 1073741824 (MiB), got -5"),
    ("max_memory_exceeded", render("--max-memory", "16"), "more than the limit of 16 MiB (--max-memory)"),
    ("max_memory_big_output", render("--width", "16384", "--height", "8192", "--max-memory", "1024"), "more than the limit of 1024 MiB"),
    ("set_no_equals", render("--set", "camera"), "expected POINTER=VALUE"),
    ("set_no_slash", render("--set", "camera/fov_deg=30"), "the JSON pointer must start with '/'"),
    ("set_bad_escape", render("--set", "/camera~2/fov=1"), "invalid JSON pointer"),
    ("set_root", render("--set", "/=1"), "unknown key ''"),
    ("set_through_number", render("--set", "/output/width/x=1"), "cannot apply --set"),
    ("set_array_index_out_of_range", render("--set", "/objects/7=1"), "no element '7' in /objects"),
    ("set_array_bad_index", render("--set", "/objects/01=1"), "no element '01' in /objects"),
    ("set_empty_array_token", render("--set", "/objects/=1"), "/objects/: cannot apply --set: unresolved reference token ''"),
    ("set_deep_value", render("--set", "/camera/fov_deg=" + "[" * 200 + "]" * 200), "nesting deeper than 64 levels"),
    ("set_wrong_type", render("--set", "/camera/fov_deg=true"), "/camera/fov_deg: expected a number, got boolean"),
    ("set_fov_out_of_range", render("--set", "/camera/fov_deg=0"), "/camera/fov_deg"),
    ("set_long_value", render("--set", "/camera/fov_deg=" + "9" * 5000), "/camera/fov_deg"),
    ("aov_unknown", render("--aov", "albedo={out}/a.exr"), "unknown AOV 'albedo'"),
    ("aov_no_file", render("--aov", "depth"), "expected NAME=FILE"),
    ("aov_empty_name", render("--aov", "={out}/a.exr"), "expected NAME=FILE"),
    ("aov_twice", render("--aov", "depth={out}/a.exr", "--aov", "depth={out}/b.exr"), "AOV 'depth' given twice"),
    ("aov_same_as_output", render("--aov", "depth={out}/image.png"), "is the same file as -o"),
    ("aov_same_as_output_other_spelling", render("--aov", "depth={out}/../out/image.png"), "is the same file as -o"),
    ("aov_same_as_other_aov", render("--aov", "depth={out}/a.exr", "--aov", "normal={out}/./a.exr"), "is the same file as --aov"),
    ("stats_same_as_output", render("--stats", "{out}/image.png"), "is the same file as -o"),
    ("output_jpg", ["render", "{in}/base.json", "-o", "{out}/image.jpg"], "unsupported image type '.jpg'"),
    ("output_no_extension", ["render", "{in}/base.json", "-o", "{out}/image"], "unsupported image type ''"),
    ("output_folder_missing", ["render", "{in}/base.json", "-o", "{out}/missing/image.png"], "folder does not exist"),
    ("output_is_folder", ["render", "{in}/base.json", "-o", "{in}/special/folder.png"], "is a directory, not a file"),
    ("output_is_fifo", ["render", "{in}/base.json", "-o", "{in}/special/fifo.png"], "is a FIFO (named pipe)"),
    ("output_is_device", ["render", "{in}/base.json", "-o", "{in}/special/null.png"], "is a character device"),
    ("output_is_scene", ["render", "{in}/scenes/scene.exr", "-o", "{in}/scenes/scene.exr"], "refusing to overwrite an input of this job"),
    ("output_is_scene_other_spelling", ["render", "{in}/scenes/scene.exr", "-o", "{in}/images/../scenes/scene.exr"], "refusing to overwrite an input of this job"),
    ("output_is_albedo", ["render", "{in}/base.json", "-o", "{in}/images/good.png"], "refusing to overwrite an input of this job: {in}/images/good.png"),
    ("output_is_height", ["render", "{in}/base.json", "-o", "{in}/images/good_h.png"], "refusing to overwrite an input of this job: {in}/images/good_h.png"),
    ("output_is_albedo_via_dots", ["render", "{in}/base.json", "-o", "{in}/obj/../images/good.png"], "refusing to overwrite an input of this job"),
    ("output_is_symlink_to_albedo", ["render", "{in}/base.json", "-o", "{in}/special/link_to_good.png"], "refusing to overwrite an input of this job"),
    ("output_is_hard_link_to_albedo", ["render", "{in}/base.json", "-o", "{in}/special/hardlink_to_good.png"], "refusing to overwrite an input of this job"),
    ("aov_is_height", render("--aov", "depth={in}/images/good_h.png"), "refusing to overwrite an input of this job"),
    ("stats_is_scene", render("--stats", "{in}/base.json"), "refusing to overwrite an input of this job: {in}/base.json"),
    ("output_is_mtl_map", ["render", "{in}/base.json", "--set", '/objects/0={"mesh": {"type": "obj", "file": "obj/textured.obj"}}',
                           "-o", "{in}/obj/textured.png"], "refusing to overwrite an input of this job"),
    ("output_is_obj_texture_hard_link", ["render", "{in}/base.json", "--set", '/objects/0={"mesh": {"type": "obj", "file": "obj/textured.obj"}}',
                                         "-o", "{in}/special/hardlink_to_textured.png"], "refusing to overwrite an input of this job"),
    ("bake_output_is_input", ["bake", "cone", "{in}/images/good.exr", "-o", "{in}/images/good.exr"], "refusing to overwrite an input of this job"),
    ("bake_output_not_exr", ["bake", "cone", "{in}/images/good_h.png", "-o", "{out}/cone.png"], "the cone map is written as .exr"),
    ("bake_kind", ["bake", "cone", "{in}/images/good_h.png", "-o", "{out}/cone.exr", "--kind", "loose"], "unknown cone kind"),
    ("bake_channel", ["bake", "cone", "{in}/images/good_h.png", "-o", "{out}/cone.exr", "--channel", "x"], "unknown channel"),
    ("bake_channel_absent", ["bake", "cone", "{in}/images/good_h.png", "-o", "{out}/cone.exr", "--channel", "a"], "no channel 'a'"),
    ("bake_address", ["bake", "cone", "{in}/images/good_h.png", "-o", "{out}/cone.exr", "--address", "repeat"], "unknown address mode"),
    ("bake_missing_input", ["bake", "cone", "{in}/images/none.png", "-o", "{out}/cone.exr"], "file not found"),
    ("plan_unknown_aov", ["plan", "{in}/base.json", "--aov", "albedo"], "unknown AOV 'albedo'"),
    ("plan_special_scene", ["plan", "{in}/special/fifo"], "is a FIFO"),
    ("unknown_subcommand", ["draw", "{in}/base.json"], "A subcommand is required"),
    ("unknown_option", render("--widht", "5"), "--widht"),
    ("missing_output", ["render", "{in}/base.json"], "--output is required"),
    ("missing_scene", ["render", "-o", "{out}/image.png"], "scene is required"),
    ("bake_no_subcommand", ["bake"], "A subcommand is required"),
]
for name, a, message in args:
    case("arg_" + name, a, message)
put("scenes/scene.exr", json.dumps(base).replace("images/", "../images/"))
oiio("--pattern", "constant:color=0.5", "16x16", "1", "-d", "float", "-o", os.path.join(FILES, "images/good.exr"))
shutil.copy(os.path.join(FILES, "images/good.png"), os.path.join(FILES, "obj/textured.png"))
put("obj/textured.mtl", "newmtl a\nmap_Kd textured.png\n")
put("obj/textured.obj", "mtllib textured.mtl\n" + tri + "vt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n")

# The orm texture (occlusion, roughness, metalness) and its occlusion.
orm = "/materials/m/layers/0/orm="
for name, args, message in [
    ("orm_missing", ["--set", orm + "images/none.png"], "/materials/m/layers/0/orm: file not found"),
    ("orm_one_channel", ["--set", orm + "images/good.exr"], "has 1 channel(s); an orm texture needs 3"),
    ("orm_occlusion_other_size", ["--set", orm + "images/good.png", "--set", '/materials/m/layers/0/occlusion={"file": "images/good.exr"}'],
     "is 16x16, the layer's orm 64x64: they must be the same size"),
    ("orm_occlusion_missing", ["--set", '/materials/m/layers/0/occlusion={"file": "images/none.png"}'], "/materials/m/layers/0/occlusion/file: file not found"),
    ("orm_occlusion_rgb", ["--set", '/materials/m/layers/0/occlusion={"file": "images/good.png", "channel": "rgb"}'],
     "an occlusion reads one channel: r, g, b or a"),
    ("orm_constant_above_1", ["--set", orm + '{"constant": [1, 2, 1]}'], "/materials/m/layers/0/orm/constant/1"),
    ("orm_procedural", ["--set", orm + '{"procedural": "noise"}'], "an orm texture is a file path or a constant"),
    ("orm_metallic_above_1", ["--set", "/materials/m/layers/0/metallic=1.5"], "/materials/m/layers/0/metallic"),
    ("orm_on_blend", ["--set", orm + "images/good.png", "--set", '/materials/m/layers/-={"height": {"file": "images/good_h.png"}}'],
     "/materials/m/layers/0/orm: an orm texture is read on a material of one layer, not on a blend"),
]:
    case(name, render(*args), message)

# --- glTF 2.0 assets (mesh/gltf.cpp): each a copy of tests/gltf/assets/quad_embedded.gltf (buffer and image as
# data: URIs, so each file stands alone) or quad.glb with one element broken; rendered on their own ----------------
GLTF_ASSETS = os.path.join(os.path.dirname(HERE), "gltf", "assets")
with open(os.path.join(GLTF_ASSETS, "quad_embedded.gltf")) as f:
    gltf_quad = json.load(f)
with open(os.path.join(GLTF_ASSETS, "quad.glb"), "rb") as f:
    glb_quad = f.read()
put("gltf/secret.bin", b"\0" * 140)

def gltf_case(name, edit, message):
    doc = json.loads(json.dumps(gltf_quad))
    edit(doc)
    put("gltf/%s.gltf" % name, json.dumps(doc, sort_keys=True))
    case("gltf_" + name, ["render", "{in}/gltf/%s.gltf" % name, "-o", "{out}/image.png"], message)

def prim(d):
    return d["meshes"][0]["primitives"][0]

def set_(obj, key, value):
    obj[key] = value

gltf_cases = [
    ("points", lambda d: set_(prim(d), "mode", 0), "/meshes/0/primitives/0/mode: points cannot be drawn"),
    ("lines", lambda d: set_(prim(d), "mode", 1), "/meshes/0/primitives/0/mode: lines cannot be drawn"),
    ("line_strip", lambda d: set_(prim(d), "mode", 3), "lines cannot be drawn"),
    ("morph_targets", lambda d: set_(prim(d), "targets", [{"POSITION": 0}]), "/meshes/0/primitives/0/targets: morph targets cannot be drawn"),
    ("skin", lambda d: (set_(d["nodes"][0], "skin", 0), set_(d, "skins", [{"joints": [0], "inverseBindMatrices": 0}])),
     "/nodes/0/skin: skinned meshes cannot be drawn"),
    ("required_draco", lambda d: (set_(d, "extensionsRequired", ["KHR_draco_mesh_compression"]), set_(d, "extensionsUsed", ["KHR_draco_mesh_compression"])),
     "/extensionsRequired/0: the asset requires KHR_draco_mesh_compression, which qdmr does not read"),
    ("sparse", lambda d: set_(d["accessors"][0], "sparse", {"count": 1, "indices": {"bufferView": 0, "componentType": 5123}, "values": {"bufferView": 0}}),
     "/accessors/0/sparse: sparse accessors are not supported"),
    ("accessor_past_view", lambda d: set_(d["accessors"][0], "count", 5), "/accessors/0/count: 5 elements of 12 bytes"),
    ("accessor_offset_past_view", lambda d: set_(d["accessors"][0], "byteOffset", 40), "/accessors/0/count"),
    ("huge_count", lambda d: set_(d["accessors"][0], "count", 4294967295), "/accessors/0/count: 4294967295 elements"),
    ("view_past_buffer", lambda d: set_(d["bufferViews"][0], "byteLength", 4000), "/bufferViews/0: bytes 0 + 4000 run past the end of buffer 0"),
    ("overlapping_stride", lambda d: set_(d["bufferViews"][0], "byteStride", 8), "/bufferViews/0/byteStride: 8 is less than an element (12 bytes): the elements overlap"),
    ("count_mismatch", lambda d: set_(d["accessors"][1], "count", 3), "/meshes/0/primitives/0/attributes/TEXCOORD_0: 3 elements, but POSITION has 4"),
    ("accessor_missing", lambda d: set_(prim(d)["attributes"], "NORMAL", 42), "/meshes/0/primitives/0/attributes/NORMAL: accessor 42 does not exist"),
    ("index_past_vertices", lambda d: [set_(d["accessors"][k], "count", 2) for k in range(3)], "past the primitive's 2 vertices"),
    ("node_cycle", lambda d: set_(d, "nodes", [{"mesh": 0}, {"children": [2]}, {"children": [1]}]), "the node graph has a cycle"),
    ("node_self_child", lambda d: set_(d["nodes"][0], "children", [0]), "the node graph has a cycle"),
    ("uri_parent", lambda d: set_(d["buffers"][0], "uri", "../gltf/secret.bin"), "/buffers/0/uri: the URI '../gltf/secret.bin' leaves the asset's folder"),
    ("uri_parent_encoded", lambda d: set_(d["buffers"][0], "uri", "%2E%2E/gltf/secret.bin"), "leaves the asset's folder"),
    ("uri_absolute", lambda d: set_(d["buffers"][0], "uri", "/etc/passwd"), "/buffers/0/uri: the URI '/etc/passwd' is an absolute path"),
    ("uri_http", lambda d: set_(d["images"][0], "uri", "http://127.0.0.1:9/a.png"), "/images/0/uri: the URI 'http://127.0.0.1:9/a.png' names a scheme"),
    ("uri_file_scheme", lambda d: set_(d["images"][0], "uri", "file:///etc/passwd"), "names a scheme"),
    ("embedded_image_not_png", lambda d: set_(d["images"][0], "uri", "data:image/png;base64,AAAAAAAA"), "/images/0: an embedded image must be PNG or JPEG"),
    ("no_position", lambda d: prim(d)["attributes"].pop("POSITION"), "/meshes/0/primitives/0/attributes: no POSITION"),
    ("metallic_roughness_texture_missing", lambda d: set_(d["materials"][0]["pbrMetallicRoughness"], "metallicRoughnessTexture", {"index": 9}),
     "/materials/0/pbrMetallicRoughness/metallicRoughnessTexture/index: texture 9 does not exist"),
    ("occlusion_texture_missing", lambda d: set_(d["materials"][0], "occlusionTexture", {"index": 9}),
     "/materials/0/occlusionTexture/index: texture 9 does not exist"),
    ("occlusion_strength_above_1", lambda d: set_(d["materials"][0], "occlusionTexture", {"index": 0, "strength": 2}),
     "/materials/0/occlusionTexture/strength: must be in [0, 1]"),
]
for name, edit, message in gltf_cases:
    gltf_case(name, edit, message)
put("gltf/not_json.gltf", '{"asset": {"version": "2.0"},')
case("gltf_not_json", ["render", "{in}/gltf/not_json.gltf", "-o", "{out}/image.png"], "parse error")
put("gltf/deep.gltf", "[" * 100000 + "]" * 100000)
case("gltf_deep_nesting", ["render", "{in}/gltf/deep.gltf", "-o", "{out}/image.png"], "nesting deeper than 64 levels")

def glb_edit(name, at, value, message):
    data = bytearray(glb_quad)
    struct.pack_into("<I", data, at, value)
    put("gltf/%s.glb" % name, bytes(data))
    case("gltf_" + name, ["render", "{in}/gltf/%s.glb" % name, "-o", "{out}/image.png"], message)

json_length = struct.unpack_from("<I", glb_quad, 12)[0]
glb_edit("glb_header_length_lies", 8, len(glb_quad) + 4, ".glb header: length %d but the file has %d bytes" % (len(glb_quad) + 4, len(glb_quad)))
glb_edit("glb_json_chunk_past_end", 12, 0x7FFFFFF0, ".glb chunk 0: length 2147483632 runs past the end of the file")
glb_edit("glb_bin_chunk_past_end", 20 + json_length, len(glb_quad), ".glb chunk 1: length %d runs past the end of the file" % len(glb_quad))
glb_edit("glb_version_1", 4, 1, ".glb header: version 1")
put("gltf/glb_truncated.glb", glb_quad[:len(glb_quad) // 2])
case("gltf_glb_truncated", ["render", "{in}/gltf/glb_truncated.glb", "-o", "{out}/image.png"], ".glb header: length")
# In a scene: an override of a glTF material the asset lacks, a displacement technique without a height, a node
# the asset lacks.
shutil.copy(os.path.join(GLTF_ASSETS, "quad.glb"), os.path.join(FILES, "gltf/quad.glb"))
case("gltf_unknown_material", render("--set", '/objects/0={"mesh": {"type": "gltf", "file": "gltf/quad.glb"}, "materials": {"chekcer": {}}}'),
     "/objects/0/materials/chekcer: unknown glTF material 'chekcer'; did you mean 'checker'?")
case("gltf_displaced_without_height", render("--set", '/objects/0={"mesh": {"type": "gltf", "file": "gltf/quad.glb"}, "materials": {"checker": {"technique": {"name": "qdm"}}}}'),
     "a displacement technique needs a height: give this glTF material one in 'layers'[0].height")
case("gltf_override_both_forms", render("--set", '/objects/0={"mesh": {"type": "gltf", "file": "gltf/quad.glb"}, "materials": {"checker": {"height": "gltf/quad.glb", "layers": [{}]}}}'),
     "/objects/0/materials/checker/height: give 'height' in 'layers'[0] or beside 'technique', not both")
case("gltf_override_two_layers", render("--set", '/objects/0={"mesh": {"type": "gltf", "file": "gltf/quad.glb"}, "materials": {"checker": {"layers": [{}, {}]}}}'),
     "/objects/0/materials/checker/layers: a glTF material has one layer: 'layers' takes one element, not 2 (it cannot become a blend; a blend is a scene material named by the object's 'material')")
case("gltf_unknown_node", render("--set", '/objects/0={"mesh": {"type": "gltf", "file": "gltf/quad.glb", "node": "qaud"}}'),
     "the asset has no node named 'qaud'; did you mean 'quad'?")
case("gltf_plan_points", ["plan", "{in}/gltf/points.gltf"], "points cannot be drawn")


# Animation (issue #58): frame ranges and output names are checked before anything is rendered; time-dependent
# patterns are checked when the scene loads.
ANIMATED = ["--set", '/animation={"frames": 10}', "--set",
            '/materials/m/layers/0/height={"procedural": "waves", "size": 64, "waves": [{"wavelength": 0.25, "speed": 0.1}]}']
def frames(*extra, out="{out}/f_%04d.png"):
    return ["render", "{in}/base.json", "-o", out, *ANIMATED, *extra]
case("frames_reversed", frames("--frames", "5:2"), "--frames 5:2: the first frame is after the last")
case("frames_past_the_end", frames("--frames", "0:10"), "--frames 0:10: the scene's animation has frames 0 to 9")
case("frames_not_integers", frames("--frames", "0:x"), "--frames 0:x: 'x' is not an integer")
case("frames_step_zero", frames("--frames", "0:4:0"), "--frames 0:4:0: the step must be at least 1")
case("frames_one_number", frames("--frames", "3"), "--frames 3: expected FIRST:LAST or FIRST:LAST:STEP")
case("frames_output_without_number", frames("--frames", "0:3", out="{out}/image.png"),
     "-o {out}/image.png: names no frame number")
case("frames_aov_without_number", frames("--frames", "0:3", "--aov", "depth={out}/depth.exr"),
     "--aov {out}/depth.exr: names no frame number")
case("frames_bad_percent", frames("--frames", "0:3", out="{out}/f_%s.png"), "a '%' starts a frame number")
case("frames_two_numbers", frames("--frames", "0:3", out="{out}/f_%d_%d.png"), "holds more than one frame number")
case("frame_past_the_end", frames("--frame", "10"), "--frame 10: the scene's animation has frames 0 to 9")
case("frame_without_animation", render("--frame", "0"), "has no /animation (frames and fps) to take frames from")
case("animation_zero_frames", render("--set", '/animation={"frames": 0}'), "/animation/frames")
case("waves_wavelength_too_long", render("--set", '/materials/m/layers/0/height={"procedural": "waves", "waves": [{"wavelength": 3}]}'),
     "/materials/m/layers/0/height/waves/0/wavelength: a wavelength of 3 along this direction has no whole cycle")
case("waves_wavelength_below_two_texels", render("--set", '/materials/m/layers/0/height={"procedural": "waves", "size": 16, "waves": [{"wavelength": 0.01}]}'),
     "is shorter than two texels of a 16-texel pattern")
case("waves_on_another_pattern", render("--set", '/materials/m/layers/0/height={"procedural": "cobbles", "waves": [{}]}'),
     "/materials/m/layers/0/height/waves: only the 'waves' pattern has waves")
case("waves_without_waves", render("--set", '/materials/m/layers/0/height={"procedural": "waves"}'),
     "/materials/m/layers/0/height: missing key 'waves'")
# AO amortized over frames: a whole number of frames from 1 to 64.
def amortized(k):
    return frames("--frames", "0:1", "--set", '/materials/m/ao={"mode": "baked", "amortize_frames": %s}' % k)
case("ao_amortize_zero", amortized("0"), "/materials/m/ao/amortize_frames: must be an integer from 1 to 64, got 0")
case("ao_amortize_negative", amortized("-3"), "/materials/m/ao/amortize_frames: must be an integer from 1 to 64, got -3")
case("ao_amortize_huge", amortized("1e12"), "/materials/m/ao/amortize_frames: must be an integer from 1 to 64")
case("ao_amortize_not_an_integer", amortized("2.5"), "/materials/m/ao/amortize_frames: expected an integer, got 2.5")
case("ao_amortize_a_string", amortized('"4"'), "/materials/m/ao/amortize_frames")
case("cone_map_on_a_dynamic_height", frames("--frames", "0:1", "--set", "/materials/m/technique/name=csm"),
     "/materials/m/technique/name: 'csm' marches a cone map baked from the heights, and this material's heights change every frame")

# Height layers from file sequences (issue #58): every frame's file is checked when the scene loads, before
# anything is rendered. Frames 0, 1 and 3 of h_%04d.pgm exist (2 is missing); d_0001.pgm is smaller than d_0000.pgm.
def pgm(side, value):
    return b"P5\n%d %d\n255\n" % (side, side) + bytes([value]) * (side * side)
for n in (0, 1, 3):
    put("seq/h_%04d.pgm" % n, pgm(8, 40 * n))
put("seq/d_0000.pgm", pgm(8, 10))
put("seq/d_0001.pgm", pgm(4, 20))
def sequence(height, frames=4):
    return render("--set", '/animation={"frames": %d}' % frames, "--set", "/materials/m/layers/0/height=" + height)
case("sequence_missing_frame", sequence('{"file": "seq/h_%04d.pgm"}'),
     "/materials/m/layers/0/height/file: frame 2 of the animation: file not found: {in}/seq/h_0002.pgm")
case("sequence_sizes_differ", sequence('{"file": "seq/d_%04d.pgm"}', 2),
     "/materials/m/layers/0/height/file: frame 1 of the animation, {in}/seq/d_0001.pgm, is 4x4 8-bit, frame 0's is 8x8 8-bit")
case("sequence_names_no_file", sequence('"seq/none_%04d.pgm"'),
     "/materials/m/layers/0/height: names no file: none of none_0000.pgm to none_0003.pgm exists in {in}/seq")
case("sequence_bad_percent", sequence('{"file": "seq/h_%4d.pgm"}'),
     "/materials/m/layers/0/height/file: a '%' starts a frame number written %d or %0Nd")
case("sequence_two_numbers", sequence('{"file": "seq/h_%04d_%d.pgm"}'), "/materials/m/layers/0/height/file: holds more than one frame number")
case("sequence_range_reversed", sequence('{"file": "seq/h_%04d.pgm", "frames": "3:0"}'),
     "/materials/m/layers/0/height/frames: the first frame is after the last")
case("sequence_range_not_a_range", sequence('{"file": "seq/h_%04d.pgm", "frames": "0-3"}'),
     "/materials/m/layers/0/height/frames: expected FIRST:LAST or FIRST:LAST:STEP")
case("sequence_range_negative", sequence('{"file": "seq/h_%04d.pgm", "frames": "-1:3"}'),
     "/materials/m/layers/0/height/frames: frame numbers start at 0")
case("sequence_range_too_short", sequence('{"file": "seq/h_%04d.pgm", "frames": "0:3:2"}'),
     "/materials/m/layers/0/height/frames: numbers 2 files, fewer than the animation's 4 frames")
case("sequence_frames_without_number", sequence('{"file": "images/good_h.png", "frames": "0:3"}'),
     "/materials/m/layers/0/height/frames: only a frame-numbered file (e.g. h_%04d.exr) has frames")

# Camera keyframes (issue #58): checked when the scene loads.
def keyframes(keys, extra="", frames=10):
    return render("--set", '/animation={"frames": %d}' % frames,
                  "--set", '/camera={"keyframes": [%s]%s}' % (keys, extra))
KEY0 = '{"frame": 0, "position": [0, -3, 2], "target": [0, 0, 0]}'
KEY5 = '{"frame": 5, "position": [1, -3, 2], "target": [0, 0, 0]}'
case("keyframes_unsorted", keyframes(KEY5 + ", " + KEY0),
     "/camera/keyframes/1/frame: keyframes are listed by frame: 0 comes after 5")
case("keyframes_duplicate_frame", keyframes(KEY0 + ", " + KEY0), "/camera/keyframes/1/frame: two keyframes at frame 0")
case("keyframes_missing_position", keyframes('{"frame": 0, "target": [0, 0, 0]}'),
     "/camera/keyframes/0: missing key 'position'")
case("keyframes_missing_frame", keyframes('{"position": [0, -3, 2], "target": [0, 0, 0]}'),
     "/camera/keyframes/0: missing key 'frame'")
case("keyframes_outside_the_animation", keyframes(KEY0 + ', {"frame": 10, "position": [1, -3, 2], "target": [0, 0, 0]}'),
     "/camera/keyframes/1/frame: frame 10 is outside the animation's frames 0 to 9")
case("keyframes_none", keyframes(""), "/camera/keyframes: expected at least one keyframe")
case("keyframes_and_a_position", keyframes(KEY0, ', "position": [0, -3, 2]'),
     "/camera/position: a camera with keyframes takes its position from them")
case("keyframes_unknown_interpolation", keyframes(KEY0, ', "interpolation": "cubic"'),
     "/camera/interpolation: unknown value 'cubic'")
case("interpolation_without_keyframes", render("--set", '/camera={"interpolation": "smooth"}'),
     "/camera/interpolation: only a camera with keyframes interpolates")
case("keyframes_view_collapses", keyframes('{"frame": 0, "position": [0, -1, 1], "target": [0, 1, 1]}, '
                                           '{"frame": 2, "position": [0, 1, 1], "target": [0, -1, 1]}'),
     "/camera/keyframes: at frame 1, the target must differ from the position")

with open(os.path.join(HERE, "cases.json"), "w") as f:
    json.dump({"comment": "Written by make_corpus.py; checked by tests/cli/bad_inputs_corpus_test.cpp.",
               "generated": generated, "cases": cases},
              f, indent=1)
files = sum(len(fs) for _, _, fs in os.walk(FILES))
print("%d cases, %d files stored, %d generated by the test" % (len(cases), files, len(generated)))
