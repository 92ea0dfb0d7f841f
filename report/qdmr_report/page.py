"""The report page: one self-contained HTML file, charts inlined as SVG, pictures beside it in images/.

It opens from disk with no server and no network: no external script, style sheet or font.
"""
import html
import json
import os
import statistics
import sys

from . import pictures, plots
from .results import DETERMINISTIC, TIMING, format_value

STYLE = """
body { font: 14px/1.45 system-ui, sans-serif; margin: 0 auto; max-width: 1280px; padding: 0 1.5em 4em; color: #222; }
h1 { margin-bottom: 0.2em; } h2 { border-bottom: 1px solid #ccc; padding-bottom: 0.2em; margin-top: 2em; }
.comment { color: #555; max-width: 60em; }
table { border-collapse: collapse; font-variant-numeric: tabular-nums; }
table.facts td { padding: 0.15em 1em 0.15em 0; vertical-align: top; } table.facts td:first-child { color: #666; }
table.rows { font-size: 12px; display: block; overflow-x: auto; max-height: 36em; }
table.rows th, table.rows td { padding: 0.2em 0.6em; border-bottom: 1px solid #eee; text-align: right; white-space: nowrap; }
table.rows th { position: sticky; top: 0; background: #f4f4f4; cursor: pointer; user-select: none; }
table.rows th[data-dir=asc]::after { content: " \\25B2"; } table.rows th[data-dir=desc]::after { content: " \\25BC"; }
table.rows tr.front td { font-weight: 600; } table.rows tr:target td { background: #fff3c4; }
.warning { background: #fde2e1; border-left: 4px solid #c0392b; padding: 0.6em 1em; margin: 1em 0; }
.note { background: #eef3fb; border-left: 4px solid #5b7bb5; padding: 0.6em 1em; margin: 1em 0; }
.charts { display: flex; flex-wrap: wrap; gap: 1.5em; align-items: flex-start; }
.charts figure, .crops figure, .card figure { margin: 0; }
figcaption { font-size: 12px; color: #555; max-width: 40em; }
.crops { display: flex; gap: 0.8em; flex-wrap: wrap; margin-bottom: 1.5em; }
.crops img { width: 256px; image-rendering: pixelated; border: 1px solid #ccc; }
.card { border-top: 1px solid #ddd; padding: 0.6em 0; } .card:target { background: #fff8dc; }
.card .pictures { display: flex; gap: 0.8em; flex-wrap: wrap; } .card img { max-width: 300px; border: 1px solid #ccc; }
pre { background: #f7f7f7; padding: 0.8em; overflow-x: auto; font-size: 12px; }
nav a { margin-right: 1em; }
"""

SORT_SCRIPT = """
for (const th of document.querySelectorAll('table.rows th')) {
  th.addEventListener('click', () => {
    const body = th.closest('table').tBodies[0], col = th.cellIndex;
    const dir = th.dataset.dir === 'asc' ? -1 : 1;
    for (const other of th.parentNode.children) delete other.dataset.dir;
    th.dataset.dir = dir === 1 ? 'asc' : 'desc';
    const key = row => {
      const cell = row.children[col], text = cell.dataset.v ?? cell.textContent, n = Number(text);
      return text !== '' && !Number.isNaN(n) ? n : text;
    };
    const rank = v => typeof v === 'number' ? 0 : v === '' ? 2 : 1;
    [...body.rows].sort((a, b) => {
      const x = key(a), y = key(b);
      if (rank(x) !== rank(y)) return rank(x) - rank(y);
      return (x < y ? -1 : x > y ? 1 : 0) * dir;
    }).forEach(row => body.appendChild(row));
  });
}
"""

KEPT = [(".png", "image"), (".reference.png", "exact reference"), (".error_texels.exr", "error_texels"),
        (".iterations.exr", "iterations"), (".cache_misses.exr", "cache_misses")]
HEATMAPS = {"error_texels": "magma", "iterations": "viridis", "cache_misses": "cividis"}


