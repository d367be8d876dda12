# What the pvbatch scripts here share: the Wavelet contoured at three values (RTData kept on it)
# and a render view of the given size with the orientation axes.
from paraview.simple import Contour, GetActiveViewOrCreate, Wavelet


def contour_and_view(width, height):
    contour = Contour(Input=Wavelet(), ContourBy=["POINTS", "RTData"], Isosurfaces=[100.0, 157.0, 214.0])
    contour.ComputeScalars = 1
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [width, height]
    view.OrientationAxesVisibility = 1
    return contour, view


def look(view):
    """The camera every script here uses, then fitted to what is shown."""
    view.CameraPosition = [60.0, -45.0, 50.0]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 0.0, 1.0]
    view.ResetCamera()
