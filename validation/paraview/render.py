"""Render one frame of a dem output directory with ParaView itself (run under pvpython).

    pvpython validation/paraview/render.py OUT_DIR PNG [--frame K]
    xvfb-run -a -s "-screen 0 1280x1024x24" pvpython validation/paraview/render.py OUT_DIR PNG

(the second without a display: Debian's ParaView 5.11 is built for X only, and
``--force-offscreen-rendering`` crashes there; see README.md).

Opens OUT_DIR/particles.pvd (written by dem.io.vtk.VTKSeriesWriter) as a time series, goes to
frame K (default: the last; negative counts from the end), and draws

- the spheres (part 0 of the collection) as Sphere glyphs scaled by the point array ``radius``
  (scale factor 2: ParaView's glyph sphere has radius 0.5), coloured by the x-component of
  ``velocity`` (m/s, relative to the trough, a diverging map symmetric about 0) with a colour bar;
- the trough (part 1: floor and the two side walls) as semi-transparent grey surfaces with their
  edges;

from a three-quarter view on a white background, and saves a PNG (default 1200 x 700).

It prints the number of time steps, the time values and the arrays found, so a log shows that
the collection opened as a time series. This is a pvpython script: it imports paraview.simple
and does not run under the project's virtual environment.
"""

from __future__ import annotations

import argparse
import os
import sys

from paraview.simple import (
    ColorBy,
    ExtractBlock,
    GetActiveViewOrCreate,
    GetAnimationScene,
    GetColorTransferFunction,
    GetScalarBar,
    Glyph,
    LoadPalette,
    OpenDataFile,
    Render,
    SaveScreenshot,
    Show,
    Text,
)


def block_paths(pvd):
    """(spheres, trough) block paths: /Root/<name> of parts 0 and 1 (/Root/Block<part> unnamed)."""
    import xml.etree.ElementTree as ET

    names = {}
    for ds in ET.parse(pvd).getroot().iter("DataSet"):
        part = int(ds.get("part", "0"))
        names.setdefault(part, ds.get("name") or f"Block{part}")
    return f"/Root/{names.get(0, 'Block0')}", f"/Root/{names.get(1, 'Block1')}"


def parse_args(argv):
    ap = argparse.ArgumentParser(description="Render a dem particles.pvd frame to a PNG.")
    ap.add_argument("out_dir", help="dem output directory holding particles.pvd")
    ap.add_argument("png", help="PNG file to write")
    ap.add_argument("--frame", type=int, default=-1, help="frame index (default -1: the last)")
    ap.add_argument("--size", type=int, nargs=2, default=(1200, 700), metavar=("W", "H"))
    ap.add_argument(
        "--zoom", type=float, default=1.9, help="camera distance in trough lengths (default 1.9)"
    )
    ap.add_argument(
        "--vmax",
        type=float,
        default=None,
        help="colour range -vmax..vmax of velocity x, m/s (default: from the frame)",
    )
    return ap.parse_args(argv)


def block_arrays(source):
    info = source.GetDataInformation()
    pd = info.GetPointDataInformation()
    out = []
    for i in range(pd.GetNumberOfArrays()):
        a = pd.GetArrayInformation(i)
        out.append(f"{a.GetName()}({a.GetNumberOfComponents()})")
    return info.GetNumberOfPoints(), out


