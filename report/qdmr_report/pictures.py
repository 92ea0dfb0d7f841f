"""Pictures of the report: kept images copied beside the page, AOVs as heatmaps, crops of the worst artifacts.

Images are read with OpenImageIO (the library qdmr writes them with) and written as PNG with matplotlib.
"""
import os
import shutil

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy  # noqa: E402
import OpenImageIO as oiio  # noqa: E402

from .results import BadResults  # noqa: E402


def read(path):
    """An image as float32 (height, width, channels); PNGs as stored (sRGB-encoded, 0..1)."""
    buf = oiio.ImageBuf(path)
    pixels = buf.get_pixels(oiio.FLOAT)
    if buf.has_error or pixels is None or getattr(pixels, "size", 0) == 0:
        raise BadResults(f"{path}: unreadable image ({buf.geterror() or 'no pixels'})")
    pixels = numpy.asarray(pixels, dtype=numpy.float32)
    if pixels.ndim == 2:
        pixels = pixels[:, :, None]
    return pixels


def save_png(path, pixels):
    plt.imsave(path, numpy.clip(pixels, 0.0, 1.0), format="png")


def copy_image(source, target):
    shutil.copyfile(source, target)


def heatmap(values, vmax, cmap, target):
    """A single-channel image mapped through cmap from 0 to vmax (values above clip to the top colour)."""
    plane = numpy.nan_to_num(values[:, :, 0], nan=vmax, posinf=vmax, neginf=0.0)
    plt.imsave(target, plane, cmap=cmap, vmin=0.0, vmax=vmax, format="png")


def covered_percentile(values, q):
    """The q-th percentile of a single-channel image over its non-zero pixels (0 where there are none)."""
    plane = numpy.nan_to_num(values[:, :, 0], nan=0.0, posinf=0.0, neginf=0.0)
    covered = plane[plane > 0]
    return float(numpy.percentile(covered, q)) if covered.size else 0.0


def worst_window(weights, size):
    """The top-left corner of the size x size window with the largest sum of weights (a summed-area table)."""
    h, w = weights.shape
    size_y, size_x = min(size, h), min(size, w)
    table = numpy.zeros((h + 1, w + 1), dtype=numpy.float64)
    table[1:, 1:] = numpy.cumsum(numpy.cumsum(numpy.nan_to_num(weights, nan=0.0), axis=0), axis=1)
    sums = (table[size_y:, size_x:] - table[:-size_y, size_x:] - table[size_y:, :-size_x]
            + table[:-size_y, :-size_x])
    y, x = numpy.unravel_index(int(numpy.argmax(sums)), sums.shape)
    return int(y), int(x), size_y, size_x


def artifact_crops(image_path, reference_path, error_path, size, stem, folder):
    """Crops of a configuration's image and its exact reference where they differ most (by the error AOV when
    kept, else by the colour difference), and the difference as a heatmap. Returns the file names and the
    crop's rectangle, or None when the images do not match in size."""
    image = read(image_path)[:, :, :3]
    reference = read(reference_path)[:, :, :3]
    if image.shape != reference.shape:
        return None
    difference = numpy.abs(image - reference).max(axis=2)
    weights = difference
    if error_path:
        error = read(error_path)[:, :, 0]
        if error.shape == difference.shape:
            weights = error
    y, x, sh, sw = worst_window(weights, size)
    names = {"image": f"{stem}.crop.png", "reference": f"{stem}.reference.crop.png",
             "difference": f"{stem}.difference.crop.png"}
    save_png(os.path.join(folder, names["image"]), image[y:y + sh, x:x + sw])
    save_png(os.path.join(folder, names["reference"]), reference[y:y + sh, x:x + sw])
    crop = difference[y:y + sh, x:x + sw]
    vmax = max(float(crop.max()), 1.0 / 255.0)
    heatmap(crop[:, :, None], vmax, "magma", os.path.join(folder, names["difference"]))
    return names, (x, y, sw, sh), vmax
