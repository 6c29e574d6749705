#!/usr/bin/python3
"""Draws the pictures of results/paper-reproduction.md, headless: the same small
box of the reduced and of the unreduced surface side by side with their
edges (the paper's Fig. 10), and one view of the whole reduced surface.

    xvfb-run -a -s "-screen 0 1600x1200x24" tools/render_surface.py REDUCED.ply RAW.ply \\
        --box 1.8,1.8,1.8,2.3,2.3,2.3 --domains 125 --job-reduced "CMD" --job-raw "CMD" --out results/paper-reproduction

REDUCED and RAW are binary PLY files written by `tetiso run` (RAW with
--no-reduce) for the same problem. Both fragments are drawn cut at the box's
faces; the triangle counts are of the whole triangles whose centroid lies in
the box. Writes OUT/fragment.png, OUT/surface.png and
OUT/render.json (the box, triangle counts, the jobs' commands, machine,
commit, date, VTK version), which results/paper-reproduction.md cites.

Dependencies: Debian's python3-vtk9 and python3-numpy. Debian's VTK renders
through X: without a display run it under xvfb-run (package xvfb).
"""
import argparse
import json
import os
import platform
import re
import subprocess
from datetime import datetime, timezone

import numpy as np
import vtk
from vtk.util import numpy_support

PLY_TYPES = {"char": "i1", "uchar": "u1", "short": "<i2", "ushort": "<u2", "int": "<i4", "uint": "<u4",
             "float": "<f4", "double": "<f8", "int8": "i1", "uint8": "u1", "int32": "<i4", "uint32": "<u4",
             "float32": "<f4", "float64": "<f8"}


def read_ply(path):
    """Vertices (n×3 float32) and triangles (m×3 int) of a binary little-endian
    PLY whose faces all have three corners (tetiso writes only those)."""
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            raise SystemExit(f"{path}: not a PLY file")
        elements = []
        while True:
            words = f.readline().decode("ascii").split()
            if not words or words[0] == "end_header":
                break
            if words[0] == "format" and words[1] != "binary_little_endian":
                raise SystemExit(f"{path}: {words[1]} PLY, expected binary_little_endian")
            if words[0] == "element":
                elements.append((words[1], int(words[2]), []))
            elif words[0] == "property":
                if words[1] == "list":
                    # Three corners each: the list is a count and three indices.
                    elements[-1][2].extend([("n", PLY_TYPES[words[2]]), (words[4], PLY_TYPES[words[3]], (3,))])
                else:
                    elements[-1][2].append((words[2], PLY_TYPES[words[1]]))
        data = {}
        for name, count, fields in elements:
            data[name] = np.fromfile(f, dtype=np.dtype(fields), count=count)
    faces = data["face"]
    if "n" in faces.dtype.names and np.any(faces["n"] != 3):
        raise SystemExit(f"{path}: faces other than triangles")
    vertices = np.stack([data["vertex"][c] for c in "xyz"], axis=1).astype(np.float32)
    return vertices, faces["vertex_indices"].astype(np.int64)


def in_box(vertices, triangles, box):
    centroids = vertices[triangles].mean(axis=1)
    low, high = np.array(box[:3]), np.array(box[3:])
    return triangles[np.all((centroids >= low) & (centroids <= high), axis=1)]


def touching(vertices, triangles, box):
    """Triangles whose bounding box meets the box: all the clip can keep a part of."""
    corners = vertices[triangles]
    low, high = np.array(box[:3]), np.array(box[3:])
    return triangles[np.all((corners.min(axis=1) <= high) & (corners.max(axis=1) >= low), axis=1)]


def polydata(vertices, triangles):
    points = vtk.vtkPoints()
    points.SetData(numpy_support.numpy_to_vtk(vertices, deep=True))
    cells = np.hstack([np.full((len(triangles), 1), 3, dtype=np.int64), triangles]).ravel()
    polys = vtk.vtkCellArray()
    polys.SetCells(len(triangles), numpy_support.numpy_to_vtkIdTypeArray(cells, deep=True))
    out = vtk.vtkPolyData()
    out.SetPoints(points)
    out.SetPolys(polys)
    return out


def clipped(mesh, box):
    """The mesh cut at the box's faces, so that both fragments end at the same
    border whatever the size of their triangles."""
    region = vtk.vtkBox()
    region.SetBounds(box[0], box[3], box[1], box[4], box[2], box[5])
    clip = vtk.vtkClipPolyData()
    clip.SetInputData(mesh)
    clip.SetClipFunction(region)
    clip.InsideOutOn()
    clip.Update()
    return clip.GetOutput()


def actor(mesh, color, edges):
    normals = vtk.vtkPolyDataNormals()
    normals.SetInputData(mesh)
    normals.SplittingOff()  # flat shading below; keep every triangle's own facet
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(normals.GetOutputPort())
    out = vtk.vtkActor()
    out.SetMapper(mapper)
    prop = out.GetProperty()
    prop.SetColor(*color)
    prop.SetInterpolationToFlat()
    prop.BackfaceCullingOff()
    if edges:
        prop.EdgeVisibilityOn()
        prop.SetEdgeColor(0.15, 0.2, 0.3)
        prop.SetLineWidth(0.6)
    return out


def save(window, path):
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetCompressionLevel(9)
    writer.SetFileName(path)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()


