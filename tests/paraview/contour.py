# Wavelet contoured at three values, coloured by RTData, with the orientation axes and a scalar
# bar: the scene of docs/compatibility.md's ParaView section and of tests/paraview.rs.
#   pvbatch contour.py OUT.png [WIDTH HEIGHT]
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from paraview.simple import ColorBy, Render, SaveScreenshot, Show
from scene import contour_and_view, look

out = sys.argv[1]
width, height = (int(sys.argv[2]), int(sys.argv[3])) if len(sys.argv) > 3 else (640, 360)
contour, view = contour_and_view(width, height)
display = Show(contour, view)
ColorBy(display, ("POINTS", "RTData"))
display.RescaleTransferFunctionToDataRange(True)
display.SetScalarBarVisibility(view, True)
look(view)
Render(view)
SaveScreenshot(out, view, ImageResolution=[width, height])
