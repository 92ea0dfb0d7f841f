#!/usr/bin/python3
"""How often the four pixels of a 2x2 quad fetch from one small block of texels: the share of quads whose bilinear
footprints, on each mip level a trilinear fetch reads, fit in 4x4 (and 6x6) texels. A sampler that loads one block
per quad instead of two texel pairs per lane (issue #12, docs/performance.md) pays off only where that share is high.

For each technique the scene is rendered with `--aov uv` (the polygon's UV, from which the LOD is taken per quad, as
`"lod": "per_quad"` does) and `--aov hit_uv` (where the albedo and normal map are fetched). The LOD follows the GL
formula, log2 of the longer of the quad's two UV derivatives in texels of a --texture-size map; level floor(LOD) and
the next are checked (quads with LOD below 0 read level 0 only); quads with a pixel of depth 0 (no surface) are
left out. Wrap seams count as misses.

  bench/quad_footprints.py [-B BUILD] [--scene bench/llvmpipe/canonical.json] [--texture-size 512]
                           [--techniques normal pom relief qdm] [--width 1920 --height 1080]

Needs numpy and OpenImageIO's Python module (Debian's python3-numpy, python3-openimageio: the system python3).
"""
import os
import subprocess
import tempfile

import numpy as np

import bench_util

MATERIAL = "/materials/cobbles"


def quads(values):
    """(H, W, C) -> (H/2, W/2, 2, 2, C): each quad's four pixels, [row in quad][column in quad]."""
    h, w, c = values.shape
    return values[: h // 2 * 2, : w // 2 * 2].reshape(h // 2, 2, w // 2, 2, c).transpose(0, 2, 1, 3, 4)


def fits(hit_quads, level):
    """Per quad: do the four bilinear footprints on `level` fit 4x4 texels, and 6x6?"""
    scale = (2.0 ** level)[..., None, None, None]
    first = np.floor(hit_quads / scale - 0.5)  # the footprint's first texel, per pixel and axis
    spread = first.max(axis=(2, 3)) - first.min(axis=(2, 3))
    return (spread <= 2).all(-1), (spread <= 4).all(-1)


def main():
    parser = bench_util.arguments(__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default=os.path.join(bench_util.ROOT, "bench", "llvmpipe", "canonical.json"))
    parser.add_argument("--texture-size", type=int, default=512)
    parser.add_argument("--techniques", nargs="+", default=["normal", "pom", "relief", "qdm"])
    args = parser.parse_args()
    qdmr = os.path.join(args.B, "qdmr")
    print(f"{'technique':10} {'quads':>8} {'LOD<0':>6} {'fine 4x4':>9} {'fine 6x6':>9} {'coarse 4x4':>11} {'coarse 6x6':>11}")
    with tempfile.TemporaryDirectory() as tmp:
        for technique in args.techniques:
            uv_file, hit_file = os.path.join(tmp, "uv.exr"), os.path.join(tmp, "hit_uv.exr")
            depth_file = os.path.join(tmp, "depth.exr")
            subprocess.run([qdmr, "render", args.scene, "-o", os.path.join(tmp, "image.png"),
                            "--width", str(args.width), "--height", str(args.height),
                            "--set", f'{MATERIAL}/technique/name="{technique}"',
                            "--aov", f"uv={uv_file}", "--aov", f"hit_uv={hit_file}", "--aov", f"depth={depth_file}"],
                           check=True, stdout=subprocess.DEVNULL)
            uv = quads(bench_util.read_exr(uv_file) * args.texture_size)
            hit = quads(bench_util.read_exr(hit_file) * args.texture_size)
            covered = (quads(bench_util.read_exr(depth_file)) > 0).all(axis=(2, 3, 4))
            ddx = uv[:, :, 0, 1] - uv[:, :, 0, 0]
            ddy = uv[:, :, 1, 0] - uv[:, :, 0, 0]
            rho = np.maximum(np.linalg.norm(ddx, axis=-1), np.linalg.norm(ddy, axis=-1))
            with np.errstate(divide="ignore", invalid="ignore"):
                lod = np.log2(rho)
            top = np.log2(args.texture_size)
            usable = covered & np.isfinite(lod)  # depth 0: no surface; the AOVs hold zeros there
            fine = np.clip(np.floor(np.where(usable, lod, 0.0)), 0, top)
            fine4, fine6 = fits(hit, fine)
            coarse4, coarse6 = fits(hit, np.minimum(fine + 1, top))
            coarse_read = usable & (lod >= 0)  # magnified quads read level 0 only
            share = lambda fit, where: f"{fit[where].mean():.4f}" if where.any() else "-"
            print(f"{technique:10} {int(usable.sum()):8d} {(lod[usable] < 0).mean():6.3f} {share(fine4, usable):>9} "
                  f"{share(fine6, usable):>9} {share(coarse4, coarse_read):>11} {share(coarse6, coarse_read):>11}")


if __name__ == "__main__":
    main()
