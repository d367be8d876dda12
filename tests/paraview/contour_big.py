# A contour of millions of triangles (a random field contoured at its median, ~TRIANGLES), coloured
# by the field, rendered and saved once: what scripts/bench-paraview times under Mesa and glray.
#   pvbatch contour_big.py OUT.png [CELLS]   (CELLS per side of the grid, default 200)
import sys, time
from paraview.simple import *

out = sys.argv[1]
cells = int(sys.argv[2]) if len(sys.argv) > 2 else 200
start = time.time()
source = RandomAttributes(Input=Wavelet(WholeExtent=[0, cells, 0, cells, 0, cells]))
source.DataType = "Float"
source.ComponentRange = [0.0, 1.0]
source.GeneratePointScalars = 1
contour = Contour(Input=source, ContourBy=["POINTS", "RandomPointScalars"], Isosurfaces=[0.5])
contour.ComputeScalars = 1
contour.ComputeNormals = 1
contour.UpdatePipeline()
triangles = contour.GetDataInformation().GetNumberOfCells()
filtered = time.time()
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [1280, 720]
view.OrientationAxesVisibility = 0
display = Show(contour, view)
ColorBy(display, ("POINTS", "RandomPointScalars"))
view.CameraPosition = [cells * 2.2, -cells * 1.6, cells * 1.8]
view.CameraFocalPoint = [cells / 2.0, cells / 2.0, cells / 2.0]
view.CameraViewUp = [0.0, 0.0, 1.0]
Render(view)
SaveScreenshot(out, view, ImageResolution=[1280, 720])
done = time.time()
print("contour_big: %d triangles, filter %.2f s, render and save %.2f s" % (triangles, filtered - start, done - filtered))
