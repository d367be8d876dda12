# The other things ParaView draws, one per run, for tests/paraview.rs and docs/compatibility.md:
#   pvbatch cases.py OUT.png clip|glyphs|translucent [WIDTH HEIGHT]
# clip: the Wavelet's contour clipped by a plane (a surface with a cut); glyphs: arrows on the
# contour's points (instanced draws); translucent: the contour at opacity 0.5 (depth peeling).
import sys
from paraview.simple import *

out, case = sys.argv[1], sys.argv[2]
width, height = (int(sys.argv[3]), int(sys.argv[4])) if len(sys.argv) > 4 else (640, 360)
wavelet = Wavelet()
contour = Contour(Input=wavelet, ContourBy=["POINTS", "RTData"], Isosurfaces=[100.0, 157.0, 214.0])
contour.ComputeScalars = 1
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [width, height]
view.OrientationAxesVisibility = 1
if case == "clip":
    shown = Clip(Input=contour, ClipType="Plane")
    shown.ClipType.Normal = [1.0, 0.3, 0.0]
    display = Show(shown, view)
    ColorBy(display, ("POINTS", "RTData"))
elif case == "glyphs":
    display = Show(contour, view)
    ColorBy(display, ("POINTS", "RTData"))
    glyphs = Glyph(Input=contour, GlyphType="Arrow")
    glyphs.ScaleArray = ["POINTS", "No scale array"]
    glyphs.ScaleFactor = 4.0
    glyphs.MaximumNumberOfSamplePoints = 200
    Show(glyphs, view)
elif case == "translucent":
    display = Show(contour, view)
    ColorBy(display, ("POINTS", "RTData"))
    display.Opacity = 0.5
else:
    raise SystemExit("case: clip, glyphs or translucent")
view.CameraPosition = [60.0, -45.0, 50.0]
view.CameraFocalPoint = [0.0, 0.0, 0.0]
view.CameraViewUp = [0.0, 0.0, 1.0]
view.ResetCamera()
Render(view)
SaveScreenshot(out, view, ImageResolution=[width, height])