def window(width, height):
    out = vtk.vtkRenderWindow()
    out.SetOffScreenRendering(1)
    out.SetSize(width, height)
    out.SetMultiSamples(4)
    return out


def label(renderer, text, size=18, y=12):
    caption = vtk.vtkTextActor()
    caption.SetInput(text)
    caption.GetTextProperty().SetFontSize(size)
    shade = 0.1 if size > 12 else 0.4  # provenance stamps in grey, captions dark
    caption.GetTextProperty().SetColor(shade, shade, shade)
    caption.SetPosition(12, y)
    renderer.AddViewProp(caption)


def render_fragment(reduced, raw, path, size, stamp):
    win = window(2 * size, size)
    camera = None
    for i, (mesh, text) in enumerate(reduced + raw):
        r = vtk.vtkRenderer()
        r.SetViewport(i / 2, 0, (i + 1) / 2, 1)
        r.SetBackground(1, 1, 1)
        r.AddActor(actor(mesh, (0.55, 0.72, 0.9), edges=True))
        label(r, text, y=30)
        if camera is None:
            r.ResetCamera()
            camera = r.GetActiveCamera()
            camera.Azimuth(35)
            camera.Elevation(25)
            r.ResetCamera()
            camera.Zoom(1.15)
        else:
            r.SetActiveCamera(camera)
        win.AddRenderer(r)
    # The stamp spans both views: a transparent renderer over the whole window.
    overlay = vtk.vtkRenderer()
    overlay.SetLayer(1)
    overlay.InteractiveOff()
    label(overlay, stamp, size=11, y=6)
    win.SetNumberOfLayers(2)
    win.AddRenderer(overlay)
    save(win, path)


def render_whole(mesh, path, size, stamp):
    win = window(size, size)
    r = vtk.vtkRenderer()
    r.SetBackground(1, 1, 1)
    a = actor(mesh, (0.86, 0.72, 0.5), edges=False)
    a.GetProperty().SetInterpolationToGouraud()
    a.GetProperty().SetSpecular(0.15)
    r.AddActor(a)
    label(r, stamp, size=11, y=6)
    r.ResetCamera()
    r.GetActiveCamera().Azimuth(30)
    r.GetActiveCamera().Elevation(25)
    r.ResetCamera()
    win.AddRenderer(r)
    save(win, path)


def git_commit():
    here = os.path.dirname(os.path.abspath(__file__))
    run = lambda *a: subprocess.run(["git", *a], capture_output=True, text=True, cwd=here).stdout.strip()
    return run("rev-parse", "--short", "HEAD") or "unknown"


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("reduced")
    parser.add_argument("raw")
    parser.add_argument("--box", required=True, help="x0,y0,z0,x1,y1,z1")
    parser.add_argument("--domains", type=int, required=True, help="the jobs' domain count, for the caption")
    parser.add_argument("--job-reduced", required=True, help="the command that wrote REDUCED")
    parser.add_argument("--job-raw", required=True, help="the command that wrote RAW")
    parser.add_argument("--commit", help="the commit the jobs' tetiso was built from (default: HEAD)")
    parser.add_argument("--size", type=int, default=600, help="pixels per view (square)")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    box = [float(v) for v in args.box.split(",")]
    os.makedirs(args.out, exist_ok=True)
    vr, tr = read_ply(args.reduced)
    vw, tw = read_ply(args.raw)
    fr, fw = in_box(vr, tr, box), in_box(vw, tw, box)
    lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
    model = next((l.split(":", 1)[1].strip() for l in lscpu.splitlines() if l.startswith("Model name")), "?")
    meta = {"command": "tools/render_surface.py " + " ".join(
                [os.path.relpath(args.reduced), os.path.relpath(args.raw), "--box", args.box]),
            "jobs": {"reduced": args.job_reduced, "raw": args.job_raw}, "domains": args.domains,
            "box": box, "triangles": {"reduced": len(tr), "raw": len(tw)},
            "fragment_triangles": {"reduced": len(fr), "raw": len(fw)},
            "machine": f"{model}, {os.cpu_count()} cores, Linux {platform.release()}",
            "commit": args.commit or git_commit(),
            "date": datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "vtk": vtk.vtkVersion.GetVTKVersion()}
    job = re.sub(r"^.*?(tetiso run)", r"\1", re.sub(r"\s+-o\s+\S+", "", args.job_reduced))
    stamp = f"{job} (and --no-reduce); commit {meta['commit']}; {meta['date'][:10]}; {model}, {os.cpu_count()} cores"
    render_fragment([(clipped(polydata(vr, touching(vr, tr, box)), box), f"reduced: {len(fr):,} triangles")],
                    [(clipped(polydata(vw, touching(vw, tw, box)), box), f"unreduced: {len(fw):,} triangles")],
                    os.path.join(args.out, "fragment.png"), args.size, stamp)
    render_whole(polydata(vr, tr), os.path.join(args.out, "surface.png"), args.size * 9 // 10,
                 stamp.replace(" (and --no-reduce)", "").replace(" --device cpu", ""))
    with open(os.path.join(args.out, "render.json"), "w") as f:
        json.dump(meta, f, indent=1)
    print(f"fragment: {len(fr):,} reduced and {len(fw):,} raw triangles in the box")


if __name__ == "__main__":
    main()
