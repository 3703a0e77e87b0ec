"""Labels against lines in an SVG, for the plotting peer (scripts/bench-plotters.sh): of the
texts drawn in a series' colour (the curves' labels), how many lie on a data line, overlap
another or run off the page. Boxes are estimated as 0.6 × the font size a character and one
font size high (baseline 0.8 above, 0.2 below); lines are the polylines in those colours,
walked in half-pixel steps. Usage: python3 label_check.py FILE.svg COLOUR..."""
import re
import sys


def attrs(tag):
    return dict(re.findall(r'([\w-]+)="([^"]*)"', tag))


def main(path, colours):
    svg = open(path, encoding="utf-8").read()
    width = float(attrs(re.search(r"<svg[^>]*>", svg).group(0))["width"].rstrip("pt"))
    colours = {c.lower() for c in colours}
    boxes = []
    for tag, words in re.findall(r"<text([^>]*)>\s*([^<]*?)\s*</text>", svg, re.S):
        a = attrs(tag)
        if a.get("fill", "").lower() not in colours or not words:
            continue
        size = float(a.get("font-size", 11))
        x, y = float(a["x"]), float(a["y"])
        dy = a.get("dy", "0")
        if dy.endswith("em"):
            y += float(dy[:-2]) * size
        elif dy.endswith("ex"):
            y += float(dy[:-2]) * size / 2
        w = 0.6 * size * len(words)
        left = {"middle": x - w / 2, "end": x - w}.get(a.get("text-anchor"), x)
        boxes.append((words, left, y - 0.8 * size, left + w, y + 0.2 * size))
    lines = []
    for tag in re.findall(r"<polyline([^>]*)>", svg):
        a = attrs(tag)
        if a.get("stroke", "").lower() in colours:
            pts = [tuple(map(float, p.split(","))) for p in a["points"].split()]
            lines.append(pts)
    on_line = 0
    for _, l, t, r, b in boxes:
        hit = False
        for pts in lines:
            for (x0, y0), (x1, y1) in zip(pts, pts[1:]):
                n = max(1, int(((x1 - x0) ** 2 + (y1 - y0) ** 2) ** 0.5 / 0.5))
                if any(l < x0 + k / n * (x1 - x0) < r and t < y0 + k / n * (y1 - y0) < b
                       for k in range(n + 1)):
                    hit = True
                    break
            if hit:
                break
        on_line += hit
    overlaps = sum(
        1
        for i, p in enumerate(boxes)
        for q in boxes[i + 1:]
        if p[1] < q[3] and q[1] < p[3] and p[2] < q[4] and q[2] < p[4]
    )
    off_page = sum(1 for _, l, _, r, _ in boxes if l < 0 or r > width)
    print(f"{path}: {len(boxes)} labels, {on_line} on a line, {overlaps} pairs overlapping, "
          f"{off_page} off the page")


main(sys.argv[1], sys.argv[2:])
