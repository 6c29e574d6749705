#!/usr/bin/python3
"""Where a lattice job's triangles under 1 degree are: a census for
results/soundness (issue 42, item 5).

    tools/near_degenerate.py SURFACE.ply --lattice N --domains D [--json FILE]

SURFACE is a `tetiso run --lattice N --domains D` surface as written (.ply,
with the vertex keys tetiso writes). For every triangle whose smallest angle
is under 1 degree, its shortest edge is classed by
  - scale: under 128 units in the last place of its largest coordinate (the
    reduction's artefact scale, core/src/reduce/geometry.hpp: the clusters
    the node clearance makes around a node on the level) or longer;
  - node: whether both ends are crossings of edges through one lattice node
    (a cluster around that node), and whether that node lies on an interface
    of the job's recursive bisection (core/src/lattice.cpp, bisect) or inside
    one domain;
  - border: whether its ends lie on the surface's border (the cube's faces):
    an interior edge between two border vertices never collapses (it would
    pinch the surface).
The census counts triangles by (scale, node, border).
"""
import argparse
import json
import math
import struct
from collections import Counter, defaultdict

ARTEFACT_ULPS = 128.0


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    counts = {line.split()[1]: int(line.split()[2]) for line in header if line.startswith("element")}
    vertex_props = []
    face_props = []
    current = None
    for line in header:
        if line.startswith("element"):
            current = line.split()[1]
        elif line.startswith("property") and current == "vertex":
            vertex_props.append(line.split()[-1])
        elif line.startswith("property") and current == "face":
            face_props.append(line.split())
    if vertex_props != ["x", "y", "z", "tetiso_key_hi", "tetiso_key_lo", "tetiso_flags"]:
        raise SystemExit(f"{path}: not a surface tetiso wrote (vertex properties {vertex_props})")
    trailing = sum(4 for p in face_props if p[1] != "list")
    vertices, offset = [], end
    for _ in range(counts["vertex"]):
        x, y, z, hi, lo, _flags = struct.unpack_from("<fffIIB", data, offset)
        vertices.append(((x, y, z), (hi << 32) | lo))
        offset += 21
    triangles = []
    for _ in range(counts["face"]):
        if data[offset] != 3:
            raise SystemExit(f"{path}: a face that is not a triangle")
        triangles.append(struct.unpack_from("<iii", data, offset + 1))
        offset += 13 + trailing
    return vertices, triangles


def smallest_angle(p):
    best = 180.0
    for c in range(3):
        o, q, r = p[c], p[(c + 1) % 3], p[(c + 2) % 3]
        u = [q[k] - o[k] for k in range(3)]
        v = [r[k] - o[k] for k in range(3)]
        lu, lv = math.hypot(*u), math.hypot(*v)
        if lu == 0 or lv == 0:
            return 0.0
        best = min(best, math.degrees(math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(u, v)) / (lu * lv))))))
    return best


def leaf_boxes(n, domains):
    """The cell boxes of the lattice's recursive bisection, as lattice.cpp cuts them."""
    leaves = []

    def bisect(lo, hi, count):
        if count == 1:
            leaves.append((lo, hi))
            return
        axis = max(range(3), key=lambda a: (hi[a] - lo[a], -a))
        length = hi[axis] - lo[axis]
        cells = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2])
        slab = cells // length
        left_length = min(max((length * (count // 2) + count // 2) // count, 1), length - 1)
        proportional = (count * left_length + length // 2) // length
        lowest = max(1, count - (length - left_length) * slab)
        highest = min(left_length * slab, count - 1)
        left_count = min(max(proportional, lowest), highest)
        cut = lo[axis] + left_length
        bisect(lo, hi[:axis] + [cut] + hi[axis + 1:], left_count)
        bisect(lo[:axis] + [cut] + lo[axis + 1:], hi, count - left_count)

    bisect([0, 0, 0], [n - 1] * 3, domains)
    return leaves


def census(path, n, domains):
    vertices, triangles = read_ply(path)
    leaves = leaf_boxes(n, domains)
    uses = Counter()
    for t in triangles:
        for c in range(3):
            uses[frozenset((t[c], t[(c + 1) % 3]))] += 1
    border = set()
    for edge, count in uses.items():
        if count == 1:
            border |= edge
    counts = Counter()
    for t in triangles:
        p = [vertices[v][0] for v in t]
        if not smallest_angle(p) < 1.0:
            continue
        lengths = [math.dist(p[c], p[(c + 1) % 3]) for c in range(3)]
        c = lengths.index(min(lengths))
        a, b = t[c], t[(c + 1) % 3]
        largest = max(abs(x) for x in vertices[a][0] + vertices[b][0])
        scale = "clearance scale" if lengths[c] < ARTEFACT_ULPS * 2.0 ** -23 * largest else "longer"
        ends = [{vertices[v][1] >> 32, vertices[v][1] & 0xFFFFFFFF} for v in (a, b)]
        common = ends[0] & ends[1]
        if not common:
            node = "no common node"
        else:
            g = min(common)
            ijk = (g % n, (g // n) % n, g // (n * n))
            holders = sum(all(lo[k] <= ijk[k] <= hi[k] for k in range(3)) for lo, hi in leaves)
            node = "node on an interface" if holders > 1 else "node inside one domain"
        on_border = (a in border) + (b in border)
        where = ["interior", "one end on the border", "both ends on the border"][on_border]
        counts[(scale, node, where)] += 1
    return [{"scale": s, "node": nd, "border": w, "triangles": k}
            for (s, nd, w), k in sorted(counts.items(), key=lambda item: (-item[1], item[0]))]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("surface")
    parser.add_argument("--lattice", type=int, required=True)
    parser.add_argument("--domains", type=int, required=True)
    parser.add_argument("--json")
    args = parser.parse_args()
    rows = census(args.surface, args.lattice, args.domains)
    text = json.dumps({"surface": args.surface, "lattice": args.lattice, "domains": args.domains,
                       "below_1": sum(r["triangles"] for r in rows), "census": rows}, indent=2)
    if args.json:
        open(args.json, "w").write(text + "\n")
    else:
        print(text)


if __name__ == "__main__":
    main()
