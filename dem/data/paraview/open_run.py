"""Open a dem run in ParaView with its spheres drawn as spheres, ready to play.

    pvpython open_run.py OUT_DIR                       # a window (ParaView's own Python)
    pvpython open_run.py OUT_DIR --screenshot run.png  # and a picture of the last frame
    pvpython open_run.py OUT_DIR --contacts            # the contact forces (output.contacts)
    paraview --script=open_run.py                      # the GUI (asks nothing: set DEM_OUT)

In ParaView's GUI (View > Python Shell): ``Run Script`` with the environment variable DEM_OUT
set to the run folder, or type::

    exec(open("/path/to/open_run.py").read()); open_run("/path/to/OUT_DIR")

Where is this file? ``python -c "from dem.io.vtk import paraview_script;
print(paraview_script())"`` prints its path in the installed dem.

What it does, on OUT_DIR/particles.pvd (the time series ``dem run`` writes; dem.io.vtk):

- the ``spheres`` block as Sphere glyphs scaled by the point array ``radius`` with scale factor
  2 (ParaView's glyph sphere has radius 0.5, so each glyph's diameter is 2 r: the spheres
  touch as they do in the run), coloured by ``speed_lab``, the speed in the lab (m/s: what a
  camera beside the feeder sees; a run before dem wrote it: the magnitude of ``velocity``);
- the ``trough`` block as semi-transparent grey walls;
- for clumps (screws) the ``grains`` block as arrows along each grain's long axis from its
  centre of mass (hidden at first: tick its eye in the Pipeline Browser);
- with ``[output] contacts = true`` the ``contacts`` block as arrows at each contact, along its
  normal force on sphere i and as long as that force (the longest 3 r), coloured by the normal
  force in N: the force chains, and the floor's load under the bed. Hidden at first; with
  ``--contacts`` shown, the spheres made translucent;
- the animation set to the run's time steps, at the last frame; the colour range that of the
  frame shown (Rescale over all time steps in the GUI for a fixed one).

Its pipeline is plain ParaView (PVDReader, Extract Block by the block names ``/Root/spheres``,
``/Root/trough``, ``/Root/grains``, Glyph), so File > Save State keeps it. It runs with
ParaView 5.10 and later (Extract Block selectors), under pvpython, not the project's Python.
"""

from __future__ import annotations

import argparse
import os
import sys
import xml.etree.ElementTree as ET

PVD = "particles.pvd"


def block_names(pvd: str) -> dict[int, str]:
    """Part number -> the block's name in the collection (``Block<part>`` where it has none)."""
    names = {}
    for ds in ET.parse(pvd).getroot().iter("DataSet"):
        part = int(ds.get("part", "0"))
        names.setdefault(part, ds.get("name") or f"Block{part}")
    return names


def glyph_scale_factor() -> float:
    """The Glyph filter's scale factor for spheres scaled by their radius.

    ParaView's Sphere glyph source has radius 0.5 (diameter 1): scaled by ``radius`` times 2,
    each glyph's diameter is 2 r.
    """
    return 2.0


