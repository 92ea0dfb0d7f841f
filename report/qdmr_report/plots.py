"""The report's charts, drawn with matplotlib: Pareto fronts, metrics along each numeric axis, cache bars.

Every chart is an SVG string for inlining in the page, so the points of a Pareto chart can link to the
configurations' sections. Colour maps are perceptually uniform (viridis, magma); axes carry units; an axis whose
data spans decades is logarithmic.
"""
import io
import math
import statistics

from .results import format_value

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)

plt.rcParams.update({
    "svg.hashsalt": "qdmr-report",  # stable element ids: the same results give the same page
    "svg.fonttype": "none",         # text stays text (searchable, small)
    "font.size": 9,
    "axes.grid": True,
    "grid.alpha": 0.3,
})

# Columns the charts know, with their axis labels.
LABELS = {
    "draw_ms_median": "draw time, median (ms)",
    "error_p99": "error p99 (texels)",
    "error_mean": "error mean (texels)",
    "missed_fraction": "missed (% of covered pixels)",
    "iterations_mean": "iterations per pixel, mean",
    "cache_miss_ratio": "texture cache miss ratio (%)",
    "cache_bytes_per_pixel": "texture cache bytes fetched per pixel",
}
PERCENT = {"missed_fraction", "cache_miss_ratio"}


def label(column):
    return LABELS.get(column, column)


def scaled(column, v):
    return None if v is None else (100.0 * v if column in PERCENT else v)


def svg(figure):
    out = io.StringIO()
    figure.savefig(out, format="svg", bbox_inches="tight", metadata={"Date": None})
    plt.close(figure)
    text = out.getvalue()
    text = text[text.index("<svg"):]  # inline: no XML prologue or doctype
    start, end = text.find("<metadata>"), text.find("</metadata>")
    if 0 <= start < end:  # matplotlib's RDF credits: bytes the page does not need
        text = text[:start] + text[end + len("</metadata>"):]
    return text


def _spans_decades(values):
    positive = [v for v in values if v is not None and v > 0]
    return len(positive) >= 2 and max(positive) / min(positive) >= 30


def _scale_axis(ax, which, values, log_hint=False):
    """Logarithmic where the data spans decades (symmetric-log when zeros are among them)."""
    values = [v for v in values if v is not None]
    if not (log_hint or _spans_decades(values)):
        return
    positive = [v for v in values if v > 0]
    if not positive:
        return
    setter = ax.set_xscale if which == "x" else ax.set_yscale
    if min(values) <= 0:
        setter("symlog", linthresh=min(positive))
        if min(values) == 0:  # no negative decades below the data's zero
            (ax.set_xlim if which == "x" else ax.set_ylim)(0, None)
    else:
        setter("log")


def pareto_chart(study, group, rows, front, link):
    """Time against p99 error for the rows of one group, the front drawn over the faint dominated rows, missed
    fraction as colour; every point links to link(index)."""
    fig, ax = plt.subplots(figsize=(5.6, 3.8))
    times = [study.number(r, "draw_ms_median") for r in rows]
    errors = [study.number(r, "error_p99") for r in rows]
    missed = [scaled("missed_fraction", study.number(r, "missed_fraction")) or 0.0 for r in rows]
    usable = [i for i, r in enumerate(rows) if times[i] is not None and errors[i] is not None]
    if not usable:
        plt.close(fig)
        return None
    vmax = max(max(missed[i] for i in usable), 1e-9)
    on_front = [i for i in usable if rows[i]["index"] in front]
    dominated = [i for i in usable if rows[i]["index"] not in front]
    scatter_kw = dict(cmap="viridis", vmin=0.0, vmax=vmax, edgecolors="black", linewidths=0.4)
    if dominated:
        points = ax.scatter([times[i] for i in dominated], [errors[i] for i in dominated],
                            c=[missed[i] for i in dominated], s=22, alpha=0.25, **scatter_kw)
        points.set_urls([link(rows[i]["index"]) for i in dominated])
    ordered = sorted(on_front, key=lambda i: (times[i], errors[i]))
    ax.plot([times[i] for i in ordered], [errors[i] for i in ordered], color="0.25", linewidth=1, zorder=2,
            drawstyle="steps-post")
    points = ax.scatter([times[i] for i in ordered], [errors[i] for i in ordered],
                        c=[missed[i] for i in ordered], s=46, zorder=3, **scatter_kw)
    points.set_urls([link(rows[i]["index"]) for i in ordered])
    colorbar = fig.colorbar(points, ax=ax)
    colorbar.set_label(label("missed_fraction"))
    ax.set_xlabel(label("draw_ms_median"))
    ax.set_ylabel(label("error_p99"))
    _scale_axis(ax, "x", [times[i] for i in usable])
    _scale_axis(ax, "y", [errors[i] for i in usable])
    ax.set_title(f"{group}: {len(ordered)} on the front, {len(dominated)} dominated (faint)")
    return svg(fig)


