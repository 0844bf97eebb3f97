#!/usr/bin/env python3
"""The Kepler error-against-cost chart of docs/guide/time-transformations.md, drawn from the
guide's own two Kepler tables (e = 0.99 and e = 0.9: the time-transformed and fixed-step
Galerkin rows, DOP853 and IAS15), so that the chart and the tables cannot disagree.

    python3 scripts/time-transform-chart.py [--out docs/figures/kepler-time-transform.svg]

Max position error over 100 orbits (log) against seconds (log), one panel per eccentricity,
one series per method family (the rows' "method" up to its last comma). A plain SVG writer:
no plotting package needed.
"""

import argparse
import math
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GUIDE = ROOT / "docs" / "guide" / "time-transformations.md"
COLORS = ["#1f77b4", "#2ca02c", "#17becf", "#d62728", "#ff7f0e", "#7f7f7f", "#9467bd", "#8c564b"]
MARKERS = ["circle", "square", "diamond", "triangle"]


def tables(text):
    """{e: [(family, label, error, seconds)]} from the tables after 'e = 0.99:' and 'e = 0.9:'."""
    out = {}
    for e in ("0.99", "0.9"):
        m = re.search(rf"(?m)^e = {re.escape(e)}:\n\n((?:\|.*\n)+)", text)
        if not m:
            raise SystemExit(f"{GUIDE}: no table after 'e = {e}:'")
        rows = []
        for line in m.group(1).splitlines()[2:]:
            cells = [c.strip() for c in line.strip("|").split("|")]
            method, error, seconds = cells[0], cells[3], cells[4]
            try:
                err, sec = float(error), float(seconds)
            except ValueError:
                continue  # a failed run
            family = re.sub(r"(, \d+ steps/orbit| tol = \S+| ε = \S+)$", "", method)
            rows.append((family, method, err, sec))
        out[e] = rows
    return out


def svg(data):
    width, height, panel_w = 1000, 460, 430
    left, top, plot_h = 70, 40, 330
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
             'font-family="sans-serif" font-size="12">',
             f'<rect width="{width}" height="{height}" fill="white"/>']
    families = []
    for rows in data.values():
        for f, *_ in rows:
            if f not in families:
                families.append(f)
    all_err = [r[2] for rows in data.values() for r in rows]
    all_sec = [r[3] for rows in data.values() for r in rows]
    ex0, ex1 = math.floor(math.log10(min(all_err))), math.ceil(math.log10(max(all_err)))
    sx0, sx1 = math.floor(math.log10(min(all_sec))), math.ceil(math.log10(max(all_sec)))
    for k, (e, rows) in enumerate(data.items()):
        x0 = left + k * (panel_w + 60)
        px = lambda s: x0 + (math.log10(s) - sx0) / (sx1 - sx0) * panel_w
        py = lambda v: top + (ex1 - math.log10(v)) / (ex1 - ex0) * plot_h
        parts.append(f'<rect x="{x0}" y="{top}" width="{panel_w}" height="{plot_h}" '
                     'fill="none" stroke="black"/>')
        parts.append(f'<text x="{x0 + panel_w / 2}" y="{top - 12}" text-anchor="middle" '
                     f'font-size="14">Kepler e = {e}, 100 orbits</text>')
        for p in range(sx0, sx1 + 1):
            x = px(10.0 ** p)
            parts.append(f'<line x1="{x}" y1="{top}" x2="{x}" y2="{top + plot_h}" stroke="#ddd"/>')
            parts.append(f'<text x="{x}" y="{top + plot_h + 16}" text-anchor="middle">1e{p}</text>')
        for p in range(ex0, ex1 + 1, 2):
            y = py(10.0 ** p)
            parts.append(f'<line x1="{x0}" y1="{y}" x2="{x0 + panel_w}" y2="{y}" stroke="#ddd"/>')
            parts.append(f'<text x="{x0 - 6}" y="{y + 4}" text-anchor="end">1e{p}</text>')
        parts.append(f'<text x="{x0 + panel_w / 2}" y="{top + plot_h + 34}" '
                     'text-anchor="middle">seconds (wall clock)</text>')
        parts.append(f'<text transform="translate({x0 - 50},{top + plot_h / 2}) rotate(-90)" '
                     'text-anchor="middle">max position error</text>')
        for i, fam in enumerate(families):
            pts = sorted((r[3], r[2]) for r in rows if r[0] == fam)
            if not pts:
                continue
            c = COLORS[i % len(COLORS)]
            path = " ".join(f"{px(s):.1f},{py(v):.1f}" for s, v in pts)
            parts.append(f'<polyline points="{path}" fill="none" stroke="{c}" stroke-width="1.5"/>')
            for s, v in pts:
                parts.append(f'<circle cx="{px(s):.1f}" cy="{py(v):.1f}" r="3.5" fill="{c}"/>')
    # Legend below the panels.
    for i, fam in enumerate(families):
        x = left + (i % 4) * 230
        y = top + plot_h + 58 + (i // 4) * 18
        c = COLORS[i % len(COLORS)]
        parts.append(f'<circle cx="{x}" cy="{y - 4}" r="4" fill="{c}"/>')
        parts.append(f'<text x="{x + 10}" y="{y}">{fam}</text>')
    parts.append("</svg>")
    return "\n".join(parts) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "figures" / "kepler-time-transform.svg"))
    args = ap.parse_args()
    data = tables(GUIDE.read_text(encoding="utf-8"))
    Path(args.out).write_text(svg(data), encoding="utf-8")
    print(f"{args.out}: {sum(len(r) for r in data.values())} points")


if __name__ == "__main__":
    main()
