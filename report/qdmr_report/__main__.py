"""qdmr report: an HTML page of a study's results (`qdmr report RESULTS -o REPORT`; docs/studies.md).

Runs as `python3 path/to/qdmr_report RESULTS -o REPORT` (qdmr's `report` command does this). Exit status 0 on
success, 2 for bad input (one line naming the file and the problem), 1 for anything unexpected. The report is
built in a temporary folder beside REPORT and renamed into place: an interrupted run leaves the previous report
or none, never half of one (a killed run's temporary folder is removed by the next run; Ctrl-C or SIGTERM removes
it at once and exits 130). It never writes into the results folder itself.
"""
import argparse
import errno
import os
import shutil
import signal
import sys
import tempfile

if __package__ in (None, ""):  # run as `python3 .../qdmr_report`: import the package from its parent folder
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    __package__ = "qdmr_report"

from qdmr_report.results import BadResults, load_study  # noqa: E402

MARKER = ".qdmr-report"  # in every report folder: what may be replaced by the next report


def check_output(results, output):
    """Refuses an output folder that would write over the study's results or over anything not a report."""
    real_results, real_output = os.path.realpath(results), os.path.realpath(output)
    if os.path.commonpath([real_output, real_results]) == real_output:
        raise BadResults(f"{output}: is or holds the study's results ({results}): choose another -o")
    images = os.path.join(real_results, "images")
    if os.path.commonpath([real_output, images]) == images:
        raise BadResults(f"{output}: inside the study's images ({images}): choose another -o")
    if os.path.exists(output):
        if not os.path.isdir(output):
            raise BadResults(f"{output}: exists and is not a folder: choose another -o")
        if os.listdir(output) and not os.path.isfile(os.path.join(output, MARKER)):
            raise BadResults(f"{output}: a folder with other files in it (not a qdmr report): choose another -o")


def remove_stale_staging(parent):
    """Removes the temporary folders (".report-PID-...", ".report-old-PID-...") of report runs that were killed:
    those whose process is gone. A folder of a running report is left alone."""
    for name in os.listdir(parent):
        if not name.startswith(".report-"):
            continue
        pid = name[len(".report-"):].removeprefix("old-").split("-")[0]
        if not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            os.kill(int(pid), 0)
            continue  # running (or another user's): not ours to remove
        except ProcessLookupError:
            pass
        except (PermissionError, OverflowError):
            continue
        shutil.rmtree(os.path.join(parent, name), ignore_errors=True)


def write_report(study, output, worst, crop):
    from qdmr_report.page import Page  # matplotlib loads here, after the inputs are checked

    parent = os.path.dirname(os.path.abspath(output))
    os.makedirs(parent, exist_ok=True)
    remove_stale_staging(parent)
    staging = tempfile.mkdtemp(prefix=f".report-{os.getpid()}-", dir=parent)
    try:
        page = Page(study, staging, worst_count=worst, crop_size=crop).render()
        with open(os.path.join(staging, "index.html"), "w", encoding="utf-8") as f:
            f.write(page)
        with open(os.path.join(staging, MARKER), "w", encoding="utf-8") as f:
            f.write("written by qdmr report; the next report into this folder replaces it\n")
        os.chmod(staging, 0o755)
        if os.path.exists(output):  # a previous report: swap, then delete the old one
            old = tempfile.mkdtemp(prefix=f".report-old-{os.getpid()}-", dir=parent)
            os.rename(output, os.path.join(old, "report"))
            os.rename(staging, output)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.rename(staging, output)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def stop(signum, frame):
    raise KeyboardInterrupt


def main(argv=None):
    parser = argparse.ArgumentParser(prog="qdmr report", description=(
        "Writes REPORT/index.html: a page of a study's results (Pareto fronts, metrics along each numeric axis, "
        "the worst artifacts beside the exact reference, every row in a sortable table). It opens from disk."))
    parser.add_argument("results", help="the -o folder of `qdmr study` (or of `qdmr study merge`)")
    parser.add_argument("-o", "--output", help="the report folder (default: RESULTS-report beside RESULTS)")
    parser.add_argument("--worst", type=int, default=6, help="how many worst artifacts to crop (default 6)")
    parser.add_argument("--crop", type=int, default=96, help="crop size in pixels (default 96)")
    parser.add_argument("--partial", action="store_true",
                        help="report an unfinished study or a single shard instead of refusing it")
    args = parser.parse_args(argv)
    signal.signal(signal.SIGTERM, stop)  # like Ctrl-C: the staging folder is removed on the way out
    results = args.results.rstrip("/") or "/"
    output = args.output or results + "-report"
    try:
        if not 0 <= args.worst <= 100:
            raise BadResults(f"--worst: must be from 0 to 100, got {args.worst}")
        if not 8 <= args.crop <= 1024:
            raise BadResults(f"--crop: must be from 8 to 1024 pixels, got {args.crop}")
        check_output(results, output)
        study = load_study(results, partial=args.partial)
        write_report(study, output, args.worst, args.crop)
    except BadResults as e:
        print(f"qdmr report: {e}", file=sys.stderr)
        return 2
    except ImportError as e:
        print(f"qdmr report: {e.name or e}: not installed (Debian: python3-matplotlib, python3-openimageio; "
              "scripts/setup installs them)", file=sys.stderr)
        return 2
    except OSError as e:
        # A full or read-only file system is the report folder's; anything else names the file it happened to.
        where = output if e.errno in (errno.ENOSPC, errno.EROFS, errno.EDQUOT) else e.filename or output
        print(f"qdmr report: {where}: {e.strerror}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("qdmr report: interrupted (SIGINT or SIGTERM): no report written", file=sys.stderr)
        return 130
    print(os.path.join(output, "index.html"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