def pipeline(out_dir: str, frame: int = -1) -> dict:
    """The sources for ``out_dir`` (no view touched): reader, blocks, glyphs, times, frame.

    ``frame``: the time step to show (negative counts from the end); the animation goes there.
    """
    from paraview import simple as ps

    pvd = os.path.join(out_dir, PVD)
    if not os.path.isfile(pvd):
        raise FileNotFoundError(
            f"open_run: no {PVD} in {out_dir}: is it a dem run folder (dem run CASE --out "
            "OUT_DIR, frames not switched off)?"
        )
    names = block_names(pvd)
    reader = ps.PVDReader(registrationName=PVD, FileName=pvd)
    times = list(reader.TimestepValues or [0.0])
    k = frame if frame >= 0 else len(times) + frame
    k = min(max(k, 0), len(times) - 1)
    scene = ps.GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.AnimationTime = times[k]

    spheres = ps.ExtractBlock(registrationName=names.get(0, "spheres"), Input=reader,
                              Selectors=[f"/Root/{names.get(0, 'spheres')}"])  # fmt: skip
    trough = ps.ExtractBlock(registrationName=names.get(1, "trough"), Input=reader,
                             Selectors=[f"/Root/{names.get(1, 'trough')}"])  # fmt: skip
    spheres.UpdatePipeline(times[k])
    trough.UpdatePipeline(times[k])
    glyph = ps.Glyph(registrationName="spheres as spheres", Input=spheres, GlyphType="Sphere")
    glyph.OrientationArray = ["POINTS", "No orientation array"]
    glyph.ScaleArray = ["POINTS", "radius"]
    glyph.ScaleFactor = glyph_scale_factor()
    glyph.GlyphMode = "All Points"
    glyph.GlyphType.Radius = 0.5
    glyph.GlyphType.ThetaResolution = 20
    glyph.GlyphType.PhiResolution = 14
    out = {"pvd": pvd, "names": names, "reader": reader, "times": times, "frame": k,
           "spheres": spheres, "trough": trough, "glyph": glyph, "arrows": None}  # fmt: skip
    parts = {name: q for q, name in names.items()}
    if "contacts" in parts:  # output.contacts: one arrow per contact, its normal force
        q = parts["contacts"]
        contacts = ps.ExtractBlock(registrationName="contacts", Input=reader,
                                   Selectors=["/Root/contacts"])  # fmt: skip
        contacts.UpdatePipeline(times[k])
        forces = ps.Glyph(registrationName="contact forces", Input=contacts, GlyphType="Arrow")
        forces.OrientationArray = ["POINTS", "normal_force_vector"]
        forces.ScaleArray = ["POINTS", "normal_force"]
        r = (
            spheres.PointData["radius"].GetRange()[1]
            if "radius" in spheres.PointData.keys()
            else 0.002
        )
        largest = max(abs(v) for v in contacts.PointData["normal_force"].GetRange()) or 1.0
        forces.ScaleFactor = 3.0 * r / largest
        forces.GlyphMode = "All Points"
        forces.GlyphType.TipRadius = 0.18
        forces.GlyphType.ShaftRadius = 0.07
        out["contacts"], out["forces"], out["contacts_part"] = contacts, forces, q
    if 2 in names and names[2] == "grains":  # clumps: the grains' long axes
        grains = ps.ExtractBlock(registrationName=names[2], Input=reader,
                                 Selectors=[f"/Root/{names[2]}"])  # fmt: skip
        arrows = ps.Glyph(registrationName="grain axes", Input=grains, GlyphType="Arrow")
        arrows.OrientationArray = ["POINTS", "axis"]
        arrows.ScaleArray = ["POINTS", "No scale array"]
        arrays = spheres.PointData.keys()
        r = spheres.PointData["radius"].GetRange()[1] if "radius" in arrays else 0.002
        arrows.ScaleFactor = 4.0 * r
        arrows.GlyphMode = "All Points"
        out["grains"], out["arrows"] = grains, arrows
    return out


