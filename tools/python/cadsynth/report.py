"""One self-contained HTML page from a dataset's report data (`cadsynth report DATASET -o OUT`).

    /usr/bin/python3 report.py DATA.json OUT.html
    from cadsynth.report import build_html   # build_html(json.load(f)) -> str

The C++ side gathers the dataset's statistics into DATA.json (report_data 1: run facts, the
verifier's verdict, per-object viewpoint coverage and histograms, per-sensor image statistics,
randomised draws, grasps, physics, a gallery of data URIs) and embeds and runs this file, so it
imports nothing of the package: the standard library, numpy and matplotlib only. Plots are drawn
with matplotlib's object-oriented API on the Agg canvas (no pyplot: no global figure registry, no
backend switch in a process that imports this module) and inlined as PNG data URIs; the page has
no script and loads nothing from the network.
"""

from __future__ import annotations

import base64
import html
import io
import json
import os
import pathlib
import sys

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

DPI = 80
KEYS_PER_FIGURE = 12  # randomised keys per figure, in a grid of GRID_COLUMNS columns
GRID_COLUMNS = 3
MAX_LISTED = 50  # problems and example images listed before "... and N more"
SECTIONS = [("run", "Run"), ("verify", "Verification"), ("objects", "Objects"),
            ("images", "Images"), ("randomization", "Randomisation"), ("grasps", "Grasps"),
            ("physics", "Physics"), ("gallery", "Gallery")]
STYLE = """
body { font-family: sans-serif; max-width: 1100px; margin: 1em auto; padding: 0 1em; color: #222; }
table { border-collapse: collapse; margin: 0.5em 0; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.6em; text-align: left; }
th { background: #f0f0f0; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
pre { background: #f6f6f6; padding: 0.6em; overflow-x: auto; }
img { max-width: 100%; }
.badge { display: inline-block; padding: 0.2em 0.8em; border-radius: 0.3em; font-size: 1.6em;
         font-weight: bold; color: #fff; background: #777; }
.badge.pass { background: #2a7d2a; } .badge.fail { background: #b22222; }
.note { color: #666; font-style: italic; }
figure { display: inline-block; margin: 0.5em; vertical-align: top; }
figcaption { font-size: 0.9em; max-width: 400px; }
"""


def esc(value) -> str:
    """VALUE as text, HTML-escaped (quotes too, so it is safe in attributes)."""
    return html.escape("" if value is None else str(value), quote=True)


def fmt(value) -> str:
    """A table cell's text: integers with thousands separators, floats to 4 significant digits."""
    if isinstance(value, bool) or value is None:
        return "" if value is None else str(value)
    if isinstance(value, int):
        return f"{value:,}"
    if isinstance(value, float):
        return f"{value:,.4g}" if abs(value) < 1e15 else f"{value:.4g}"
    return str(value)


def table(header: list, rows: list) -> str:
    """An HTML table; numeric cells right-aligned."""
    head = "".join(f"<th>{esc(h)}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(
            f'<td class="num">{esc(fmt(c))}</td>' if isinstance(c, (int, float))
            and not isinstance(c, bool) else f"<td>{esc(fmt(c))}</td>" for c in row) + "</tr>"
        for row in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def note(text: str) -> str:
    """A paragraph in the 'nothing here' style."""
    return f'<p class="note">{esc(text)}</p>'


def listing(items: list, render) -> str:
    """A <ul> of the first MAX_LISTED items, RENDER(item) -> HTML, and how many were left off."""
    lines = "".join(f"<li>{render(i)}</li>" for i in items[:MAX_LISTED])
    more = len(items) - MAX_LISTED
    return f"<ul>{lines}</ul>" + (note(f"... and {more:,} more") if more > 0 else "")


# -- plots ------------------------------------------------------------------------------------


