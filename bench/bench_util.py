"""What the bench scripts share: their command line, one render through the qdmr command, read back from its
--stats JSON, and reading an image (an AOV) back as an array."""
import argparse
import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def arguments(description):
    """The options every bench script takes: -n runs, -B build folder, --width/--height; add more, then parse."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("-n", type=int, default=3)
    parser.add_argument("-B", default=os.path.join(ROOT, "build", "release"))
    parser.add_argument("--width", type=int, default=1920)
    parser.add_argument("--height", type=int, default=1080)
    return parser


def render(qdmr, scene, sets, width, height, tmp, env=None, extra=()):
    """Renders `scene` (a path) with --set pointer=value pairs into tmp; returns the stats JSON, plus "cpu_ms"."""
    stats = os.path.join(tmp, "stats.json")
    cmd = [qdmr, "render", scene, "-o", os.path.join(tmp, "image.exr"), "--stats", stats,
           "--width", str(width), "--height", str(height)]
    for pointer, value in sets:
        cmd += ["--set", f"{pointer}={value}"]
    process = subprocess.Popen(cmd + list(extra), stdout=subprocess.DEVNULL, env=env)
    _, status, usage = os.wait4(process.pid, 0)
    process.returncode = os.waitstatus_to_exitcode(status)
    if process.returncode != 0:
        raise subprocess.CalledProcessError(process.returncode, cmd)
    with open(stats) as f:
        result = json.load(f)
    # CPU time of the whole process, every thread, user + system: unlike wall time it hardly grows when other
    # processes share the cores.
    result["cpu_ms"] = (usage.ru_utime + usage.ru_stime) * 1000.0
    return result


def cpu_model():
    """The model name with the family, model and stepping (a VM often names only "AMD EPYC") and the widest vector
    extensions the CPU reports: the figures of the AVX2 class and the AVX-512 class are judged apart."""
    fields = {}
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if not line.strip():
                    break  # the first processor's block
                key, _, value = line.partition(":")
                fields[key.strip()] = value.strip()
    except OSError:
        return "unknown CPU"
    flags = set(fields.get("flags", "").split())
    vector = [name for flag, name in (("avx512f", "AVX-512"), ("avx2", "AVX2"), ("fma", "FMA")) if flag in flags]
    if "avx512f" not in flags:
        vector.append("no AVX-512")
    return (f"{fields.get('model name', 'unknown CPU')} (family {fields.get('cpu family', '?')} model "
            f"{fields.get('model', '?')} stepping {fields.get('stepping', '?')}; {', '.join(vector)})")


def bits_version(qdmr):
    """The bits version of a qdmr build ("qdmr 0.1.0 (bits version 2)"), for the manifests a benchmark writes."""
    out = subprocess.run([qdmr, "--version"], check=True, capture_output=True, text=True).stdout
    return int(out.rsplit("bits version", 1)[1].strip(" )\n"))


def read_exr(path):
    """An image as a float array (height, width, channels), top row first. Needs numpy and OpenImageIO's Python
    module (Debian: python3-openimageio, for the system python3), imported here so that the scripts that read no
    image do not need them."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    pixels = buf.get_pixels(oiio.FLOAT)
    if buf.has_error or pixels is None:
        raise RuntimeError(f"cannot read {path}: {buf.geterror()}")
    return pixels