def zipped_followers(study):
    """Axes zipped to an earlier one (they advance together, so a chart along them repeats the first's)."""
    followers = set()
    for group in study.header.get("spec", {}).get("zip", []):
        followers.update(group[1:])
    return followers


def numeric_axes(study):
    """The axes whose values are numbers, with at least three distinct values: what line plots are drawn along
    (an axis zipped to an earlier one is left out)."""
    found = []
    followers = zipped_followers(study)
    for axis in study.axes:
        values = {study.number(r, axis) for r in study.rows} - {None}
        if axis not in followers and len(values) >= 3 and all(
                isinstance(r["config"].get(axis), (int, float, type(None)))
                and not isinstance(r["config"].get(axis), bool) for r in study.rows):
            found.append(axis)
    return found


MAX_LINES = 8


def line_series(study, along):
    """What the lines of a chart along an axis are: every combination of the categorical axes (strings,
    booleans, or fewer than three numbers; zipped followers left out) when there are at most MAX_LINES of them,
    else the group axis alone. Returns (axis names, a function of a row giving its line's label)."""
    followers = zipped_followers(study)
    numeric = set(numeric_axes(study))
    categorical = [a for a in study.axes if a != along and a not in numeric and a not in followers
                   and len({format_value(r["config"].get(a)) for r in study.rows}) > 1]
    combinations = {tuple(format_value(r["config"].get(a)) for a in categorical) for r in study.rows}
    if not categorical or len(combinations) > MAX_LINES:
        categorical = [study.group_axis] if study.group_axis else []
    if len(categorical) == 1:
        return categorical, lambda r: format_value(r["config"].get(categorical[0]))
    return categorical, lambda r: ", ".join(f"{a}={format_value(r['config'].get(a))}" for a in categorical)


def line_chart(study, axis, metrics):
    """One panel per metric along `axis`, one line per value of the categorical axes (line_series): the median
    over the other axes' values at each point, the band from their minimum to their maximum."""
    metrics = [m for m in metrics if any(study.number(r, m) is not None for r in study.rows)]
    if not metrics:
        return None
    columns = min(len(metrics), 2)
    rows = (len(metrics) + columns - 1) // columns
    fig, panels = plt.subplots(rows, columns, figsize=(3.6 * columns, 2.9 * rows), squeeze=False)
    for ax in panels.flat[len(metrics):]:
        ax.set_visible(False)
    spec = study.axis_spec(axis)
    xs_all = [study.number(r, axis) for r in study.rows]
    positive = [x for x in xs_all if x is not None and x > 0]
    # A log range, or positive values spanning a factor of ten or more (map sizes, caps), get a log axis.
    log_x = spec.get("range", {}).get("scale") == "log" or (
        len(positive) == len([x for x in xs_all if x is not None]) and positive and max(positive) / min(positive) >= 10)
    unit = " (degrees)" if spec.get("camera") else ""
    colours = plt.get_cmap("viridis")
    series, line_of = line_series(study, axis)
    lines = []
    for r in study.rows:
        if line_of(r) not in lines:
            lines.append(line_of(r))
    for ax, metric in zip(panels.flat, metrics):
        all_y = []
        for l_index, line in enumerate(lines):
            points = {}
            for r in study.rows:
                if line_of(r) != line:
                    continue
                x, y = study.number(r, axis), scaled(metric, study.number(r, metric))
                if x is not None and y is not None:
                    points.setdefault(x, []).append(y)
            if not points:
                continue
            xs = sorted(points)
            colour = colours(l_index / max(len(lines) - 1, 1) * 0.9)
            ax.plot(xs, [statistics.median(points[x]) for x in xs], marker="o", markersize=3, color=colour,
                    label=line)
            if any(len(points[x]) > 1 for x in xs):
                ax.fill_between(xs, [min(points[x]) for x in xs], [max(points[x]) for x in xs], color=colour,
                                alpha=0.15, linewidth=0)
            all_y += [y for x in xs for y in points[x]]
        ax.set_xlabel(axis + unit)
        ax.set_ylabel(label(metric))
        _scale_axis(ax, "x", xs_all, log_hint=log_x)
        _scale_axis(ax, "y", all_y)
    if len(lines) > 1:
        panels.flat[0].legend(title=", ".join(series) if len(series) == 1 else None, fontsize=7, title_fontsize=7)
    fig.tight_layout()
    return svg(fig)


