#!/usr/bin/env python3
"""Writes the glTF test assets under tests/gltf/assets/ (and the glTF example and scene assets): small, exact,
deterministic (no timestamps, zlib level 9). Re-run after editing and commit what it writes (the goldens of
tests/golden/gltf_assets.json and the expectations of tests/mesh/gltf_test.cpp are made from these files).

  quad.gltf + quad.bin + checker.png   a textured quad (external buffer and image), the same quad as quad.obj + quad.mtl
  quad_embedded.gltf                   the same asset with its buffer and image as data: URIs
  quad_tinted.gltf                     the quad with a baseColorFactor over its texture, and metal; ../quad_tinted_gltf.json
                                       draws it, ../quad_tinted_obj.json the OBJ quad with the qdmr material it maps to
                                       (albedo file x factor, Cook-Torrance F0 and roughness): the same bits
  quad_orm.gltf + orm.png              the quad with one image as metallicRoughnessTexture and occlusionTexture (R
                                       occlusion, G roughness, B metalness: gradients and a metal half)
  quad_orm_split.gltf                  the same with occlusion.png (grey: orm.png's R) and metal_rough.png (orm.png's
                                       G and B, R not occlusion): qdmr packs them into orm.png's texture, the same bits
  quad_orm_white.gltf + white.png      quad.gltf's material with a white 1x1 metallicRoughnessTexture and
                                       occlusionTexture (metallicFactor 0): quad.gltf's bits (the texture changes nothing)
  quad.glb                             the same asset as one .glb: the buffer in the BIN chunk, the image in a buffer view
  hierarchy.gltf                       a node hierarchy (TRS with a quaternion, a matrix, a scale) and a camera node
  indices.gltf                         four quads: 8-, 16-, 32-bit indices and none; normals left out of the last (flat)
  sparse.gltf                          a sparse accessor: refused (qdmr does not read sparse accessors)
  wall.glb                             a brick-coloured wall with a normal map and a sampler, for the displaced
                                       example (examples/gltf/) and the shipped scene (scenes/gltf_wall.json)

glTF is +Y up; qdmr turns it +Z up ((x, y, z) -> (x, -z, y)), so the quad lies in glTF's XZ plane facing +Y and
lands exactly on quad.obj's XY plane facing +Z."""
import base64, json, math, os, struct, sys, zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ASSETS = os.path.join(HERE, "assets")
ROOT = os.path.dirname(os.path.dirname(HERE))


