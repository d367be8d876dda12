# Wavelet contoured at three values, coloured by RTData, with the orientation axes and a scalar
# bar: the scene of docs/compatibility.md's ParaView section and of tests/paraview.rs.
#   pvbatch contour.py OUT.png [WIDTH HEIGHT]
import sys
from paraview.simple import *

out = sys.argv[1]
width, height = (int(sys.argv[2]), int(sys.argv[3])) if len(sys.argv) > 3 else (640, 360)
wavelet = Wavelet()
contour = Contour(Input=wavelet, ContourBy=["POINTS", "RTData"], Isosurfaces=[100.0, 157.0, 214.0])
contour.ComputeScalars = 1
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [width, height]
view.OrientationAxesVisibility = 1
display = Show(contour, view)
ColorBy(display, ("POINTS", "RTData"))
display.RescaleTransferFunctionToDataRange(True)
display.SetScalarBarVisibility(view, True)
view.CameraPosition = [60.0, -45.0, 50.0]
view.CameraFocalPoint = [0.0, 0.0, 0.0]
view.CameraViewUp = [0.0, 0.0, 1.0]
view.ResetCamera()
Render(view)
SaveScreenshot(out, view, ImageResolution=[width, height])
