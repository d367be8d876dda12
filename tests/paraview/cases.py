# The other things ParaView draws, one per run, for tests/paraview.rs and docs/compatibility.md:
#   pvbatch cases.py OUT.png clip|specular|wireframe|points|glyphs|glyphs3d|translucent [WIDTH HEIGHT]
# clip: the Wavelet's contour clipped by a plane (a surface with a cut); specular: the contour
# with specular highlights (VTK's Phong term); wireframe, points: the
# contour drawn as lines and as points; glyphs: the Glyph filter's arrows on the contour's
# points (no normals); glyphs3d: the 3D Glyphs representation (instanced draws); translucent:
# the contour at opacity 0.5 (depth peeling).
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paraview.simple import Clip, ColorBy, Glyph, Render, SaveScreenshot, Show
from scene import contour_and_view, look

out, case = sys.argv[1], sys.argv[2]
width, height = (int(sys.argv[3]), int(sys.argv[4])) if len(sys.argv) > 4 else (640, 360)
contour, view = contour_and_view(width, height)
if case == "clip":
    shown = Clip(Input=contour, ClipType="Plane")
    shown.ClipType.Normal = [1.0, 0.3, 0.0]
    display = Show(shown, view)
    ColorBy(display, ("POINTS", "RTData"))
elif case == "specular":
    display = Show(contour, view)
    ColorBy(display, ("POINTS", "RTData"))
    display.Specular = 0.6
    display.SpecularPower = 30.0
elif case in ("wireframe", "points"):
    display = Show(contour, view)
    ColorBy(display, ("POINTS", "RTData"))
    display.SetRepresentationType("Wireframe" if case == "wireframe" else "Points")
elif case == "glyphs":
    display = Show(contour, view)
    ColorBy(display, ("POINTS", "RTData"))
    glyphs = Glyph(Input=contour, GlyphType="Arrow")
    glyphs.ScaleArray = ["POINTS", "No scale array"]
    glyphs.ScaleFactor = 4.0
    glyphs.MaximumNumberOfSamplePoints = 200
    Show(glyphs, view)
elif case == "glyphs3d":
    display = Show(contour, view)
    ColorBy(display, ("POINTS", "RTData"))
    display.SetRepresentationType("3D Glyphs")
    display.GlyphType = "Arrow"
    display.ScaleFactor = 2.0
elif case == "translucent":
    display = Show(contour, view)
    ColorBy(display, ("POINTS", "RTData"))
    display.Opacity = 0.5
else:
    raise SystemExit("case: clip, specular, wireframe, points, glyphs, glyphs3d or translucent")
look(view)
Render(view)
SaveScreenshot(out, view, ImageResolution=[width, height])