def png(width, height, channels, pixels):
    """An 8-bit PNG, rows top first, `pixels` a flat list of width*height*channels values."""
    kind = {1: 0, 3: 2, 4: 6}[channels]
    raw = b"".join(b"\0" + bytes(pixels[y * width * channels:(y + 1) * width * channels]) for y in range(height))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, kind, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def checker(size=16, cells=4):
    out = []
    for y in range(size):
        for x in range(size):
            on = ((x * cells // size) + (y * cells // size)) % 2
            out += [220, 180, 40] if on else [40, 90, 200]
            if y < size // cells and x < size // cells:  # the top-left cell red: shows which way up the image is
                out[-3:] = [230, 30, 30]
    return png(size, size, 3, out)


def bricks(size=64):
    """Albedo, tangent-space normal map (OpenGL convention) and height of 4 x 8 bricks, rows top first."""
    albedo, normal, height = [], [], []
    for y in range(size):
        for x in range(size):
            row = y // (size // 8)
            bx = (x + (row % 2) * (size // 8)) % (size // 4)
            by = y % (size // 8)
            mortar = bx < 2 or by < 2
            h = 0 if mortar else 255
            height.append(h)
            albedo += [150, 140, 130] if mortar else [170 + (row * 7) % 30, 70 + (row * 11) % 20, 50]
            # the slope at the brick's left and bottom edges, pointing out of the mortar
            nx = 0.6 if bx in (2, 3) else 0.0
            ny = -0.6 if by in (2, 3) else 0.0
            nz = math.sqrt(max(0.0, 1.0 - nx * nx - ny * ny))
            normal += [round(127.5 + 127.5 * nx), round(127.5 + 127.5 * ny), round(127.5 + 127.5 * nz)]
    return png(size, size, 3, albedo), png(size, size, 3, normal), png(size, size, 1, height)


class Buffer:
    """One glTF buffer built from views; accessors refer to views by index."""

    def __init__(self):
        self.data = bytearray()
        self.views, self.accessors = [], []

    def view(self, data, target=None, stride=None):
        while len(self.data) % 4:
            self.data.append(0)
        v = {"buffer": 0, "byteOffset": len(self.data), "byteLength": len(data)}
        if target:
            v["target"] = target
        if stride:
            v["byteStride"] = stride
        self.data += data
        self.views.append(v)
        return len(self.views) - 1

    def accessor(self, fmt, values, type_, component, target=None, minmax=False, normalized=False):
        per = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[type_]
        data = struct.pack("<%d%s" % (len(values), fmt), *values)
        a = {"bufferView": self.view(data, target), "componentType": component, "count": len(values) // per,
             "type": type_}
        if normalized:
            a["normalized"] = True
        if minmax:
            a["min"] = [min(values[i::per]) for i in range(per)]
            a["max"] = [max(values[i::per]) for i in range(per)]
        self.accessors.append(a)
        return len(self.accessors) - 1

    def floats(self, values, type_, minmax=False):
        return self.accessor("f", values, type_, 5126, 34962, minmax)

    def indices(self, values, component=5123):
        return self.accessor({5121: "B", 5123: "H", 5125: "I"}[component], values, "SCALAR", component, 34963)


# The quad of quad.obj: corners (-1,-1,0) (1,-1,0) (1,1,0) (-1,1,0) with UVs (0,0) (1,0) (1,1) (0,1) in qdmr,
# i.e. glTF positions (x, 0, -y) and glTF UVs (u, 1 - v).
QUAD_POSITIONS = [-1, 0, 1, 1, 0, 1, 1, 0, -1, -1, 0, -1]
QUAD_NORMALS = [0, 1, 0] * 4
QUAD_UVS = [0, 1, 1, 1, 1, 0, 0, 0]
QUAD_INDICES = [0, 1, 2, 0, 2, 3]


def quad_primitive(buf, material=0, component=5123, normals=True, indexed=True, offset=(0.0, 0.0)):
    pos = [p + (offset[0] if i % 3 == 0 else offset[1] if i % 3 == 2 else 0) for i, p in enumerate(QUAD_POSITIONS)]
    if not indexed:
        expand = lambda v, n: [c for i in QUAD_INDICES for c in v[n * i:n * i + n]]
        pos, uvs, nrm = expand(pos, 3), expand(QUAD_UVS, 2), expand(QUAD_NORMALS, 3)
    else:
        uvs, nrm = QUAD_UVS, QUAD_NORMALS
    attributes = {"POSITION": buf.floats(pos, "VEC3", True), "TEXCOORD_0": buf.floats(uvs, "VEC2")}
    if normals:
        attributes["NORMAL"] = buf.floats(nrm, "VEC3")
    prim = {"attributes": attributes, "material": material, "mode": 4}
    if indexed:
        prim["indices"] = buf.indices(QUAD_INDICES, component)
    return prim


def document(buf, extra, buffer_uri=None):
    doc = {"asset": {"version": "2.0", "generator": "qdmr tests/gltf/make_assets.py"}}
    doc.update(extra)
    doc["buffers"] = [{"byteLength": len(buf.data)}]
    if buffer_uri is not None:
        doc["buffers"][0]["uri"] = buffer_uri
    doc["bufferViews"] = buf.views
    doc["accessors"] = buf.accessors
    return doc


def write(rel, data, root=ASSETS):
    path = os.path.join(root, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


def text(doc):
    return json.dumps(doc, indent=1, sort_keys=True) + "\n"


def glb(doc, bin_data):
    js = json.dumps(doc, sort_keys=True, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    bin_data = bytes(bin_data) + b"\0" * (-len(bin_data) % 4)
    body = struct.pack("<II", len(js), 0x4E4F534A) + js + struct.pack("<II", len(bin_data), 0x004E4942) + bin_data
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def quad_material():
    return {"name": "checker", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
                                                        "roughnessFactor": 0.6}}


def quad_assets():
    image = checker()
    write("checker.png", image)
    buf = Buffer()
    prim = quad_primitive(buf)
    extra = {"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "quad"}],
             "meshes": [{"name": "quad", "primitives": [prim]}], "materials": [quad_material()],
             "textures": [{"source": 0}], "images": [{"uri": "checker.png"}]}
    write("quad.bin", bytes(buf.data))
    write("quad.gltf", text(document(buf, extra, "quad.bin")))
    embedded = dict(extra, images=[{"uri": "data:image/png;base64," + base64.b64encode(image).decode()}])
    write("quad_embedded.gltf", text(document(buf, embedded,
                                              "data:application/octet-stream;base64," + base64.b64encode(bytes(buf.data)).decode())))
    # .glb: the image in a buffer view after the geometry
    bin_buf = Buffer()
    bin_buf.data, bin_buf.views, bin_buf.accessors = bytearray(buf.data), list(buf.views), list(buf.accessors)
    view = bin_buf.view(image)
    glb_extra = dict(extra, images=[{"bufferView": view, "mimeType": "image/png"}])
    doc = document(bin_buf, glb_extra)
    write("quad.glb", glb(doc, bin_buf.data))
    write("quad.obj", "# the quad of quad.gltf\nmtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl checker\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n")
    write("quad.mtl", "newmtl checker\nKd 1 1 1\nmap_Kd checker.png\n")


def tinted_assets():
    """The quad's material with baseColorFactor over the texture and metallicFactor 0.5, and the same quad as OBJ
    with the scene material glTF's maps to: albedo factor = baseColorFactor x (1 - metallic), F0 = 0.04 +
    (luminance(baseColorFactor) - 0.04) x metallic (the double Python and C++ both compute, printed exactly)."""
    factor, metallic, roughness = [0.8, 0.6, 0.4], 0.5, 0.6
    buf = Buffer()
    prim = quad_primitive(buf)
    material = {"name": "tinted", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "baseColorFactor": factor + [1.0],
                                                           "metallicFactor": metallic, "roughnessFactor": roughness}}
    extra = {"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "quad"}],
             "meshes": [{"name": "quad", "primitives": [prim]}], "materials": [material],
             "textures": [{"source": 0}], "images": [{"uri": "checker.png"}]}
    write("quad_tinted.gltf", text(document(buf, extra, "quad.bin")))
    f0 = 0.04 + (0.2126 * factor[0] + 0.7152 * factor[1] + 0.0722 * factor[2] - 0.04) * metallic
    view = {"output": {"width": 160, "height": 90},
            "camera": {"position": [0.4, -2.2, 1.4], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 50}}
    gltf_scene = dict(view, comment="assets/quad_tinted.gltf; quad_tinted_obj.json gives the same bits (make_assets.py)",
                      objects=[{"name": "quad", "mesh": {"type": "gltf", "file": "assets/quad_tinted.gltf"}}])
    obj_scene = dict(view, comment="The OBJ quad with the material quad_tinted.gltf's maps to (make_assets.py)",
                     materials={"tinted": {"layers": [{"albedo": {"file": "assets/checker.png",
                                                                  "factor": [c * (1 - metallic) for c in factor]}}],
                                           "lighting": {"model": "cook_torrance", "specular": f0, "roughness": roughness}}},
                     objects=[{"name": "quad", "mesh": {"type": "obj", "file": "assets/quad.obj"}, "material": "tinted"}])
    write("quad_tinted_gltf.json", text(gltf_scene), HERE)
    write("quad_tinted_obj.json", text(obj_scene), HERE)


def orm_texels(size=16):
    """R occlusion falling from 1 to 1/4 along x, G roughness rising along y, B metal on the right half."""
    out = []
    for y in range(size):
        for x in range(size):
            out += [255 - 12 * x, 40 + 13 * y, 255 if x >= size // 2 else 0]
    return out


def orm_assets():
    size = 16
    texels = orm_texels(size)
    write("orm.png", png(size, size, 3, texels))
    write("occlusion.png", png(size, size, 1, texels[0::3]))
    rough_metal = []
    for i in range(size * size):  # R is not occlusion in a metallicRoughnessTexture: something else there
        rough_metal += [(37 * i) % 256, texels[3 * i + 1], texels[3 * i + 2]]
    write("metal_rough.png", png(size, size, 3, rough_metal))
    write("white.png", png(1, 1, 3, [255, 255, 255]))
    for name, images, occlusion, metallic in (("quad_orm", ["orm.png"], 1, 1.0),
                                              ("quad_orm_split", ["metal_rough.png", "occlusion.png"], 2, 1.0),
                                              ("quad_orm_white", ["white.png"], 1, 0.0)):
        buf = Buffer()
        prim = quad_primitive(buf)
        material = quad_material()
        material["pbrMetallicRoughness"].update(metallicRoughnessTexture={"index": 1}, metallicFactor=metallic)
        material["occlusionTexture"] = {"index": occlusion, "strength": 1.0}
        if name != "quad_orm_white":
            material["pbrMetallicRoughness"]["roughnessFactor"] = 1.0
        extra = {"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "quad"}],
                 "meshes": [{"name": "quad", "primitives": [prim]}], "materials": [material],
                 "textures": [{"source": i} for i in range(len(images) + 1)],
                 "images": [{"uri": "checker.png"}] + [{"uri": u} for u in images]}
        write(name + ".gltf", text(document(buf, extra, "quad.bin")))
    view = {"output": {"width": 160, "height": 90},
            "camera": {"position": [0.4, -2.2, 1.4], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 50}}
    write("quad_orm_gltf.json", text(dict(view, comment="assets/quad_orm.gltf; quad_orm_obj.json gives the same bits (make_assets.py)",
                                          objects=[{"name": "quad", "mesh": {"type": "gltf", "file": "assets/quad_orm.gltf"}}])), HERE)
    write("quad_orm_obj.json", text(dict(
        view, comment="The OBJ quad with the scene material quad_orm.gltf's maps to: orm.png as the layer's orm, metallic 1, "
                      "Cook-Torrance with the dielectric F0 0.04 and roughness 1 (make_assets.py)",
        materials={"orm": {"layers": [{"albedo": "assets/checker.png", "orm": "assets/orm.png", "metallic": 1.0,
                                       "occlusion_strength": 1.0}],
                           "lighting": {"model": "cook_torrance", "specular": 0.04, "roughness": 1.0}}},
        objects=[{"name": "quad", "mesh": {"type": "obj", "file": "assets/quad.obj"}, "material": "orm"}])), HERE)
    # Displaced (qdm with per-frame AO, which the ORM occlusion multiplies): quad_orm, and the white ORM against none.
    for name, asset in (("displaced_orm", "quad_orm"), ("displaced_orm_white", "quad_orm_white"), ("displaced_quad", "quad")):
        comment = {"displaced_orm": "quad_orm.gltf displaced from the scene: the ORM texture sampled at the hit",
                   "displaced_orm_white": "quad_orm_white.gltf displaced: displaced_quad.json's bits (a white ORM without metal changes nothing)",
                   "displaced_quad": "quad.gltf displaced as displaced_orm_white.json"}[name]
        write(name + ".json", text(dict(view, comment=comment + " (make_assets.py)", objects=[
            {"name": "quad", "mesh": {"type": "gltf", "file": "assets/" + asset + ".gltf"},
             "materials": {"checker": {"height": "assets/wall_height.png", "technique": {"name": "qdm", "depth_scale": 0.08},
                                       "ao": {"mode": "frame"}}}}])), HERE)


def colour(name, rgb):
    return {"name": name, "pbrMetallicRoughness": {"baseColorFactor": rgb + [1.0], "metallicFactor": 0.0,
                                                   "roughnessFactor": 0.5}}


def hierarchy_asset():
    buf = Buffer()
    prims = [quad_primitive(buf, material=m) for m in range(3)]
    half = math.sqrt(0.5)
    nodes = [
        {"name": "root", "translation": [0.0, 0.5, 0.0], "rotation": [0.0, half, 0.0, half], "scale": [0.5, 0.5, 0.5],
         "children": [1, 2]},
        {"name": "left", "mesh": 0, "translation": [-2.5, 0.0, 0.0], "children": [3]},
        {"name": "right", "mesh": 1, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2.5, 0, 0, 1]},
        {"name": "lifted", "mesh": 2, "translation": [0.0, 1.0, 0.0], "scale": [0.5, 0.5, 0.5]},
        {"name": "eye", "camera": 0, "translation": [0.0, 6.0, 6.0], "rotation": [-math.sin(math.pi / 8), 0.0, 0.0,
                                                                                math.cos(math.pi / 8)]},
    ]
    extra = {"scene": 0, "scenes": [{"name": "all", "nodes": [0, 4]}], "nodes": nodes,
             "meshes": [{"name": "q%d" % i, "primitives": [p]} for i, p in enumerate(prims)],
             "materials": [colour("red", [0.8, 0.1, 0.1]), colour("green", [0.1, 0.7, 0.2]), colour("blue", [0.1, 0.2, 0.8])],
             "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100.0}}]}
    write("hierarchy.gltf", text(document(buf, extra, "data:application/octet-stream;base64," +
                                          base64.b64encode(bytes(buf.data)).decode())))


def indices_asset():
    buf = Buffer()
    prims = [quad_primitive(buf, 0, 5121, offset=(-4.5, 0)), quad_primitive(buf, 1, 5123, offset=(-1.5, 0)),
             quad_primitive(buf, 2, 5125, offset=(1.5, 0)), quad_primitive(buf, 3, indexed=False, normals=False, offset=(4.5, 0))]
    extra = {"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
             "meshes": [{"name": "quads", "primitives": prims}],
             "materials": [colour("u8", [0.8, 0.2, 0.2]), colour("u16", [0.2, 0.8, 0.2]), colour("u32", [0.2, 0.2, 0.8]),
                           colour("none", [0.8, 0.8, 0.2])]}
    write("indices.gltf", text(document(buf, extra, "data:application/octet-stream;base64," +
                                        base64.b64encode(bytes(buf.data)).decode())))


def sparse_asset():
    buf = Buffer()
    prim = quad_primitive(buf)
    idx = buf.view(struct.pack("<H", 2))
    val = buf.view(struct.pack("<3f", 1.0, 0.5, -1.0))
    buf.accessors[prim["attributes"]["POSITION"]]["sparse"] = {
        "count": 1, "indices": {"bufferView": idx, "componentType": 5123}, "values": {"bufferView": val}}
    extra = {"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": [{"primitives": [prim]}],
             "materials": [colour("grey", [0.5, 0.5, 0.5])]}
    write("sparse.gltf", text(document(buf, extra, "data:application/octet-stream;base64," +
                                       base64.b64encode(bytes(buf.data)).decode())))


def wall_asset(root):
    """A 4 x 2 wall of bricks (glTF: in the XY plane facing +Z, so qdmr stands it up facing -Y), its UVs 2 x 1
    repeats; the height map beside it for scenes to add (glTF has no height map)."""
    albedo, normal, height = bricks()
    buf = Buffer()
    pos = [-2, 0, 0, 2, 0, 0, 2, 2, 0, -2, 2, 0]
    uvs = [0, 1, 2, 1, 2, 0, 0, 0]
    prim = {"attributes": {"POSITION": buf.floats(pos, "VEC3", True), "NORMAL": buf.floats([0, 0, 1] * 4, "VEC3"),
                           "TEXCOORD_0": buf.floats(uvs, "VEC2")},
            "indices": buf.indices(QUAD_INDICES), "material": 0, "mode": 4}
    a, n = buf.view(albedo), buf.view(normal)
    extra = {"scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "name": "wall"}],
             "meshes": [{"name": "wall", "primitives": [prim]}],
             "materials": [{"name": "bricks", "normalTexture": {"index": 1, "scale": 1.0},
                            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0,
                                                     "roughnessFactor": 0.8}}],
             "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}],
             "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 0}],
             "images": [{"bufferView": a, "mimeType": "image/png", "name": "albedo"},
                        {"bufferView": n, "mimeType": "image/png", "name": "normal"}]}
    write("wall.glb", glb(document(buf, extra), buf.data), root)
    write("wall_height.png", height, root)


def fuzz_seeds():
    """fuzz/corpus/gltf: the assets, and quad.gltf naming the files fuzz_gltf puts beside its input (b.bin, 256
    zero bytes; i.png)."""
    seeds = os.path.join(ROOT, "fuzz", "corpus", "gltf")
    for name in ("quad_embedded.gltf", "quad.glb", "hierarchy.gltf", "indices.gltf", "sparse.gltf"):
        with open(os.path.join(ASSETS, name), "rb") as f:
            write(name, f.read(), seeds)
    doc = json.loads(open(os.path.join(ASSETS, "quad.gltf")).read())
    doc["buffers"][0].update(uri="b.bin", byteLength=256)
    doc["images"][0]["uri"] = "i.png"
    write("side_files.gltf", json.dumps(doc, sort_keys=True, separators=(",", ":")), seeds)


quad_assets()
tinted_assets()
orm_assets()
hierarchy_asset()
indices_asset()
sparse_asset()
wall_asset(ASSETS)
wall_asset(os.path.join(ROOT, "examples", "gltf"))
wall_asset(os.path.join(ROOT, "scenes", "assets"))
fuzz_seeds()
