"""The 3D viewport's view as shgi.Camera fields, read from its matrices. No bpy.

A viewport is described by ``region_data.view_matrix`` (camera_from_world) and
``region_data.window_matrix`` (the OpenGL projection Blender draws with), for a region of
width x height pixels. Rather than re-deriving Blender's rules (a free perspective view is a
camera with the view's lens and a 72 mm sensor, i.e. 36 mm at zoom 2; camera view adds the
camera's sensor fit, shift, the view's zoom and pan), the frustum is read back from the
projection, so the rendered image lines up with what Blender draws in every case, camera view
with its border included. With sensor_fit HORIZONTAL and any sensor width S:

  perspective  W[0][0] = 2 lens / S            -> lens = W[0][0] S / 2
               W[0][2] = 2 shift_x             W[1][2] = 2 shift_y width / height
               near = W[2][3] / (W[2][2] - 1)  far = W[2][3] / (W[2][2] + 1)
  orthographic W[0][0] = 2 / ortho_scale       W[0][3] = -2 shift_x
               W[1][3] = -2 shift_y width / height
               near = (W[2][3] + 1) / W[2][2]  far = (W[2][3] - 1) / W[2][2]

(shgi.Camera follows Blender's BKE_camera_params_compute_viewplane: the fitted axis spans the
sensor, shifts are in units of it.) Blender's matrices are float32: with a far clip more than
about 1e7 times the near one, W[2][2] rounds to -1 and the perspective's far clip (infinite by
the formula) is lost; it then becomes MAX_CLIP_END, as far as a ray goes. An orthographic
viewport clips from behind its eye (near < 0, Blender centres the clip range on the view); a ray
camera cannot start behind its origin, so the origin moves back along the view axis by -near
and the clip range follows.
"""

import numpy as np

# Any sensor width works with a horizontal fit; Blender's default keeps the lens readable.
SENSOR_WIDTH_MM = 36.0
# The far clip of a projection too deep for float32 (native/scene/ray.h kMaxCoordinate: no ray
# travels farther).
MAX_CLIP_END = 1e12


def is_perspective(window_matrix):
    """True for a perspective projection (its last row is (0, 0, -1, 0))."""
    return np.asarray(window_matrix, np.float64)[3, 3] == 0.0


def camera_fields_from_view(view_matrix, window_matrix, width, height):
    """shgi.Camera keyword fields (type as "PERSP"/"ORTHO") of a viewport.

    view_matrix, window_matrix: 4 x 4 (row-major, as mathutils.Matrix rows); width, height:
    the region's size in pixels (the camera's resolution).
    """
    view = np.asarray(view_matrix, np.float64).reshape(4, 4)
    window = np.asarray(window_matrix, np.float64).reshape(4, 4)
    world_from_camera = np.linalg.inv(view)
    aspect = float(width) / float(height)
    fields = {"sensor_width": SENSOR_WIDTH_MM, "sensor_fit": "HORIZONTAL",
              "resolution_x": int(width), "resolution_y": int(height)}
    if is_perspective(window):
        near = window[2, 3] / (window[2, 2] - 1.0)
        depth = window[2, 2] + 1.0  # -2 near / (far - near), which float32 may round to 0
        far = window[2, 3] / depth if depth < 0.0 else MAX_CLIP_END
        far = min(far, MAX_CLIP_END) if far > near else MAX_CLIP_END
        fields.update(type="PERSP", lens=window[0, 0] * SENSOR_WIDTH_MM / 2.0,
                      shift_x=window[0, 2] / 2.0, shift_y=window[1, 2] / 2.0 / aspect,
                      clip_start=near, clip_end=far)
    else:
        near = (window[2, 3] + 1.0) / window[2, 2]
        far = (window[2, 3] - 1.0) / window[2, 2]
        back = max(0.0, -near)
        # Camera space looks down -Z: moving the eye back is +Z in camera space.
        world_from_camera = world_from_camera @ _translation((0.0, 0.0, back))
        fields.update(type="ORTHO", ortho_scale=2.0 / window[0, 0],
                      shift_x=-window[0, 3] / 2.0, shift_y=-window[1, 3] / 2.0 / aspect,
                      clip_start=near + back, clip_end=far + back)
    fields["world_from_camera"] = world_from_camera
    return {key: (float(value) if isinstance(value, np.floating) else value)
            for key, value in fields.items()}


def scaled_fields(fields, divisor):
    """The same view at 1/divisor of the resolution (at least 1 x 1 pixels).

    The horizontal fit keeps the horizontal extent exact; the vertical one follows the rounded
    aspect ratio (off by less than one reduced pixel).
    """
    scaled = dict(fields)
    scaled["resolution_x"] = max(1, int(fields["resolution_x"]) // divisor)
    scaled["resolution_y"] = max(1, int(fields["resolution_y"]) // divisor)
    return scaled


def shgi_camera(shgi, fields):
    """shgi.Camera of fields from camera_fields_from_view."""
    # Imported here: conversions imports shgi, and viewport.py imports this module before the
    # native module is known to import.
    from ..export.conversions import CAMERA_TYPES, SENSOR_FITS

    values = dict(fields)
    values["type"] = CAMERA_TYPES[values["type"]]
    values["sensor_fit"] = SENSOR_FITS[values["sensor_fit"]]
    return shgi.Camera(**values)


def view_key(fields):
    """A hashable value equal for equal views (to tell when the view changed)."""
    return tuple((key, value.tobytes() if isinstance(value, np.ndarray) else value)
                 for key, value in sorted(fields.items()))


def _translation(offset):
    matrix = np.eye(4)
    matrix[:3, 3] = offset
    return matrix