def figure(width: float, height: float) -> Figure:
    """A figure on the Agg canvas, laid out by matplotlib's constrained layout."""
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def img(fig: Figure, alt: str) -> str:
    """FIG as an <img> with an inline PNG data URI."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, metadata={"Software": None})
    fig.clear()
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img src="data:image/png;base64,{data}" alt="{esc(alt)}">'


def hist_arrays(hist) -> tuple[np.ndarray, np.ndarray] | None:
    """(edges, counts) of a HIST, or None when it is missing, malformed or all zero."""
    if not isinstance(hist, dict):
        return None
    edges = np.asarray(hist.get("edges") or [], dtype=float)
    counts = np.asarray(hist.get("counts") or [], dtype=float)
    if counts.size == 0 or edges.size != counts.size + 1 or not counts.any():
        return None
    return edges, counts


def has_data(*hists) -> bool:
    """Whether any of the HISTs has a count."""
    return any(hist_arrays(h) is not None for h in hists)


def no_data(ax, title: str) -> None:
    """An empty panel that says so."""
    ax.set_title(title, fontsize=9)
    ax.text(0.5, 0.5, "no data", ha="center", va="center", color="0.5", transform=ax.transAxes)
    ax.set_xticks([])
    ax.set_yticks([])


def draw_hist(ax, hist, title: str, legend: str | None = None) -> None:
    """HIST's pre-binned counts as a filled step plot, log x axis when asked (and possible)."""
    arrays = hist_arrays(hist)
    if arrays is None:
        if legend is None:
            no_data(ax, title)
        return
    edges, counts = arrays
    ax.stairs(counts, edges, fill=True, alpha=0.6 if legend else 1.0, label=legend)
    if hist.get("log") and edges[0] > 0:
        ax.set_xscale("log")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel(hist.get("label") or "", fontsize=8)
    ax.tick_params(labelsize=7)


def coverage_arrays(cov) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(x_edges, y_edges, counts) of a HIST2D, or None when missing, malformed or all zero."""
    if not isinstance(cov, dict):
        return None
    counts = np.asarray(cov.get("counts") or [], dtype=float)
    x_edges = np.asarray(cov.get("x_edges") or [], dtype=float)
    y_edges = np.asarray(cov.get("y_edges") or [], dtype=float)
    if counts.ndim != 2 or counts.shape != (y_edges.size - 1, x_edges.size - 1) or not counts.any():
        return None
    return x_edges, y_edges, counts


def draw_coverage(fig, ax, cov) -> None:
    """HIST2D of camera directions as a map: azimuth x, elevation y, empty bins grey."""
    arrays = coverage_arrays(cov)
    if arrays is None:
        return no_data(ax, "viewpoint coverage")
    x_edges, y_edges, counts = arrays
    mesh = ax.pcolormesh(x_edges, y_edges, np.ma.masked_equal(counts, 0), cmap="viridis")
    ax.set_facecolor("0.85")
    fig.colorbar(mesh, ax=ax, label="views").ax.yaxis.set_major_locator(
        MaxNLocator(integer=True))
    ax.set_title("viewpoint coverage (grey: never seen)", fontsize=9)
    ax.set_xlabel(cov.get("x_label") or "azimuth (deg)", fontsize=8)
    ax.set_ylabel(cov.get("y_label") or "elevation (deg)", fontsize=8)
    ax.tick_params(labelsize=7)


def draw_choice(ax, counts: dict, title: str) -> None:
    """A choice's draws as a bar chart, one bar per option."""
    if not isinstance(counts, dict) or not any(counts.values()):
        return no_data(ax, title)
    labels = [k if len(k) <= 16 else k[:15] + "…" for k in map(str, counts)]
    ax.bar(range(len(labels)), list(counts.values()))
    ax.set_xticks(range(len(labels)), labels, rotation=30 if len(labels) > 4 else 0,
                  ha="right" if len(labels) > 4 else "center")
    ax.set_title(title, fontsize=9)
    ax.tick_params(labelsize=7)


# -- sections ---------------------------------------------------------------------------------


def run_section(run) -> str:
    """The run's facts, its shards when there are several, and the recipe."""
    run = run or {}
    splits = run.get("splits") or {}
    facts = [("version", run.get("version")), ("run key", run.get("run_key")),
             ("recipe", run.get("recipe_path")), ("started (UTC)", run.get("started_utc")),
             ("seconds", run.get("seconds")), ("threads", run.get("threads")),
             ("shards", len(run["shards"]) if run.get("shards") else None),
             ("frames", run.get("frames")), ("scenes", run.get("scenes")),
             ("objects", run.get("objects")), ("instances", run.get("instances")),
             ("files", run.get("files")), ("bytes", run.get("bytes")),
             ("splits", ", ".join(f"{k} {fmt(v)}" for k, v in splits.items()) or None)]
    rows = [[name, value] for name, value in facts if value is not None]
    out = table(["", "value"], rows) if rows else note("no run facts")
    shards = run.get("shards") or []
    if len(shards) > 1:
        out += table(["shard", "seconds", "frames"],
                     [[s.get("index"), s.get("seconds"), s.get("frames")] for s in shards])
    if run.get("recipe_text"):
        out += f"<details><summary>recipe</summary><pre>{esc(run['recipe_text'])}</pre></details>"
    return out