def main(argv):
    args = parse_args(argv)
    pvd = os.path.join(args.out_dir, "particles.pvd")
    if not os.path.isfile(pvd):
        sys.exit(f"render.py: no particles.pvd in {args.out_dir}")

    reader = OpenDataFile(pvd)
    times = list(reader.TimestepValues or [])
    if not times:
        sys.exit(f"render.py: {pvd} opened without time steps (not a time series?)")
    k = args.frame if args.frame >= 0 else len(times) + args.frame
    if not 0 <= k < len(times):
        sys.exit(f"render.py: frame {args.frame} out of range, {len(times)} time steps")
    t = times[k]
    print(
        f"opened {pvd} with {reader.GetXMLName()}: {len(times)} time steps, "
        f"t = {times[0]:.6g} .. {times[-1]:.6g} s"
    )
    print(f"rendering frame {k} (t = {t:.6g} s)")

    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = t

    spheres_path, trough_path = block_paths(pvd)
    spheres = ExtractBlock(Input=reader, Selectors=[spheres_path])
    trough = ExtractBlock(Input=reader, Selectors=[trough_path])
    spheres.UpdatePipeline(t)
    trough.UpdatePipeline(t)
    n, arrays = block_arrays(spheres)
    print(f"part 0 (spheres): {n} points, point arrays: {', '.join(arrays)}")
    n_t, arrays_t = block_arrays(trough)
    cells = trough.GetDataInformation().GetNumberOfCells()
    names = ", ".join(arrays_t) or "-"
    print(f"part 1 (trough): {n_t} points, {cells} cells, point arrays: {names}")
    if n == 0:
        sys.exit("render.py: no spheres in this frame")

    vx_range = spheres.PointData["velocity"].GetRange(0)
    vmax = args.vmax or max(abs(vx_range[0]), abs(vx_range[1]), 1e-6)
    print(f"velocity x range at this frame: {vx_range[0]:.4g} .. {vx_range[1]:.4g} m/s")

    glyph = Glyph(Input=spheres, GlyphType="Sphere")
    glyph.OrientationArray = ["POINTS", "No orientation array"]
    glyph.ScaleArray = ["POINTS", "radius"]
    glyph.ScaleFactor = 2.0  # the glyph sphere has radius 0.5: diameter = 2 r
    glyph.GlyphMode = "All Points"
    glyph.GlyphType.ThetaResolution = 24
    glyph.GlyphType.PhiResolution = 16
    print(f"glyph sphere radius {glyph.GlyphType.Radius}, scale factor {glyph.ScaleFactor}")

    LoadPalette("WhiteBackground")
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = list(args.size)
    view.OrientationAxesVisibility = 1
    try:  # ParaView >= 5.10 keeps a per-view background switch
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    view.Background = [1.0, 1.0, 1.0]

    gdisp = Show(glyph, view)
    ColorBy(gdisp, ("POINTS", "velocity", "X"))
    lut = GetColorTransferFunction("velocity")
    lut.ApplyPreset("Cool to Warm", True)
    lut.RescaleTransferFunction(-vmax, vmax)
    lut.AutomaticRescaleRangeMode = "Never"
    gdisp.SetScalarBarVisibility(view, True)
    bar = GetScalarBar(lut, view)
    bar.Title = "velocity x (m/s)"
    bar.ComponentTitle = ""
    bar.TitleColor = [0.0, 0.0, 0.0]
    bar.LabelColor = [0.0, 0.0, 0.0]
    bar.RangeLabelFormat = "%-#.3f"
    bar.WindowLocation = "Any Location"
    bar.Orientation = "Vertical"
    bar.Position = [0.90, 0.15]
    bar.ScalarBarLength = 0.6
    gdisp.Specular = 0.3

    tdisp = Show(trough, view)
    ColorBy(tdisp, None)
    tdisp.Representation = "Surface With Edges"
    tdisp.AmbientColor = tdisp.DiffuseColor = [0.55, 0.6, 0.68]
    tdisp.EdgeColor = [0.2, 0.2, 0.25]
    tdisp.Opacity = 0.25
    tdisp.LineWidth = 2.0
    view.EnableRenderOnInteraction = 0
    try:
        view.UseRenderViewSettingsForGlyphs = 0
    except AttributeError:
        pass

    label = Text(
        Text=f"dem: {n} spheres, frame {k + 1}/{len(times)}, t = {t:.4f} s\n"
        "colour: velocity x relative to the trough"
    )
    ldisp = Show(label, view)
    ldisp.WindowLocation = "Upper Left Corner"
    ldisp.Color = [0.0, 0.0, 0.0]
    ldisp.FontSize = 14
    ldisp.Justification = "Left"

    # three-quarter view: from the front left, above the bed, looking down the trough (+x)
    Render(view)  # the first render resets the camera: set ours after it
    b = trough.GetDataInformation().GetBounds()
    cx, cy = 0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3])
    length = b[1] - b[0]
    view.CameraFocalPoint = [cx, cy, 0.2 * (b[5] - b[4])]
    direction = [-0.42, -0.8, 0.78]  # from the front left, above
    norm = sum(c * c for c in direction) ** 0.5
    dist = args.zoom * length
    view.CameraPosition = [
        f + dist * c / norm for f, c in zip(view.CameraFocalPoint, direction, strict=True)
    ]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.CameraViewAngle = 30.0
    view.CameraParallelProjection = 0
    Render(view)
    SaveScreenshot(
        args.png,
        view,
        ImageResolution=list(args.size),
        TransparentBackground=0,
        CompressionLevel="9",
    )
    print(f"wrote {args.png} ({os.path.getsize(args.png)} bytes, {args.size[0]}x{args.size[1]})")


if __name__ == "__main__":
    main(sys.argv[1:])