def open_run(out_dir: str, *, screenshot: str | None = None, frame: int = -1,
             size: tuple[int, int] = (1400, 800), contacts: bool = False):  # fmt: skip
    """Build the pipeline for ``out_dir`` and show it in the active view; returns the view.

    ``frame``: the time step shown (negative counts from the end). ``screenshot``: a PNG of
    ``size`` pixels written of that frame. ``contacts``: show the contact forces (a run with
    ``output.contacts``) and make the spheres translucent.
    """
    from paraview import simple as ps

    p = pipeline(out_dir, frame)
    times, k, names = p["times"], p["frame"], p["names"]
    view = ps.GetActiveViewOrCreate("RenderView")
    shown = ps.Show(p["glyph"], view)
    if "speed_lab" in p["spheres"].PointData.keys():
        ps.ColorBy(shown, ("POINTS", "speed_lab"))
        lut, title = ps.GetColorTransferFunction("speed_lab"), "speed in the lab (m/s)"
    else:  # a run written before the lab velocity was
        ps.ColorBy(shown, ("POINTS", "velocity", "Magnitude"))
        lut, title = ps.GetColorTransferFunction("velocity"), "speed |velocity| (m/s)"
    lut.ApplyPreset("Viridis (matplotlib)", True)
    shown.RescaleTransferFunctionToDataRange(False, True)
    shown.SetScalarBarVisibility(view, True)
    bar = ps.GetScalarBar(lut, view)
    bar.Title = title
    bar.ComponentTitle = ""
    bar.RangeLabelFormat = "%-#.3f"
    bar.TitleFontSize = 14
    bar.LabelFontSize = 12
    bar.ScalarBarLength = 0.4
    shown.Specular = 0.3

    walls = ps.Show(p["trough"], view)
    ps.ColorBy(walls, None)
    walls.Representation = "Surface With Edges"
    walls.AmbientColor = walls.DiffuseColor = [0.6, 0.63, 0.7]
    walls.EdgeColor = [0.2, 0.2, 0.25]
    walls.Opacity = 0.3
    if p["arrows"] is not None:
        ps.Hide(p["arrows"], view)  # in the Pipeline Browser, shown with a click
    if contacts and "forces" not in p:
        raise ValueError(f"open_run: {out_dir} has no contacts block: run the case with "
                         "[output] contacts = true (and frames)")  # fmt: skip
    if "forces" in p:
        arrows = ps.Show(p["forces"], view)
        ps.ColorBy(arrows, ("POINTS", "normal_force"))
        force_lut = ps.GetColorTransferFunction("normal_force")
        force_lut.ApplyPreset("Inferno (matplotlib)", True)
        arrows.RescaleTransferFunctionToDataRange(False, True)
        if contacts:
            arrows.SetScalarBarVisibility(view, True)
            force_bar = ps.GetScalarBar(force_lut, view)
            force_bar.Title = "normal force (N)"
            force_bar.ComponentTitle = ""
            force_bar.WindowLocation = "Any Location"
            force_bar.Position = [0.89, 0.55]
            force_bar.ScalarBarLength = 0.33
            ps.ColorBy(shown, None)  # the spheres as grey ghosts, so the forces show
            bar.Visibility = 0
            shown.AmbientColor = shown.DiffuseColor = [0.75, 0.75, 0.78]
            shown.Opacity = 0.12
        else:
            ps.Hide(p["forces"], view)  # in the Pipeline Browser, shown with a click
    ps.SetActiveSource(p["glyph"])

    view.OrientationAxesVisibility = 1
    if screenshot:
        view.ViewSize = list(size)  # text and bars keep their size in the picture
    ps.Render(view)  # the first render resets the camera: a three-quarter view after it
    b = p["trough"].GetDataInformation().GetBounds()
    length = max(b[1] - b[0], b[3] - b[2], 1e-9)
    focus = [0.5 * (b[0] + b[1]), 0.5 * (b[2] + b[3]), b[4] + 0.2 * (b[5] - b[4])]
    direction = [-0.42, -0.8, 0.78]  # from the front left, above, looking along +x
    norm = sum(c * c for c in direction) ** 0.5
    view.CameraFocalPoint = focus
    view.CameraPosition = [
        f + 1.9 * length * c / norm for f, c in zip(focus, direction, strict=True)
    ]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.CameraViewAngle = 30.0
    ps.Render(view)
    blocks = ", ".join(names[q] for q in sorted(names))
    print(f"open_run: {p['pvd']}: {len(times)} time steps, t = {times[0]:.6g} .. "
          f"{times[-1]:.6g} s; blocks {blocks}; showing t = {times[k]:.6g} s")  # fmt: skip
    if screenshot:
        ps.SaveScreenshot(screenshot, view, ImageResolution=list(size), TransparentBackground=0)
        print(f"open_run: wrote {screenshot}")
    return view


def main(argv: list[str]) -> int:
    """Command line: ``pvpython open_run.py OUT_DIR [--screenshot PNG] [--frame K]``."""
    ap = argparse.ArgumentParser(prog="open_run.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("out_dir", nargs="?", default=os.environ.get("DEM_OUT"),
                    help="a dem run folder holding particles.pvd (default: $DEM_OUT)")  # fmt: skip
    ap.add_argument("--screenshot", metavar="PNG", help="write a picture of the frame shown")
    ap.add_argument("--frame", type=int, default=-1, help="time step shown (default -1: last)")
    ap.add_argument("--size", type=int, nargs=2, default=(1400, 800), metavar=("W", "H"))
    ap.add_argument("--contacts", action="store_true",
                    help="show the contact forces (output.contacts = true)")  # fmt: skip
    ap.add_argument("--no-window", action="store_true",
                    help="do not keep a window open (pvpython): with --screenshot")  # fmt: skip
    args = ap.parse_args(argv)
    if not args.out_dir:
        print("open_run.py: give the run folder: pvpython open_run.py OUT_DIR, or set DEM_OUT,"
              " or in the Python shell open_run('OUT_DIR')", file=sys.stderr)  # fmt: skip
        return 2
    view = open_run(args.out_dir, screenshot=args.screenshot, frame=args.frame,
                    size=tuple(args.size), contacts=args.contacts)  # fmt: skip
    if not args.no_window and not args.screenshot:
        from paraview import simple as ps

        ps.Interact(view)  # pvpython: a window until it is closed
    return 0


if __name__ == "__main__":
    if sys.argv and sys.argv[0] and os.path.basename(sys.argv[0]).startswith("open_run"):
        code = main(sys.argv[1:])  # pvpython open_run.py ...
        if code:
            sys.exit(code)
    elif os.environ.get("DEM_OUT"):  # the GUI's Run Script or --script, with DEM_OUT set
        open_run(os.environ["DEM_OUT"])
    else:
        print("open_run.py loaded: open_run('/path/to/OUT_DIR') opens a dem run")