def verify_section(verify, dataset: str) -> str:
    """The verifier's verdict as a badge, its checks and its problems."""
    if not verify:
        return (f'<p class="note">not verified: run <code>cadsynth verify {esc(dataset)}</code>'
                "</p>")
    verdict = str(verify.get("verdict") or "unknown")
    css = verdict if verdict in ("pass", "fail") else ""
    out = f'<p><span class="badge {css}">{esc(verdict.upper())}</span> '
    out += f"{esc(verify.get('summary'))}</p>"
    checks = verify.get("checks") or []
    if checks:
        out += table(["check", "checked", "failed"],
                     [[c.get("name"), c.get("checked"), c.get("failed")] for c in checks])
    problems = verify.get("problems") or []
    if problems:
        total = verify.get("problem_count") or len(problems)  # the certificate lists the first
        out += f"<h3>problems ({total:,})</h3>"
        out += listing(problems,
                       lambda p: f"<code>{esc(p.get('file'))}</code>: {esc(p.get('reason'))}")
    return out


def object_figure(obj: dict, label: str) -> str:
    """One figure for an object: coverage map left, its four histograms in a 2 x 2 grid right."""
    hists = [("inplane_deg", "in-plane rotation"), ("distance_mm", "distance"),
             ("visib_fract", "visible fraction"), ("px_count_visib", "visible pixels")]
    empty = not has_data(*(obj.get(key) for key, _ in hists))
    if empty and coverage_arrays(obj.get("coverage")) is None:
        return note("no data")
    fig = figure(11, 4)
    grid = fig.add_gridspec(2, 4)
    draw_coverage(fig, fig.add_subplot(grid[:, :2]), obj.get("coverage"))
    for (key, title), cell in zip(hists, [grid[0, 2], grid[0, 3], grid[1, 2], grid[1, 3]]):
        draw_hist(fig.add_subplot(cell), obj.get(key), title)
    return img(fig, f"{label}: viewpoint coverage (azimuth, elevation) and histograms of "
                    "in-plane rotation, distance, visible fraction and visible pixels")


def objects_section(objects) -> str:
    """Per object: a heading, a row of counts and its figure."""
    if not objects:
        return note("no objects")
    out = ""
    for obj in objects:
        obj_id = obj.get("obj_id")
        slug = f"obj_{obj_id:06d}" if isinstance(obj_id, int) else f"obj_{obj_id}"
        label = f"{slug} {obj.get('name') or ''}".strip()
        out += f'<h3 id="{esc(slug)}">{esc(label)}</h3>'
        out += table(["diameter (mm)", "symmetry", "instances", "visible", "targets"],
                     [[obj.get("diameter_mm"), obj.get("symmetry"), obj.get("instances"),
                       obj.get("visible"), obj.get("targets")]])
        out += object_figure(obj, label)
    return out


def sensor_figure(sensor: dict, label: str) -> str:
    """One row of per-image histograms: instances, visible instances, occlusion, depth range."""
    keys = ["instances_per_image", "visible_instances_per_image", "occlusion_per_image",
            "depth_min_mm", "depth_max_mm"]
    if not has_data(*(sensor.get(k) for k in keys)):
        return note("no data")
    fig = figure(12, 2.8)
    axes = fig.subplots(1, 4)
    draw_hist(axes[0], sensor.get("instances_per_image"), "instances per image")
    draw_hist(axes[1], sensor.get("visible_instances_per_image"), "visible instances per image")
    draw_hist(axes[2], sensor.get("occlusion_per_image"), "occlusion per image")
    if has_data(sensor.get("depth_min_mm"), sensor.get("depth_max_mm")):
        draw_hist(axes[3], sensor.get("depth_min_mm"), "object depth range", "nearest")
        draw_hist(axes[3], sensor.get("depth_max_mm"), "object depth range", "farthest")
        axes[3].legend(fontsize=7)
    else:
        no_data(axes[3], "object depth range")
    return img(fig, f"{label}: histograms of instances, visible instances and occlusion per "
                    "image, and of the nearest and farthest object depth per image")


def images_section(sensors) -> str:
    """Per sensor: image counts, empty and sparse images, and its per-image histograms."""
    if not sensors:
        return note("no images")
    out = ""
    for sensor in sensors:
        label = f"sensor {sensor['name']}" if sensor.get("name") else "camera"
        out += f"<h3>{esc(label)}</h3>"
        size = f"{sensor.get('width')} x {sensor.get('height')}" if sensor.get("width") else ""
        sparse = f"sparse (< {fmt(sensor.get('sparse_threshold_px'))} px visible)"
        out += table(["images", "size", "empty", sparse],
                     [[sensor.get("images"), size, sensor.get("empty_images"),
                       sensor.get("sparse_images")]])
        examples = sensor.get("empty_examples") or []
        if examples:
            out += "<p>empty images:</p>" + listing(examples, esc)
        out += sensor_figure(sensor, label)
    return out