def cache_series(study, row, quadtree_axis):
    """The bar series of a row in the cache charts: its group, split by quadtree storage where that axis applies."""
    group = study.group_of(row)
    storage = row["config"].get(quadtree_axis) if quadtree_axis else None
    return group if storage is None else f"{group}, {storage}"


def cache_chart(study, layout_axis, quadtree_axis=None):
    """The cache study: miss ratio and bytes per pixel as bars per texture layout, one bar per group (and quadtree
    storage), the median over the other axes."""
    layouts, series = [], []
    for r in study.rows:
        if r["config"].get(layout_axis) not in layouts:
            layouts.append(r["config"].get(layout_axis))
        if cache_series(study, r, quadtree_axis) not in series:
            series.append(cache_series(study, r, quadtree_axis))
    metrics = [m for m in ("cache_miss_ratio", "cache_bytes_per_pixel")
               if any(study.number(r, m) is not None for r in study.rows)]
    fig, axes = plt.subplots(len(metrics), 1, squeeze=False,
                             figsize=(min(12.0, max(5.0, 0.3 * len(layouts) * max(len(series), 1) + 2.0)),
                                      2.8 * len(metrics)))
    width = 0.8 / max(len(series), 1)
    colours = plt.get_cmap("viridis")
    for ax, metric in zip(axes.flat, metrics):
        scale = 100.0 if metric in PERCENT else 1.0
        for s_index, name in enumerate(series):
            heights = []
            for layout in layouts:
                values = [study.number(r, metric) for r in study.rows
                          if cache_series(study, r, quadtree_axis) == name and r["config"].get(layout_axis) == layout]
                values = [v for v in values if v is not None]
                heights.append(scale * statistics.median(values) if values else math.nan)
            ax.bar([i + s_index * width for i in range(len(layouts))], heights, width, label=name,
                   color=colours(s_index / max(len(series) - 1, 1) * 0.9))
        ax.set_xticks([i + width * (len(series) - 1) / 2 for i in range(len(layouts))], [str(v) for v in layouts])
        ax.set_ylabel(label(metric), fontsize=8)
    axes.flat[-1].set_xlabel(layout_axis)
    if len(series) > 1:
        axes.flat[0].legend(title=study.group_axis, fontsize=7, title_fontsize=7, ncol=2)
    fig.tight_layout()
    return svg(fig)


def colour_scale(cmap, vmax, unit):
    """A horizontal colour bar from 0 to vmax, the key of the heatmaps."""
    fig, ax = plt.subplots(figsize=(3.2, 0.5))
    norm = matplotlib.colors.Normalize(0.0, vmax)
    fig.colorbar(matplotlib.cm.ScalarMappable(norm=norm, cmap=cmap), cax=ax, orientation="horizontal",
                 label=unit)
    return svg(fig)