def esc(v):
    return html.escape(format_value(v) if not isinstance(v, str) else v, quote=True)


class Page:
    def __init__(self, study, folder, worst_count=6, crop_size=96):
        self.study = study
        self.folder = folder               # the report folder being written (a temporary one, renamed after)
        self.images = os.path.join(folder, "images")
        self.worst_count = worst_count
        self.crop_size = crop_size
        self.cards = {}                    # index -> the pictures of that configuration's section
        os.makedirs(self.images, exist_ok=True)
        rows = study.rows
        self.error_max = max([study.number(r, "error_p99") or 0.0 for r in rows] + [1.0])
        self.iterations_max = max([study.number(r, "iterations_max") or 0.0 for r in rows] + [1.0])
        self.cache_max = None  # from the kept cache_misses pictures (make_cards): no column holds a maximum

    def anchor(self, index):
        return f"#c{index}" if index in self.cards else f"#row{index}"

    # The pictures of every configuration that kept any: copies and heatmaps in images/.
    def make_cards(self):
        terminal = sys.stderr.isatty()  # a progress line on a terminal; quiet in CI logs
        for done, row in enumerate(self.study.rows, 1):
            if terminal:
                print(f"\rreport: pictures of configuration {done}/{len(self.study.rows)}", end="", file=sys.stderr,
                      flush=True)
            index = row["index"]
            made = []
            for suffix, what in KEPT:
                source = self.study.kept(index, suffix)
                if not source:
                    continue
                if suffix.endswith(".png"):
                    name = f"{index}{suffix}"
                    pictures.copy_image(source, os.path.join(self.images, name))
                else:
                    name = f"{index}.{what}.png"
                    pictures.heatmap(pictures.read(source), self.heatmap_max(what), HEATMAPS[what],
                                     os.path.join(self.images, name))
                made.append((name, what))
            if made:
                self.cards[index] = made
        if terminal:
            print(file=sys.stderr)

    def heatmap_max(self, what):
        if what == "error_texels":
            return self.error_max
        if what == "iterations":
            return self.iterations_max
        if self.cache_max is None:
            # The 99th percentile of the covered pixels' misses, the largest over the study: one scale for all.
            p99 = [pictures.covered_percentile(pictures.read(path), 99.0)
                   for path in (self.study.kept(r["index"], ".cache_misses.exr") for r in self.study.rows) if path]
            self.cache_max = max(p99 + [1.0])
        return self.cache_max

    def header(self):
        s, h = self.study, self.study.header
        machine = h.get("machine", {})
        run = h.get("run", {})
        spec = h.get("spec", {})
        draw_total = sum((s.number(r, "draw_ms_median") or 0.0) for r in s.rows) / 1000.0
        facts = [
            ("spec", h.get("spec_file", "")),
            ("spec hash", h.get("spec_hash", "")),
            ("qdmr version", h.get("qdmr_version", "")),
            ("bits version", h.get("bits_version", "")),
            ("machine", f"{machine.get('cpu', '?')}, {machine.get('cores', '?')} cores; drawn with "
                        f"{machine.get('threads', '?')} threads, {machine.get('isa', '?')} kernel"),
            ("configurations", f"{len(s.rows)} of {h.get('configurations')}"
                               + ("" if s.complete else " (partial)")),
            ("size", f"{spec.get('width', 480)} x {spec.get('height', 270)}, {spec.get('frames', 3)} timed frames "
                     f"after {spec.get('warmup', 1)} warm-up"),
        ]
        if run:
            taken = f"{run.get('wall_seconds', 0):.1f} s wall"
            if run.get("shards", 1) > 1:
                taken += (f" summed over {run['shards']} shards (the longest {run.get('longest_shard_seconds', 0):.1f} s)")
            facts.append(("time taken", f"{taken}; median draws sum to {draw_total:.2f} s"))
        out = [f"<h1>qdmr study: {esc(os.path.basename(h.get('spec_file', 'study')))}</h1>"]
        if spec.get("comment"):
            out.append(f"<p class=comment>{esc(spec['comment'])}</p>")
        out.append("<table class=facts>" + "".join(f"<tr><td>{esc(k)}</td><td>{esc(v)}</td></tr>" for k, v in facts)
                   + "</table>")
        out.append(f"<details><summary>The spec</summary><pre>{esc(json.dumps(spec, indent=2))}</pre></details>")
        bad = [r for r in s.rows if (s.number(r, "nonfinite") or 0) > 0 or (s.number(r, "error_nonfinite") or 0) > 0]
        if bad:
            links = ", ".join(f"<a href='#row{r['index']}'>{r['index']}</a>" for r in bad[:40])
            out.append(f"<p class=warning><b>{len(bad)} configuration(s) produced NaN or infinite values</b> "
                       f"(columns nonfinite, error_nonfinite): {links}</p>")
        if not s.complete:
            out.append(f"<p class=warning>A partial study: {len(s.rows)} of {h.get('configurations')} "
                       "configurations have rows. Fronts and curves cover those only.</p>")
        return "\n".join(out)

    def pareto_section(self):
        s = self.study
        out = ["<section id=pareto><h2>Pareto fronts</h2>",
               "<p>Time against p99 error (distance of the hit from the exact fp64 reference's, in level-0 texels); "
               "colour is the fraction of covered pixels missed by more than a texel. A configuration is on the "
               "front when no other is at least as good in all of time, p99 error and missed fraction and better in "
               "one. Each point links to its configuration.</p>", "<div class=charts>"]
        groups = [(g, f"{s.group_axis}={g}" if s.group_axis else "all") for g in s.groups()]
        if len(groups) > 1:
            groups.append(("all", "all"))
        drawn = 0
        for group, front_name in groups:
            rows = s.rows if group == "all" and front_name == "all" else [r for r in s.rows if s.group_of(r) == group]
            chart = plots.pareto_chart(s, group if front_name != "all" or len(groups) == 1 else "every configuration",
                                       rows, s.fronts.get(front_name, set()), self.anchor)
            if chart:
                out.append(f"<figure>{chart}</figure>")
                drawn += 1
        out.append("</div>")
        if not drawn:
            out.append("<p class=note>No row has both a time and an error p99: the spec's metrics need "
                       "<code>time</code> and <code>error</code> for fronts.</p>")
        return "\n".join(out)

    def axes_section(self):
        s = self.study
        axes = plots.numeric_axes(s)
        out = ["<section id=axes><h2>Along each numeric axis</h2>"]
        if not axes:
            out.append("<p class=note>No axis has three or more numeric values.</p>")
            return "\n".join(out)
        series, _ = plots.line_series(s, axes[0])
        out.append(f"<p>One line per value of {esc(', '.join(series) or 'the study')} (the categorical axes, or the "
                   "group axis when they make too many lines): the median over the other axes' values at each point, "
                   "the band from their minimum to their maximum.</p>")
        for axis in axes:
            chart = plots.line_chart(s, axis, ["error_p99", "missed_fraction", "draw_ms_median", "iterations_mean"])
            if chart:
                out.append(f"<h3>{esc(axis)}</h3><figure>{chart}</figure>")
        return "\n".join(out)

    def worst_section(self):
        s = self.study
        # The worst of every group value first (by p99), then the second worst of each, ...: one technique's
        # near-identical variants do not crowd out the others.
        ranked = sorted((r for r in s.rows if s.number(r, "error_p99") is not None
                         and s.kept(r["index"], ".png") and s.kept(r["index"], ".reference.png")),
                        key=lambda r: (-s.number(r, "error_p99"), r["index"]))
        place, seen = {}, {}
        for r in ranked:
            g = s.group_of(r)
            place[r["index"]] = seen.get(g, 0)
            seen[g] = place[r["index"]] + 1
        with_reference = sorted(ranked, key=lambda r: (place[r["index"]], -s.number(r, "error_p99"), r["index"]))
        out = ["<section id=worst><h2>Worst artifacts</h2>"]
        if not with_reference:
            out.append("<p class=note>No configuration kept both its image and its exact reference: add "
                       "<code>\"keep\": [\"image\", \"reference\", \"error_texels\"]</code> to the spec to see the worst "
                       "artifacts beside the exact reference.</p>")
            return "\n".join(out)
        by = f" of each {esc(s.group_axis)}" if s.group_axis else ""
        out.append(f"<p>The {min(self.worst_count, len(with_reference))} configurations with the highest p99 error, "
                   f"the worst{by} first (of those that kept their image and reference): a {self.crop_size}-pixel "
                   "crop where the error is "
                   "largest, the same crop of the configuration rendered at the exact reference's hits "
                   "(<code>exact_hits</code>) and their colour difference (magma, black = equal).</p>")
        for row in with_reference[:self.worst_count]:
            index = row["index"]
            made = pictures.artifact_crops(s.kept(index, ".png"), s.kept(index, ".reference.png"),
                                           s.kept(index, ".error_texels.exr"), self.crop_size, str(index), self.images)
            if not made:
                continue
            names, (x, y, w, h), vmax = made
            caption = (f"<a href='{self.anchor(index)}'>#{index}</a> {esc(s.label(row))}: error p99 "
                       f"{s.number(row, 'error_p99'):.3g} texels, missed "
                       f"{100 * (s.number(row, 'missed_fraction') or 0):.2f} %; crop at ({x}, {y}), {w} x {h}")
            out.append(f"<p>{caption}</p><div class=crops>")
            for key, title in (("image", "technique"), ("reference", "exact reference"),
                               ("difference", f"difference (white = {vmax:.2g})")):
                out.append(f"<figure><img src='images/{names[key]}' alt='{esc(title)} #{index}'>"
                           f"<figcaption>{esc(title)}</figcaption></figure>")
            out.append("</div>")
        return "\n".join(out)

    def cache_section(self):
        s = self.study
        out = ["<section id=cache><h2>Texture cache</h2>"]
        has_cache = any(s.number(r, "cache_miss_ratio") is not None for r in s.rows)
        layout_axes = [a for a in s.axes if a == "layout" or s.axis_spec(a).get("path", "").endswith("/layout")]
        if not has_cache or not layout_axes:
            out.append("<p class=note>This study has no texture-cache columns per layout (a <code>layout</code> axis "
                       "and the <code>cache_miss_ratio</code> column).</p>")
            return "\n".join(out)
        quadtree_axes = [a for a in s.axes if a == "quadtree" or s.axis_spec(a).get("path", "").endswith("/quadtree")]
        quadtree = quadtree_axes[0] if quadtree_axes else None
        out.append("<p>The emulated texture cache's miss ratio and the bytes it fetched per pixel (misses times the "
                   "line size), the median over the other axes, per texel layout"
                   + (" and quadtree storage" if quadtree else "") + ".</p>")
        out.append(f"<figure>{plots.cache_chart(s, layout_axes[0], quadtree)}</figure>")
        if quadtree:
            out.append(self.quadtree_table(layout_axes[0], quadtree))
        return "\n".join(out)

    def quadtree_table(self, layout_axis, quadtree_axis):
        """Per layout: the bytes per pixel of each quadtree storage, and the change from the first."""
        s = self.study
        storages = [v for v in s.axis_spec(quadtree_axis).get("values", [])]
        layouts = []
        for r in s.rows:
            if r["config"].get(layout_axis) not in layouts:
                layouts.append(r["config"].get(layout_axis))
        out = ["<table><thead><tr><th>" + esc(layout_axis) + "</th>"
               + "".join(f"<th>{esc(v)}: bytes per pixel</th>" for v in storages)
               + "".join(f"<th>{esc(v)} vs {esc(storages[0])}</th>" for v in storages[1:]) + "</tr></thead><tbody>"]
        for layout in layouts:
            medians = []
            for storage in storages:
                values = [s.number(r, "cache_bytes_per_pixel") for r in s.rows
                          if r["config"].get(layout_axis) == layout and r["config"].get(quadtree_axis) == storage]
                values = [v for v in values if v is not None]
                medians.append(statistics.median(values) if values else None)
            cells = [f"<td>{esc(layout)}</td>"] + [f"<td>{m:.1f}</td>" if m is not None else "<td></td>" for m in medians]
            for m in medians[1:]:
                change = (m / medians[0] - 1.0) * 100.0 if m is not None and medians[0] else None
                cells.append(f"<td>{change:+.1f} %</td>" if change is not None else "<td></td>")
            out.append("<tr>" + "".join(cells) + "</tr>")
        out.append("</tbody></table>")
        return "\n".join(out)

    def budget_section(self):
        """The spec's budget: per group value (and per value of the `per` axes), the fastest configuration whose
        missed fraction is below the budget, and its time over the `relative_to` configuration's."""
        s = self.study
        budget = s.header.get("spec", {}).get("budget")
        if not budget:
            return ""
        limit = float(budget["missed_fraction"])
        per = list(budget.get("per", []))
        relative_to = budget.get("relative_to", {})
        fixed = set(per) | {s.group_axis} | set(relative_to) | plots.zipped_followers(s)

        def key(row):
            return tuple(format_value(row["config"].get(a)) for a in per)

        def is_reference(row):
            return all(row["config"].get(a) == v for a, v in relative_to.items())

        def time(row):
            return s.number(row, "draw_ms_median")

        references = {}
        for r in s.rows:
            if is_reference(r) and time(r) is not None:
                k = key(r)
                references[k] = min(references.get(k, time(r)), time(r))
        keys = sorted({key(r) for r in s.rows})
        groups = [g for g in s.groups() if not (relative_to and all(
            format_value(v) == g for a, v in relative_to.items() if a == s.group_axis))]
        out = ["<section id=budget><h2>Within budget</h2>",
               f"<p>Per {esc(s.group_axis)}{' and ' + esc(', '.join(per)) if per else ''}: the fastest configuration "
               f"with fewer than {100 * limit:.3g} % of its covered pixels missed (and no NaN or Inf), its time"
               + (" over " + esc(", ".join(f"{a}={format_value(v)}" for a, v in relative_to.items()))
                  + (" at the same " + esc(", ".join(per)) if per else "") if relative_to else "")
               + ", and the knobs that got it there. Where no configuration is within the budget, the one that "
                 "missed least.</p>",
               "<table><thead><tr><th>" + esc(s.group_axis) + "</th>"
               + "".join(f"<th>{esc(', '.join(f'{a}={v}' for a, v in zip(per, k)))}</th>" for k in keys)
               + "</tr></thead><tbody>"]
        for g in groups:
            cells = [f"<td>{esc(g)}</td>"]
            for k in keys:
                rows = [r for r in s.rows if s.group_of(r) == g and key(r) == k and time(r) is not None
                        and s.number(r, "missed_fraction") is not None]
                if not rows:
                    cells.append("<td></td>")
                    continue
                within = [r for r in rows if s.number(r, "missed_fraction") < limit and not s.number(r, "nonfinite")]
                best = min(within, key=time) if within else min(rows, key=lambda r: s.number(r, "missed_fraction"))
                knobs = ", ".join(f"{a}={format_value(v)}" for a, v in best["config"].items()
                                  if a not in fixed and v is not None)
                ratio = f"{time(best) / references[k]:.2f}x" if k in references and references[k] > 0 else \
                    f"{time(best):.3g} ms"
                missed = 100 * s.number(best, "missed_fraction")
                text = (f"<b>{ratio}</b>" if within else f"not reached ({ratio})") + \
                    f"<br><small>{esc(knobs)}{'; ' if knobs else ''}{missed:.3g} % missed, p99 " \
                    f"{format_value(s.number(best, 'error_p99'))}</small>"
                cells.append(f"<td><a href='{self.anchor(best['index'])}'>{text}</a></td>")
            out.append("<tr>" + "".join(cells) + "</tr>")
        out.append("</tbody></table>")
        return "\n".join(out)

    def table_section(self):
        s = self.study
        det, timing = s.columns(DETERMINISTIC), s.columns(TIMING)
        on_front = set().union(*s.fronts.values()) if s.fronts else set()
        out = ["<section id=rows><h2>Every configuration</h2>",
               "<p>Click a column to sort. Bold rows are on a Pareto front. Timing columns (last) vary from run to "
               "run; the others are bit-identical across runs, threads, ISAs and shards.</p>",
               "<table class=rows><thead><tr><th>index</th>"
               + "".join(f"<th>{esc(c)}</th>" for c in s.axes + det + timing) + "</tr></thead><tbody>"]
        for row in s.rows:
            index = row["index"]
            cells = [f"<td data-v='{index}'><a href='{self.anchor(index)}'>{index}</a></td>"]
            for c in s.axes + det + timing:
                v = s.value(row, c)
                text = f"{v:.4g}" if isinstance(v, float) else format_value(v)
                number = f" data-v='{v!r}'" if isinstance(v, (int, float)) and not isinstance(v, bool) else ""
                cells.append(f"<td{number}>{esc(text)}</td>")
            cls = " class=front" if index in on_front else ""
            out.append(f"<tr id=row{index}{cls}>" + "".join(cells) + "</tr>")
        out.append("</tbody></table>")
        return "\n".join(out)

    def cards_section(self):
        if not self.cards:
            return ("<section id=configurations><h2>Configurations</h2><p class=note>The spec kept no files per configuration "
                    "(<code>keep</code>).</p>")
        cache = f", cache_misses (cividis) from 0 to {self.cache_max:.0f} misses" if self.cache_max is not None else ""
        out = ["<section id=configurations><h2>Configurations</h2>",
               f"<p>What each configuration kept. Heatmaps share one scale across the study: error_texels (magma) from "
               f"0 to {self.error_max:.3g} texels, iterations (viridis) from 0 to {self.iterations_max:.0f}{cache}.</p>",
               "<div class=charts>", f"<figure>{plots.colour_scale('magma', self.error_max, 'error (texels)')}</figure>",
               f"<figure>{plots.colour_scale('viridis', self.iterations_max, 'iterations')}</figure>"]
        if self.cache_max is not None:
            out.append(f"<figure>{plots.colour_scale('cividis', self.cache_max, 'texture cache misses')}</figure>")
        out.append("</div>")
        for row in self.study.rows:
            index = row["index"]
            if index not in self.cards:
                continue
            out.append(f"<div class=card id=c{index}><b><a href='#row{index}'>#{index}</a></b> "
                       f"{esc(self.study.label(row))}<div class=pictures>")
            for name, what in self.cards[index]:
                out.append(f"<figure><img src='images/{name}' alt='{esc(what)} #{index}'>"
                           f"<figcaption>{esc(what)}</figcaption></figure>")
            out.append("</div></div>")
        return "\n".join(out)

    def render(self):
        self.make_cards()
        budget = self.budget_section()
        sections = [self.pareto_section(), *([budget] if budget else []), self.axes_section(), self.worst_section(),
                    self.cache_section(), self.table_section(), self.cards_section()]
        body = [self.header(),
                "<nav><a href='#pareto'>Pareto fronts</a>" + ("<a href='#budget'>Within budget</a>" if budget else "")
                + "<a href='#axes'>Axes</a><a href='#worst'>Worst artifacts</a>"
                "<a href='#cache'>Cache</a><a href='#rows'>Every configuration</a>"
                "<a href='#configurations'>Pictures</a></nav>",
                *(section + "\n</section>" for section in sections)]
        title = esc(os.path.basename(self.study.header.get("spec_file", "study")))
        return ("<!doctype html>\n<html lang=en><head><meta charset=utf-8>"
                "<meta name=viewport content='width=device-width, initial-scale=1'>"
                f"<title>qdmr study: {title}</title><style>{STYLE}</style></head><body>\n"
                + "\n".join(body) + f"\n<script>{SORT_SCRIPT}</script>\n</body></html>\n")