def verdict(check) -> str:
    """A draw test's result as a table cell: its p-value and whether the draws agree."""
    if not isinstance(check, dict):
        return ""
    p = check.get("p_value")
    word = "as asked" if check.get("agrees") else "DIFFERS"
    return f"{word} ({check.get('test')}, p = {fmt(p)})"


def draw_expected(ax, key: dict) -> None:
    """What the recipe asked for KEY, drawn over its draws: the expected count of each bin (a
    number) or option (a choice), as a dashed line."""
    expected = key.get("expected")
    if key.get("kind") == "choice" and isinstance(expected, dict):
        counts = key.get("counts") or {}
        values = [float(expected.get(name, 0.0)) for name in counts]
        if values:
            ax.plot(range(len(values)), values, "k_", markersize=14, markeredgewidth=1.5,
                    label="asked")
    elif isinstance(expected, list):
        arrays = hist_arrays(key.get("hist"))
        if arrays is not None and len(expected) == arrays[1].size:
            ax.stairs(np.asarray(expected, dtype=float), arrays[0], color="k", linestyle="--",
                      linewidth=1.0, label="asked")


def randomization_section(keys, note_text=None) -> str:
    """A table of the randomised keys, what the recipe asked and whether the draws agree with it,
    then their draws in grids of plots with the expected counts over them."""
    if not keys:
        return note("no randomisation")
    out = note(note_text) if note_text else ""
    differ = [str(k.get("key")) for k in keys
              if isinstance(k.get("check"), dict) and not k["check"].get("agrees")]
    tested = sum(isinstance(k.get("check"), dict) for k in keys)
    if tested:
        out += note(f"{tested} of {len(keys)} randomised quantities tested against the recipe: "
                    + (f"{len(differ)} differ ({', '.join(differ)})" if differ
                       else "all drawn as asked (p >= 0.001)"))
    out += table(["key", "kind", "asked", "drawn per", "draws", "against the recipe"],
                 [[k.get("key"), k.get("kind"), k.get("asked") or "", k.get("per") or "",
                   k.get("samples"), verdict(k.get("check"))] for k in keys])
    for start in range(0, len(keys), KEYS_PER_FIGURE):
        chunk = keys[start:start + KEYS_PER_FIGURE]
        rows = -(-len(chunk) // GRID_COLUMNS)
        fig = figure(11, 2.4 * rows)
        axes = fig.subplots(rows, GRID_COLUMNS, squeeze=False).ravel()
        for ax, key in zip(axes, chunk):
            asked = str(key.get("asked") or "")
            title = str(key.get("key")) + (f"\n{asked[:50]}{'…' if len(asked) > 50 else ''}"
                                           if asked else "")
            if key.get("kind") == "choice":
                draw_choice(ax, key.get("counts"), title)
            else:
                draw_hist(ax, key.get("hist"), title)
            draw_expected(ax, key)
        for ax in axes[len(chunk):]:
            ax.set_visible(False)
        names = ", ".join(str(k.get("key")) for k in chunk)
        out += img(fig, f"distributions of the randomised draws of {names}")
    return out


def grasps_section(grasps: dict) -> str:
    """Grasp labels per object, and histograms of the grasps per frame."""
    per_object = grasps.get("per_object") or []
    out = table(["object", "parallel jaw", "suction"],
                [[g.get("obj_id"), g.get("parallel_jaw"), g.get("suction")]
                 for g in per_object]) if per_object else note("no grasps per object")
    per_frame = grasps.get("per_frame") or {}
    if has_data(per_frame.get("parallel_jaw"), per_frame.get("suction")):
        fig = figure(8, 2.6)
        axes = fig.subplots(1, 2)
        draw_hist(axes[0], per_frame.get("parallel_jaw"), "parallel-jaw grasps per frame")
        draw_hist(axes[1], per_frame.get("suction"), "suction grasps per frame")
        out += img(fig, "histograms of parallel-jaw and suction grasps per frame")
    return out


def physics_section(physics: dict) -> str:
    """Tables of how piles came to rest and of pick sequences' steps, each with its summary and
    (piles) a histogram of the settle times."""
    tables = physics.get("tables")
    if tables is None and physics.get("rows"):  # one table (older report data)
        tables = [{"columns": physics.get("columns") or [], "rows": physics["rows"]}]
    out = ""
    for t in tables or []:
        rows = t.get("rows") or []
        if not rows:
            continue
        if t.get("title"):
            out += f"<h3>{esc(t['title'])}</h3>"
        if t.get("summary"):
            out += f"<p>{esc(t['summary'])}</p>"
        out += table(t.get("columns") or [], rows)
        if t.get("more"):
            out += note(f"... and {fmt(t['more'])} more rows (not at rest first)")
        if has_data(t.get("settle_seconds")) and len(rows) > 1:
            fig = figure(5, 2.6)
            draw_hist(fig.subplots(), t["settle_seconds"], "settle time per pile")
            out += img(fig, "histogram of the piles' simulated settle times")
    return out or note("no physics statistics")


def gallery_section(gallery) -> str:
    """Each image as a <figure> with its title and caption; only data URIs are shown."""
    if not gallery:
        return note("no gallery")
    out = ""
    sensors = {str(entry.get("sensor") or "") for entry in gallery}
    shown = None
    for entry in gallery:
        sensor = str(entry.get("sensor") or "")
        if len(sensors) > 1 and sensor != shown:
            out += f"<h3>{esc('sensor ' + sensor if sensor else 'camera')}</h3>"
            shown = sensor
        title, caption = entry.get("title") or "", entry.get("caption") or ""
        where = f"scene {entry.get('scene_id')} image {entry.get('im_id')}"
        if entry.get("sensor"):
            where += f" ({entry['sensor']})"
        image = str(entry.get("image") or "")
        if image.startswith("data:image/"):
            shown = f'<img src="{esc(image)}" alt="{esc(title or where)}: {esc(where)}">'
        else:
            shown = note(f"{where}: image missing")
        text = f"<b>{esc(title)}</b> {esc(caption)}" if title else esc(caption or where)
        out += f"<figure>{shown}<figcaption>{text}</figcaption></figure>"
    return out


def build_html(data: dict) -> str:
    """The report page for DATA (report data version 1) as one HTML string."""
    if not isinstance(data, dict):
        raise ValueError("report data is not a JSON object")
    dataset = str(data.get("dataset") or "")
    bodies = {"run": run_section(data.get("run")),
              "verify": verify_section(data.get("verify"), dataset or "DATASET"),
              "objects": objects_section(data.get("objects")),
              "images": images_section(data.get("sensors")),
              "randomization": randomization_section(data.get("randomization"),
                                                   data.get("randomization_note"))}
    if data.get("grasps") is not None:
        bodies["grasps"] = grasps_section(data["grasps"])
    if data.get("physics") is not None:
        bodies["physics"] = physics_section(data["physics"])
    bodies["gallery"] = gallery_section(data.get("gallery"))
    present = [(sid, name) for sid, name in SECTIONS if sid in bodies]
    title = str(data.get("title") or "cadsynth dataset report")
    version = data.get("report_data")
    warning = note(f"report data version {version}; this script reads version 1") \
        if version != 1 else ""
    toc = "".join(f'<li><a href="#{sid}">{name}</a></li>' for sid, name in present)
    sections = "".join(f'<section><h2 id="{sid}">{name}</h2>{bodies[sid]}</section>'
                       for sid, name in present)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f"<title>{esc(title)}</title><style>{STYLE}</style></head><body>"
            f"<h1>{esc(title)}</h1><p>dataset <code>{esc(dataset)}</code> &middot; "
            f"generated by {esc(data.get('generated_by'))}</p>{warning}"
            f"<nav><ul>{toc}</ul></nav>{sections}</body></html>\n")


def write_atomically(path: pathlib.Path, text: str) -> None:
    """Write TEXT to PATH through a temporary file beside it, so PATH is whole or untouched."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "x", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def main(argv: list[str]) -> int:
    """report.py DATA.json OUT.html: 0 written, 1 unreadable data or output, 2 usage."""
    if len(argv) != 2:
        print("usage: report.py DATA.json OUT.html", file=sys.stderr)
        return 2
    data_path, out_path = pathlib.Path(argv[0]), pathlib.Path(argv[1])
    try:
        data = json.loads(data_path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        print(f"report.py: {data_path}: cannot read report data: {error}", file=sys.stderr)
        return 1
    try:
        page = build_html(data)
    except (AttributeError, KeyError, TypeError, ValueError) as error:
        print(f"report.py: {data_path}: unusable report data: {type(error).__name__}: {error}",
              file=sys.stderr)
        return 1
    try:
        write_atomically(out_path, page)
    except OSError as error:
        print(f"report.py: {out_path}: cannot write: {error}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
