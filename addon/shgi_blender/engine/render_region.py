"""Render Region (Output > Render Region, ``render.use_border``) as Cycles renders it. No bpy.

Blender gives a render engine a result of the border's size when Render Region is on (its
pipeline cuts the border from the full frame, truncating border x size to whole pixels) and,
without Crop to Render Region, pastes that result into an empty full frame itself. So the engine
renders only the border's pixels: ``region_camera_fields`` turns the full frame's camera into
one whose image is exactly the region (the same rays through the same pixels; Blender's
viewplane with a border, BKE_camera_params_compute_viewplane), and the renderers then trace only
those pixels.

The renderers seed each pixel's samples by its index in the image, so a region's noise is not
the full frame's noise at the same pixels: both converge to the same image.
"""

from dataclasses import dataclass


@dataclass(frozen=True)
class Region:
    """A rectangle of the full frame in pixels: `x` columns from the left, `top` rows from the
    top, `width` x `height` pixels."""

    x: int
    top: int
    width: int
    height: int


def border_region(full_width, full_height, min_x, min_y, max_x, max_y):
    """The Region of Blender's render border (fractions of the frame, y up) in a full frame of
    full_width x full_height pixels; ValueError when it holds no whole pixel."""
    x0, x1 = int(min_x * full_width), int(max_x * full_width)
    y0, y1 = int(min_y * full_height), int(max_y * full_height)
    if x1 - x0 < 1 or y1 - y0 < 1:
        raise ValueError(f"Render Region {x1 - x0}x{y1 - y0} px of a {full_width}x{full_height} "
                         "px frame holds no whole pixel; draw a larger region (Ctrl+B in the "
                         "camera view) or turn Output > Render Region off")
    return Region(x0, full_height - y1, x1 - x0, y1 - y0)


def _fitted_horizontally(camera, width, height, shgi):
    """Whether the sensor spans the image's width (Blender's sensor fit; Auto: the larger side)."""
    if camera.sensor_fit == shgi.SensorFit.AUTO:
        return width >= height
    return camera.sensor_fit == shgi.SensorFit.HORIZONTAL


def region_camera_fields(shgi, camera, region):
    """{shgi.Camera field: value} making `camera` (the full frame's) render only `region`.

    The region camera keeps the full frame's pixel size and fits its sensor along the same axis
    (explicitly: Auto could pick the other axis for the region's aspect); its shift moves the
    image centre to the region's centre. Shifts are in units of the fitted dimension."""
    full_width, full_height = camera.resolution_x, camera.resolution_y
    horizontal = _fitted_horizontally(camera, full_width, full_height, shgi)
    full_factor = full_width if horizontal else full_height
    factor = region.width if horizontal else region.height
    # The sensor (ortho_scale) spans `factor` pixels of the full frame's size.
    scale = factor / full_factor
    fields = {"resolution_x": region.width, "resolution_y": region.height,
              "sensor_fit": shgi.SensorFit.HORIZONTAL if horizontal else shgi.SensorFit.VERTICAL,
              "shift_x": (camera.shift_x * full_factor - 0.5 * full_width + region.x
                          + 0.5 * region.width) / factor,
              "shift_y": (camera.shift_y * full_factor + 0.5 * full_height - region.top
                          - 0.5 * region.height) / factor}
    if camera.type == shgi.CameraType.ORTHOGRAPHIC:
        fields["ortho_scale"] = camera.ortho_scale * scale
    else:
        # Only an explicit Vertical fit spans sensor_height; Auto spans sensor_width either way.
        sensor = (camera.sensor_height if camera.sensor_fit == shgi.SensorFit.VERTICAL
                  else camera.sensor_width)
        fields["sensor_width" if horizontal else "sensor_height"] = sensor * scale
    return fields


def crop_camera(shgi, camera, region):
    """`camera` (a shgi.Camera, changed in place and returned) seeing only `region`."""
    for name, value in region_camera_fields(shgi, camera, region).items():
        setattr(camera, name, value)
    return camera
